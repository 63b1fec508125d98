// Output.time_series full | thin | none and output.time_series_file csv | hdf5 — which
// rows thin keeps, the HDF5 file's round trip, and the runner's folders, journal and resume.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "models/perfoot/per_foot_model.h"
#include "analytic_test_util.h"
#include "random_cases.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/time_series_h5.h"
#include "plotting/result_folder.h"
#include "common/atomic_file.h"
#include "results/columns.h"
#include "results/thin_series.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tailsim_tsout_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// A series with t, phi and rot_state columns from explicit values.
TimeSeries series(const std::vector<double>& phi, const std::vector<double>& state) {
  TimeSeries ts;
  ts.addColumn(col::kT);
  ts.addColumn(col::kPhi);
  ts.addColumn(col::kRotState);
  for (size_t k = 0; k < phi.size(); ++k) ts.appendRow({static_cast<double>(k) / 1000.0, phi[k], state[k]});
  return ts;
}

fs::path writeSweep(const fs::path& dir, const std::string& output, const std::string& models = "[analytic]") {
  const fs::path f = dir / "sweep.yaml";
  std::ofstream(f) << "name: ts_sweep\nrobot: paper\ntail: {links: 1}\n"
                   << "trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.2, 0.3, 0.4, 0.5]}}\n"
                   << "models: " << models << "\noutput: " << output << "\n";
  return f;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

}  // namespace

// ---- thin -----------------------------------------------------------------------------------

TEST(ThinSeries, KeepsGridSwitchesMarksAndTurningPoints) {
  // 25 rows: phi rises to row 7, falls to row 13, stays flat from 13 to 18, rises again; the
  // state switches between rows 4/5 and 13/14.
  std::vector<double> phi(25), state(25, 0.0);
  for (int k = 0; k < 25; ++k)
    phi[k] = k <= 7 ? k : k <= 13 ? 14 - k : k <= 18 ? 1 : 1 + 0.5 * (k - 18);
  for (int k = 5; k <= 13; ++k) state[k] = 1.0;
  const std::vector<size_t> rows = thinRowIndices(series(phi, state), {0.0105}, 10);
  // grid 0, 10, 20, last 24; switch 4, 5 and 13, 14; mark 0.0105 between rows 10 and 11;
  // turning points: 7 (max), 13 (min, plateau starts), 18 (plateau ends); global max row 7,
  // global min row 0 (phi = 0 there).
  const std::vector<size_t> expect = {0, 4, 5, 7, 10, 11, 13, 14, 18, 20, 24};
  EXPECT_EQ(rows, expect);
}

TEST(ThinSeries, MarkOnASampleKeepsThatRowAndTheOneBefore) {
  std::vector<double> phi(12, 0.0), state(12, 0.0);
  const std::vector<size_t> rows = thinRowIndices(series(phi, state), {0.003}, 10);
  EXPECT_EQ(rows, (std::vector<size_t>{0, 2, 3, 10, 11}));
}

