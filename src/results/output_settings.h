// The output time grid that both models sample on, so their CSVs line up row for row, and which
// of the sampled rows are kept, and where (docs/experiment-format.md "Time-series output").
#pragma once

#include <cmath>

#include "settings/fields.h"

namespace tailsim {

// Which rows of the time series a case keeps.
enum class TimeSeriesOutput {
  kFull,  // every sample (today's behaviour)
  kThin,  // the rows of thinRows() (results/thin_series.h): a 10-sample grid plus events and extremes
  kNone,  // no time series: the case's results are its row of results.csv / summary.json only
};

// Where the kept rows go.
enum class TimeSeriesFile {
  kCsv,   // DIR/cases/<dir>/<model>.csv, one file per case and model
  kHdf5,  // DIR/time_series.h5, one group per case and model for the whole experiment
};

inline const settings::EnumNames<TimeSeriesOutput>& timeSeriesOutputNames() {
  static const settings::EnumNames<TimeSeriesOutput> k = {
      {TimeSeriesOutput::kFull, "full"}, {TimeSeriesOutput::kThin, "thin"}, {TimeSeriesOutput::kNone, "none"}};
  return k;
}
inline const settings::EnumNames<TimeSeriesFile>& timeSeriesFileNames() {
  static const settings::EnumNames<TimeSeriesFile> k = {{TimeSeriesFile::kCsv, "csv"}, {TimeSeriesFile::kHdf5, "hdf5"}};
  return k;
}

struct OutputSettings {
  double sample_dt_s = 1e-3;  // CSV row spacing  [s]
  double duration_s = 0.0;    // simulated time; 0 = tail end time + settle_s  [s]
  double settle_s = 0.5;      // time simulated after the tail stops, when duration_s = 0  [s]
  TimeSeriesOutput time_series = TimeSeriesOutput::kFull;
  TimeSeriesFile time_series_file = TimeSeriesFile::kCsv;

  // Whether the case gets its own folder DIR/cases/<dir>/ (CSV time series kept).
  bool caseFolder() const { return time_series != TimeSeriesOutput::kNone && time_series_file == TimeSeriesFile::kCsv; }

  // The run's length and rows, one rule for every model, the loader and the work estimate: a run
  // whose tail stops at tail_end_s ends at duration_s, or settle_s after the tail stops; its rows
  // are the grid 0, dt, 2 dt, ... up to t_end (a sample within 1e-9 dt of t_end counts), as a
  // double, so that a caller checks it against limits::kMaxRowsPerRun before it becomes a count.
  double runEnd(double tail_end_s) const { return duration_s > 0.0 ? duration_s : tail_end_s + settle_s; }
  double rows(double t_end) const { return std::floor(t_end / sample_dt_s + 1e-9) + 1; }
};

// The YAML/JSON keys of OutputSettings (settings/fields.h), declared once.
template <class V, class S>
settings::For<S, OutputSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"sample_dt_s", "CSV row spacing [s]"}, s.sample_dt_s, Limits::positive());
  v.number(Field{"duration_s", "simulated time; 0 = tail end time + settle_s [s]"}, s.duration_s, Limits::nonNegative());
  v.number(Field{"settle_s", "time simulated after the tail stops, when duration_s = 0 [s]"}, s.settle_s,
           Limits::nonNegative());
  v.choice(Field{"time_series",
                 "full: every sample; thin: every 10th sample plus stick/slip switches, tail phase boundaries and "
                 "phi's turning points and extremes; none: no time series, no case folders (results.csv only)"},
           s.time_series, timeSeriesOutputNames());
  v.choice(Field{"time_series_file",
                 "csv: cases/<case>/<model>.csv; hdf5: the whole experiment in DIR/time_series.h5 (one group per "
                 "case and model), no case folders"},
           s.time_series_file, timeSeriesFileNames());
}

}  // namespace tailsim
