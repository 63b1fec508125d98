// What a model run produces: a time series sampled on the output grid, plus summary figures.
// Both models fill the same column names where the quantity exists in both.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace tailsim {

// Column-oriented table; every column has one value per row. Names carry their unit as a
// suffix (t_s, phi_deg, MzT_Nm), which is also the CSV header.
class TimeSeries {
 public:
  // Adds a column (all previous rows get NaN) and returns its index.
  int addColumn(const std::string& name);
  int column(const std::string& name) const;  // -1 if absent
  bool has(const std::string& name) const { return column(name) >= 0; }
  void appendRow(const std::vector<double>& row);  // row.size() == numColumns()
  // Appends `count` copies of `row` (row.size() == numColumns()), except that column grid_col of
  // copy i holds (first + i) * step: a grid column (the time) that goes on while the rest stays.
  void appendRepeated(const std::vector<double>& row, size_t count, int grid_col, long first, double step);
  // Appends `rows` rows stored one after another in data (row-major, numColumns() values each).
  void appendRowMajor(const double* data, size_t rows);
  void reserveRows(size_t rows);                   // capacity for `rows` rows (no reallocation while appending)
  const std::vector<std::string>& names() const { return names_; }
  size_t numColumns() const { return names_.size(); }
  size_t numRows() const { return names_.empty() ? 0 : data_[0].size(); }
  const std::vector<double>& values(int col) const { return data_[col]; }
  const std::vector<double>& values(const std::string& name) const;  // throws if absent
  double at(size_t row, int col) const { return data_[col][row]; }

 private:
  std::vector<std::string> names_;
  std::vector<std::vector<double>> data_;
};

// Summary of one model run of one case (goes into summary.json).
struct RunSummary {
  std::string model;          // "analytic" | "mujoco"
  double phi_net_deg = 0.0;   // phi at the end of the run minus phi at t = 0 (summary.json: null when !ok)
  double t_stop_s = 0.0;      // last time the body came to rest in yaw (or the run's end if it never did)
  int stick_slip_events = 0;  // all located stick/slip switches (rotation + translation)
  double wall_time_s = 0.0;   // wall-clock time of the simulation itself
  long solver_steps = 0;      // accepted integrator steps (MuJoCo: mj_step calls)
  bool ok = true;             // false: the run failed (error holds why)
  std::string error;
  bool at_rest = true;        // the body (yaw and translation) was at rest when the run ended
  std::vector<std::string> warnings;  // the result is computed but doubtful: why (e.g. still moving at the end)
  std::map<std::string, double> extra;  // model-specific figures (e.g. tracking_rms_deg_j1)
};

// How a run's warning begins when its phi_net is not to be read as a plain number (the MuJoCo
// run's own uncertainty exceeds its stated share, or its check run failed): readers (console,
// report, verdict) mark such a result "uncertain".
inline constexpr char kUncertainWarning[] = "phi_net is uncertain";

struct RunResult {
  RunSummary summary;
  TimeSeries series;
  // The model already kept only output.time_series: thin's rows (thinRowIndices); else every
  // sample, and the caller thins.
  bool series_thinned = false;
};

}  // namespace tailsim