TEST(ThinSeries, Fig7KeepsEveryEventAndExtremeInAFifthOfTheRows) {
  const RunResult full = tailsim::testing::runFig7();
  ASSERT_TRUE(full.summary.ok);
  const TailTrajectory traj = tailsim::testing::sameMove(1, 0, -90, 0.25, 0.25);
  const TimeSeries thin = thinRows(full.series, traj.breakpoints());
  ASSERT_EQ(thin.names(), full.series.names());
  EXPECT_LT(thin.numRows() * 5, full.series.numRows());
  EXPECT_EQ(thin.values(col::kT).back(), full.series.values(col::kT).back());
  // Every kept row is a row of the full series, unchanged.
  const auto& tf = full.series.values(col::kT);
  for (size_t k = 0; k < thin.numRows(); ++k) {
    const auto it = std::lower_bound(tf.begin(), tf.end(), thin.values(col::kT)[k]);
    ASSERT_TRUE(it != tf.end() && *it == thin.values(col::kT)[k]);
    const size_t r = static_cast<size_t>(it - tf.begin());
    for (size_t c = 0; c < thin.numColumns(); ++c) {
      const double a = thin.at(k, static_cast<int>(c)), b = full.series.at(r, static_cast<int>(c));
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b)));
    }
  }
  // The same number of state switches, and phi's range, as the full series.
  auto switches = [](const TimeSeries& s) {
    int n = 0;
    const auto& v = s.values(col::kRotState);
    for (size_t k = 1; k < v.size(); ++k) n += v[k] != v[k - 1];
    return n;
  };
  EXPECT_GT(switches(full.series), 0);
  EXPECT_EQ(switches(thin), switches(full.series));
  const auto& pf = full.series.values(col::kPhi);
  const auto& pt = thin.values(col::kPhi);
  EXPECT_EQ(*std::max_element(pt.begin(), pt.end()), *std::max_element(pf.begin(), pf.end()));
  EXPECT_EQ(*std::min_element(pt.begin(), pt.end()), *std::min_element(pf.begin(), pf.end()));
  // The tail's phase boundaries t0 = 0, t1 = 0.0625 and t2 = 0.25 s: the samples on both sides
  // (at most one sample_dt = 1 ms away) are kept.
  const auto& tt = thin.values(col::kT);
  for (double t : {0.0, 0.0625, 0.25}) {
    EXPECT_TRUE(std::any_of(tt.begin(), tt.end(), [&](double x) { return x <= t + 1e-12 && x > t - 1e-3 - 1e-12; })) << t;
    EXPECT_TRUE(std::any_of(tt.begin(), tt.end(), [&](double x) { return x >= t - 1e-12 && x < t + 1e-3 + 1e-12; })) << t;
  }
}

// ---- HDF5 -----------------------------------------------------------------------------------

TEST(TimeSeriesH5, WrittenFileReadsBackTheSameColumnsWithUnits) {
  const fs::path dir = tempDir("h5");
  const RunResult r = tailsim::testing::runFig7();
  const std::string path = (dir / "time_series.h5").string();
  {
    TimeSeriesH5Writer w(path);
    w.write("w_ss=0.25", "w_ss=0.25", "KEY1", {{"trajectory.w_ss", "0.25"}, {"note", "abc"}}, "analytic", "full",
            r.series);
    EXPECT_FALSE(fs::exists(path));  // nothing published before the end
    w.publish();
  }
  ASSERT_TRUE(fs::exists(path));
  for (const auto& f : fs::directory_iterator(dir)) EXPECT_EQ(f.path().string().find(".tailsim-tmp."), std::string::npos);
  const TimeSeriesH5Reader in(path);
  ASSERT_TRUE(in.ok());
  EXPECT_TRUE(in.hasCase("w_ss=0.25", "KEY1", {"analytic"}));
  EXPECT_FALSE(in.hasCase("w_ss=0.25", "KEY2", {"analytic"}));  // another resume key
  EXPECT_FALSE(in.hasCase("w_ss=0.25", "KEY1", {"mujoco"}));
  const TimeSeries back = in.read("w_ss=0.25", "analytic");
  ASSERT_EQ(back.names(), r.series.names());  // CSV column order kept
  ASSERT_EQ(back.numRows(), r.series.numRows());
  for (size_t c = 0; c < back.numColumns(); ++c)
    for (size_t k = 0; k < back.numRows(); ++k) {
      const double a = back.at(k, static_cast<int>(c)), b = r.series.at(k, static_cast<int>(c));
      ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << back.names()[c] << " row " << k;
    }
  EXPECT_THROW(in.read("w_ss=0.3", "analytic"), std::runtime_error);
  EXPECT_EQ(columnUnits("t_s"), "s");
  EXPECT_EQ(columnUnits("phidot_dps"), "deg/s");
  EXPECT_EQ(columnUnits("MzT_Nm"), "N m");
  EXPECT_EQ(columnUnits("rot_state"), "1");
  fs::remove_all(dir);
}

TEST(TimeSeriesH5, UnpublishedWriterLeavesNothing) {
  const fs::path dir = tempDir("h5_abandon");
  {
    TimeSeriesH5Writer w((dir / "time_series.h5").string());
    w.write("a", "a", "K", {}, "analytic", "thin", tailsim::testing::runFig7().series);
  }  // an exception unwinding the run: no file published, the temporary removed
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

// ---- runner -----------------------------------------------------------------------------------

TEST(TimeSeriesOutput, NoneWritesNoCaseFoldersAndResumesFromTheJournal) {
  const fs::path dir = tempDir("none");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  o.max_new_cases = 2;
  EXPECT_EQ(runExperiment(e, o).ran, 2);
  EXPECT_FALSE(fs::exists(dir / "out" / "cases"));
  const fs::path journal = dir / "out" / "cases.jsonl";
  std::string text = readText(journal);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2);
  // A torn last line (a kill inside the append) is ignored and cut off, not glued to the next line.
  std::ofstream(journal, std::ios::app) << "{\"dir\":\"w_ss=0.4\",\"experi";
  o.max_new_cases = -1;
  const RunStats s = runExperiment(e, o);
  EXPECT_EQ(s.resumed, 2);
  EXPECT_EQ(s.ran, 2);
  EXPECT_FALSE(fs::exists(dir / "out" / "cases"));
  text = readText(journal);
  std::istringstream lines(text);
  std::string line;
  std::vector<std::string> names;
  while (std::getline(lines, line)) names.push_back(nlohmann::json::parse(line).at("name").get<std::string>());
  EXPECT_EQ(names, (std::vector<std::string>{"w_ss=0.2", "w_ss=0.3", "w_ss=0.4", "w_ss=0.5"}));  // case order
  // results.csv holds every case; a plot reader says why there is no time series.
  const ExperimentResults r = loadResults((dir / "out").string());
  ASSERT_EQ(r.cases.size(), 4u);
  EXPECT_TRUE(std::isfinite(r.phiNet(r.cases[0], "analytic")));
  try {
    r.series(r.cases[0], "analytic");
    FAIL() << "no time series expected";
  } catch (const std::runtime_error& ex) {
    EXPECT_NE(std::string(ex.what()).find("output.time_series: none"), std::string::npos) << ex.what();
  }
  EXPECT_NE(r.seriesNote().find("4 of 4 cases"), std::string::npos);
  // The output mode is in the resume key: full recomputes every case and writes their folders.
  const Experiment full = loadExperiment(writeSweep(dir, "{time_series: full}").string());
  EXPECT_NE(caseKey(full.cases[0], false), caseKey(e.cases[0], false));
  EXPECT_EQ(runExperiment(full, o).ran, 4);
  EXPECT_TRUE(fs::exists(dir / "out" / "cases" / "w_ss=0.2" / "analytic.csv"));
  fs::remove_all(dir);
}

TEST(TimeSeriesOutput, ThinAndHdf5GiveTheFullSeriesRowsInOneFile) {
  const fs::path dir = tempDir("hdf5");
  const Experiment full = loadExperiment(writeSweep(dir, "{time_series: full}").string());
  RunOptions o;
  o.progress = false;
  o.out_dir = (dir / "full").string();
  runExperiment(full, o);
  const Experiment h5 = loadExperiment(writeSweep(dir, "{time_series: thin, time_series_file: hdf5}").string());
  o.out_dir = (dir / "h5").string();
  o.max_new_cases = 3;
  runExperiment(h5, o);  // 3 cases, published
  o.max_new_cases = -1;
  const RunStats s = runExperiment(h5, o);
  EXPECT_EQ(s.resumed, 3);  // their groups copied from the published file
  EXPECT_EQ(s.ran, 1);
  EXPECT_FALSE(fs::exists(dir / "h5" / "cases"));
  const ExperimentResults rf = loadResults((dir / "full").string());
  const ExperimentResults rh = loadResults((dir / "h5").string());
  ASSERT_EQ(rh.cases.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    const TimeSeries a = rf.series(rf.cases[i], "analytic");  // from the CSV (12 significant digits)
    const TimeSeries b = rh.series(rh.cases[i], "analytic");  // from time_series.h5 (exact)
    ASSERT_EQ(a.names(), b.names());
    ASSERT_LT(b.numRows() * 3, a.numRows());
    // Every thin row is the full CSV's row at the same time.
    const auto& ta = a.values(col::kT);
    for (size_t k = 0; k < b.numRows(); ++k) {
      const auto it = std::lower_bound(ta.begin(), ta.end(), b.values(col::kT)[k] - 1e-12);
      ASSERT_TRUE(it != ta.end());
      const size_t r = static_cast<size_t>(it - ta.begin());
      EXPECT_NEAR(a.values(col::kPhi)[r], b.values(col::kPhi)[k], 1e-9 * (1 + std::abs(b.values(col::kPhi)[k])));
    }
    EXPECT_EQ(rf.phiNet(rf.cases[i], "analytic"), rh.phiNet(rh.cases[i], "analytic"));
  }
  fs::remove_all(dir);
}

// appendRepeated (the analytic recorder's rows after the body comes to rest for good) writes what
// a loop of appendRow would, the grid column included bit for bit (k * dt, as the recorder's time).
TEST(TimeSeriesRows, AppendRepeatedEqualsAppendingEachRow) {
  TimeSeries a, b;
  for (const char* c : {"t_s", "x_m", "phi_deg"}) {
    a.addColumn(c);
    b.addColumn(c);
  }
  const double dt = 1e-3;
  std::vector<double> row = {7 * dt, 0.25, -3.5};
  a.appendRow(row);
  b.appendRow(row);
  for (long k = 8; k < 8 + 500; ++k) {
    row[0] = static_cast<double>(k) * dt;
    a.appendRow(row);
  }
  b.appendRepeated(row, 500, 0, 8, dt);
  ASSERT_EQ(a.numRows(), 501u);
  ASSERT_EQ(b.numRows(), 501u);
  for (int c = 0; c < 3; ++c)
    for (std::size_t i = 0; i < a.numRows(); ++i) ASSERT_EQ(a.at(i, c), b.at(i, c)) << c << " " << i;
  EXPECT_THROW(b.appendRepeated({1.0, 2.0}, 3, 0, 0, dt), std::logic_error);
  EXPECT_THROW(b.appendRepeated(row, 3, 3, 0, dt), std::logic_error);
}

// The analytic recorder writes rows row-major in blocks and moves them into the columns with
// appendRowMajor: the same table as appending each row, in blocks of any size (0 included).
TEST(TimeSeriesRows, AppendRowMajorEqualsAppendingEachRow) {
  TimeSeries a, b;
  for (const char* c : {"t_s", "x_m", "phi_deg", "rot_state"}) {
    a.addColumn(c);
    b.addColumn(c);
  }
  std::vector<double> block;
  std::size_t in_block = 0, rows = 0;
  for (std::size_t block_rows : {0u, 1u, 5u, 32u, 3u}) {
    for (std::size_t i = 0; i < block_rows; ++i, ++rows) {
      const double k = static_cast<double>(rows);
      const std::vector<double> row = {k * 1e-3, 0.5 * k, -k * k, std::fmod(k, 2.0)};
      a.appendRow(row);
      block.insert(block.end(), row.begin(), row.end());
      ++in_block;
    }
    b.appendRowMajor(block.data(), in_block);
    block.clear();
    in_block = 0;
  }
  ASSERT_EQ(a.numRows(), 41u);
  ASSERT_EQ(b.numRows(), 41u);
  for (int c = 0; c < 4; ++c)
    for (std::size_t i = 0; i < a.numRows(); ++i) ASSERT_EQ(a.at(i, c), b.at(i, c)) << c << " " << i;
}

// With time_series none (and no video) the analytic and per-foot runs record two rows, t = 0 and
// the end, instead of one per sample_dt_s: nothing reads the others. Every summary field of every
// run is the same as with the full series, bit for bit (wall times aside): the summaries come
// from the state, and a row's evaluation does not feed back into the run. Strokes that slide,
// stick and break away again (stiction, two links with their own timings) and the ADAMS law.
TEST(TimeSeriesOutput, NoneRecordsTwoRowsAndSummarizesTheSame) {
  const fs::path dir = tempDir("none_same");
  auto write = [&](const std::string& output) {
    const fs::path f = dir / ("sweep_" + output + ".yaml");
    std::ofstream(f) << "name: ts_same\nrobot: paper\ntail: {links: 2}\n"
                     << "friction: {mu_s: {sweep: [0.15, 0.4]}}\n"
                     << "trajectory: {theta0_deg: [45, 0], dtheta_deg: [-90, 60], dT_s: [0.25, 0.15], "
                     << "w_ss: [{sweep: [0.2, 0.7]}, 0.5], t0_s: [0, 0.05]}\n"
                     << "effects: {friction: {sweep: [stiction, continuous]}}\n"
                     << "models: [analytic, perfoot]\noutput: {time_series: " << output << "}\n";
    return loadExperiment(f.string());
  };
  const Experiment full = write("full"), none = write("none");
  ASSERT_EQ(none.cases.size(), 8u);
  for (const ExperimentCase& c : none.cases)
    for (const char* m : {"analytic", "perfoot"}) {
      const RunResult r = findModel(m)->run(c, nullptr);
      EXPECT_EQ(r.series.numRows(), 2u) << m << " " << c.name;
    }
  RunOptions o;
  o.progress = false;
  o.out_dir = (dir / "full").string();
  runExperiment(full, o);
  o.out_dir = (dir / "none").string();
  runExperiment(none, o);
  std::map<std::string, nlohmann::json> by_name;
  std::istringstream lines(readText(dir / "none" / "cases.jsonl"));
  for (std::string line; std::getline(lines, line);) {
    const nlohmann::json j = nlohmann::json::parse(line);
    by_name[j.at("name").get<std::string>()] = j.at("runs");
  }
  ASSERT_EQ(by_name.size(), 8u);
  int compared = 0, cases = 0;
  for (const fs::directory_entry& d : fs::directory_iterator(dir / "full" / "cases")) {
    const nlohmann::json j = nlohmann::json::parse(readText(d.path() / "result.json"));
    const std::string name = j.at("name").get<std::string>();
    const nlohmann::json& f = j.at("runs");
    ASSERT_TRUE(by_name.count(name)) << name;
    const nlohmann::json& n = by_name.at(name);
    ++cases;
    for (const char* m : {"analytic", "perfoot"}) {
      ASSERT_TRUE(f.contains(m) && n.contains(m)) << name;
      EXPECT_GE(f.at(m).at("extra").size(), 5u) << name << " " << m;  // compared as one object below
      for (const auto& [key, value] : f.at(m).items()) {
        if (key == "wall_time_s") continue;
        EXPECT_EQ(value, n.at(m).value(key, nlohmann::json())) << name << " " << m << " " << key;
        ++compared;
      }
    }
  }
  EXPECT_EQ(cases, 8);
  EXPECT_GE(compared, 8 * 2 * 6);
  fs::remove_all(dir);
}

// With time_series thin the analytic model keeps every row's state and evaluates only the rows
// thinning keeps (AnalyticRecorder): the series equals thinRows of the full series, every value
// bit for bit (NaN where NaN), and the summary is the same. Fig. 7 and 400 seeded random cases
// (n 1-6, stiction / ADAMS law / none, paper and exact coupling, bodies at rest for good before
// the end, whose rows are copies of one: random_cases.h).
TEST(TimeSeriesOutput, ThinRowsEvaluatedLazilyEqualThinningTheFullSeries) {
  using namespace tailsim::testing;
  auto same = [](const RunResult& full, const RunResult& thin, const std::vector<double>& marks, const std::string& what) {
    ASSERT_FALSE(full.series_thinned);
    ASSERT_TRUE(thin.series_thinned);
    const TimeSeries want = thinRows(full.series, marks);
    ASSERT_EQ(want.names(), thin.series.names()) << what;
    ASSERT_EQ(want.numRows(), thin.series.numRows()) << what;
    EXPECT_LT(thin.series.numRows(), full.series.numRows()) << what;
    for (size_t c = 0; c < want.numColumns(); ++c)
      for (size_t k = 0; k < want.numRows(); ++k) {
        const double a = want.at(k, static_cast<int>(c)), b = thin.series.at(k, static_cast<int>(c));
        if (!(std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b))))
          FAIL() << what << ": row " << k << " column " << want.names()[c] << ": " << a << " vs " << b;
      }
    EXPECT_EQ(full.summary.phi_net_deg, thin.summary.phi_net_deg) << what;
    EXPECT_EQ(full.summary.solver_steps, thin.summary.solver_steps) << what;
    EXPECT_EQ(full.summary.extra, thin.summary.extra) << what;
    EXPECT_EQ(full.summary.ok, thin.summary.ok) << what;
  };
  OutputSettings thin;
  thin.time_series = TimeSeriesOutput::kThin;
  {
    const RobotParams r = paperRobot(1);
    const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);
    same(simulateAnalytic(r, tr, {}, {}, {}), simulateAnalytic(r, tr, {}, {}, thin), tr.breakpoints(), "fig7");
  }
  RandomCases gen(4242);
  int repeated = 0;
  for (int k = 0; k < 400; ++k) {
    const RandomCase c = gen.next();
    const RunResult full = simulateAnalytic(c.robot, c.trajectory, c.settings, c.effects, {});
    if (!full.summary.ok) continue;
    const size_t n = full.series.numRows();
    bool copies = n > 2;  // the last two rows differ only in t: rows at rest, repeated
    for (size_t col = 1; copies && col < full.series.numColumns(); ++col) {
      const double a = full.series.at(n - 1, static_cast<int>(col)), b = full.series.at(n - 2, static_cast<int>(col));
      copies = a == b || (std::isnan(a) && std::isnan(b));
    }
    repeated += copies;
    same(full, simulateAnalytic(c.robot, c.trajectory, c.settings, c.effects, thin), c.trajectory.breakpoints(),
         "random case " + std::to_string(k) + ": " + describe(c));
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(repeated, 50);
  // The per-foot model's recorder does the same (both normal-load models).
  {
    const RobotParams r = paperRobot(1);
    const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);
    same(simulatePerFoot(r, tr, {}, {}, {}), simulatePerFoot(r, tr, {}, {}, thin), tr.breakpoints(), "per-foot fig7");
  }
  RandomCases pf_gen(4343);
  int pf_repeated = 0, pf_compared = 0;
  for (int k = 0; k < 120; ++k) {
    const RandomCase c = pf_gen.next();
    PerFootSettings s;
    if (k % 2) s.normal_loads = NormalLoadModel::kLoadTransfer;
    const RunResult full = simulatePerFoot(c.robot, c.trajectory, s, c.effects, {});
    if (!full.summary.ok) continue;
    const size_t n = full.series.numRows();
    bool copies = n > 2;
    for (size_t col = 1; copies && col < full.series.numColumns(); ++col) {
      const double a = full.series.at(n - 1, static_cast<int>(col)), b = full.series.at(n - 2, static_cast<int>(col));
      copies = a == b || (std::isnan(a) && std::isnan(b));
    }
    pf_repeated += copies;
    ++pf_compared;
    same(full, simulatePerFoot(c.robot, c.trajectory, s, c.effects, thin), c.trajectory.breakpoints(),
         "per-foot random case " + std::to_string(k) + ": " + describe(c));
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(pf_compared, 100);
  EXPECT_GT(pf_repeated, 10);
}
