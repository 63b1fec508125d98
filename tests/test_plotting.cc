// Plots and the reproduction report from synthetic result folders whose answers are known:
// monotone sweeps must give YES, broken ones NO naming the failing step, closed-form pose data
// must match Eq. (24), and every figure must exist as a non-trivial PNG and SVG.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include "experiments/experiment_loader.h"
#include "plotting/figure_sheet.h"
#include "plotting/findings.h"
#include "plotting/gnuplot.h"
#include "plotting/plots.h"
#include "plotting/report.h"
#include "plotting/style.h"
#include "plotting/sweep_summary.h"
#include "common/atomic_file.h"
#include "results/csv.h"
#include "trajectory/split_cycle_profile.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace tailsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

struct SynthCase {
  std::map<std::string, json> sweep;
  std::map<std::string, double> phi;             // model -> phi_net_deg
  std::map<std::string, TimeSeries> csv;         // model -> CSV
};

// Writes DIR/summary.json, experiment.yaml, robot.yaml (the paper robot, as a run copies it),
// cases/<name>/<model>.csv in the documented layout. Findings take the values the cases ran with
// from experiment.yaml through the loader, so the experiments they need are real experiment files.
void writeExperiment(const fs::path& dir, const std::string& name, const std::vector<std::string>& swept_keys,
                     const std::vector<SynthCase>& cases, const std::string& yaml) {
  fs::create_directories(dir / "cases");
  json s;
  s["experiment"] = name;
  s["source"] = (dir / "source.yaml").string();
  s["swept_keys"] = swept_keys;
  s["cases"] = json::array();
  for (const SynthCase& c : cases) {
    std::string cname;
    for (const auto& [k, v] : c.sweep) {
      const std::string leaf = k.substr(k.rfind('.') + 1);
      cname += (cname.empty() ? "" : ",") + leaf + "=" + (v.is_string() ? v.get<std::string>() : v.dump());
    }
    if (cname.empty()) cname = "base";
    json j;
    j["name"] = cname;
    j["dir"] = cname;
    j["sweep"] = json::object();
    for (const auto& [k, v] : c.sweep) j["sweep"][k] = v;
    for (const auto& [m, phi] : c.phi) {
      j["runs"][m] = {{"model", m}, {"phi_net_deg", phi}, {"ok", true}, {"t_stop_s", 0.4}, {"wall_time_s", 0.01}};
    }
    fs::create_directories(dir / "cases" / cname);
    for (const auto& [m, ts] : c.csv) writeCsvAtomic((dir / "cases" / cname / (m + ".csv")).string(), ts);
    s["cases"].push_back(j);
  }
  writeFileAtomic((dir / "summary.json").string(), s.dump(2));
  writeFileAtomic((dir / "experiment.yaml").string(), yaml);
  writeFileAtomic((dir / "source.yaml").string(), yaml);
  std::ifstream robot(fs::path(TAILSIM_SOURCE_DIR) / "configs" / "robots" / "paper_quadruped.yaml");
  std::stringstream rs;
  rs << robot.rdbuf();
  writeFileAtomic((dir / "robot.yaml").string(), rs.str());
}

// A simulate CSV driven by split-cycle profiles (joint columns), with a made-up phi(t) and
// moments. `lag_s` shifts the joint motion (a badly tracking model).
TimeSeries simCsv(const std::vector<SplitCycleParams>& joints, double phi_net, double lag_s = 0.0) {
  TimeSeries ts;
  ts.addColumn("t_s");
  const int n = static_cast<int>(joints.size());
  for (int j = 1; j <= n; ++j) {
    ts.addColumn("theta" + std::to_string(j) + "_deg");
    ts.addColumn("thetadot" + std::to_string(j) + "_dps");
  }
  for (const char* c : {"phi_deg", "phidot_dps", "MzT_Nm", "MzF_Nm", "Izz_phiddot_Nm"}) ts.addColumn(c);
  double end = 0;
  for (const auto& p : joints) end = std::max(end, p.t0_s + p.dT_s);
  const double dur = end + 0.3, dt = 1e-3;
  for (int k = 0; k * dt <= dur + 1e-12; ++k) {
    const double t = k * dt;
    std::vector<double> row = {t};
    for (const auto& p : joints) {
      const JointState st = SplitCycleProfile(p).at(t - lag_s);
      row.push_back(st.theta / kDeg);
      row.push_back(st.theta_dot / kDeg);
    }
    const double x = std::min(t / end, 1.0);
    const double mzt = 5 * std::sin(2 * kPi * x) * (t < end);
    row.push_back(phi_net * x * x * (3 - 2 * x));
    row.push_back(t < end ? phi_net * 6 * x * (1 - x) / end : 0.0);  // never turns back
    row.push_back(mzt);
    row.push_back(-0.5 * mzt);
    row.push_back(0.5 * mzt);
    ts.appendRow(row);
  }
  return ts;
}

TimeSeries poseCsv(const std::map<std::string, double>& values) {
  TimeSeries ts;
  std::vector<double> row;
  for (const auto& [k, v] : values) {
    ts.addColumn(k);
    row.push_back(v);
  }
  ts.appendRow(row);
  return ts;
}

class SyntheticSuite : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(root_); }
  static void SetUpTestSuite() {
    // One folder per process: CTest runs the tests of this suite as parallel processes.
    root_ = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_suite_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);

    // fig06a: no sweep, MuJoCo rotates more.
    {
      SplitCycleParams p{0.0, -90 * kDeg, 0.25, 0.25, 0.0};
      writeExperiment(root_ / "fig06a_model_comparison_1dof", "fig06a_model_comparison_1dof", {},
                      {{{}, {{"analytic", 10.0}, {"mujoco", 14.0}},
                        {{"analytic", simCsv({p}, 10.0)}, {"mujoco", simCsv({p}, 14.0)}}}},
                      "name: fig06a_model_comparison_1dof\nkind: simulate\n");
    }
    // fig07: exact profile for analytic; MuJoCo lags 20 ms (peak time off by more than tolerance).
    {
      SplitCycleParams p{0.0, -90 * kDeg, 0.25, 0.25, 0.0};
      writeExperiment(root_ / "fig07_loading", "fig07_loading", {},
                      {{{}, {{"analytic", 8.0}, {"mujoco", 9.0}},
                        {{"analytic", simCsv({p}, 8.0)}, {"mujoco", simCsv({p}, 9.0, 0.02)}}}},
                      "name: fig07_loading\nkind: simulate\nrobot: robot.yaml\ntrajectory: {theta0_deg: 0, "
                      "dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n");
    }
    // fig08: pose over theta, Eq. (24) closed form with thetadot = thetaddot = 1.
    {
      const double mQ = 8.458, mL = 2.4, L = 0.3, IzzL = 2.236e-2, d = 0.125, m = mQ + mL;
      const double Ieff = mQ * mL / (2 * m) * L * d, rot = -(IzzL + 0.25 * mL * L * L * mQ / m);
      std::vector<SynthCase> cs;
      for (int th = -90; th <= 90; th += 15) {
        const double tan = -Ieff * std::cos(th * kDeg), cen = Ieff * std::sin(th * kDeg);
        cs.push_back({{{"pose.theta_deg", th}},
                      {{"analytic", 0.0}},
                      {{"analytic", poseCsv({{"MzT_tan_Nm", tan}, {"MzT_cen_Nm", cen}, {"MzT_Nm", rot + tan + cen},
                                             {"Izz_kgm2", 0.3}, {"LF_m", 0.2}})}}});
      }
      writeExperiment(root_ / "fig08_moment_contributions", "fig08_moment_contributions", {"pose.theta_deg"}, cs,
                      "name: fig08_moment_contributions\nkind: pose\nrobot: robot.yaml\ntail: {links: 1}\n"
                      "quadruped: {d_Q2B_m: 0.125}\npose: {theta_deg: {range: [-90, 90, 15]}, thetadot_radps: 1, "
                      "thetaddot_radps2: 1}\n");
    }
    // fig09: phi_net = 100 d + g(theta0), g peaks at 60 except for d = 0.15 (peak at 75);
    // analytic only. Rises with d everywhere.
    {
      std::vector<SynthCase> cs;
      for (int i = 0; i <= 6; ++i)
        for (int th = 0; th <= 90; th += 15) {
          const double d = 0.025 * i;
          double g = -std::pow((th - 60) / 30.0, 2);
          if (i == 6) g = -std::pow((th - 75) / 30.0, 2);
          char dv[16];
          std::snprintf(dv, sizeof dv, "%g", d);
          cs.push_back({{{"quadruped.d_Q2B_m", std::string(dv)}, {"trajectory.theta0_deg", th}},
                        {{"analytic", 100 * d + g}},
                        {}});
        }
      writeExperiment(root_ / "fig09_theta0_dQ2B", "fig09_theta0_dQ2B",
                      {"quadruped.d_Q2B_m", "trajectory.theta0_deg"}, cs, "name: fig09_theta0_dQ2B\n");
    }
    // fig10: L_F = 0.2 (1 + 0.02 sin theta * d / 0.15): max variation 2 % from the median 0.2.
    {
      std::vector<SynthCase> cs;
      for (int i = 0; i <= 6; ++i)
        for (int th = -90; th <= 90; th += 30) {
          const double d = 0.025 * i;
          cs.push_back({{{"quadruped.d_Q2B_m", d}, {"pose.theta_deg", th}},
                        {{"analytic", 0.0}},
                        {{"analytic", poseCsv({{"LF_m", 0.2 * (1 + 0.02 * std::sin(th * kDeg) * d / 0.15)}})}}});
        }
      writeExperiment(root_ / "fig10_LF", "fig10_LF", {"quadruped.d_Q2B_m", "pose.theta_deg"}, cs,
                      "name: fig10_LF\nkind: pose\nrobot: robot.yaml\nquadruped: {d_Q2B_m: {range: [0, 0.15, "
                      "0.025]}}\npose: {theta_deg: {range: [-90, 90, 30]}}\n");
    }
    // fig11: analytic falls with w_ss; MuJoCo has a bump between 0.5 and 0.6.
    {
      std::vector<SynthCase> cs;
      for (int i = 1; i <= 9; ++i) {
        const double w = 0.1 * i;
        const double mj = 20 - 10 * w + (i == 6 ? 2.0 : 0.0);
        SplitCycleParams p{45 * kDeg, -90 * kDeg, 0.25, w, 0.0};
        cs.push_back({{{"trajectory.w_ss", w}},
                      {{"analytic", 15 - 10 * w}, {"mujoco", mj}},
                      {{"analytic", simCsv({p}, 15 - 10 * w)}, {"mujoco", simCsv({p}, mj)}}});
      }
      writeExperiment(root_ / "fig11_wss", "fig11_wss", {"trajectory.w_ss"}, cs, "name: fig11_wss\n");
    }
    // fig14: Eq. (25) trajectories, phi_net rising with n.
    {
      std::vector<SynthCase> cs;
      for (int n = 1; n <= 6; ++n) {
        const SplitCycleParams p = equalPeakSpeedParams(n, 600 * kDeg, 0.25);
        const std::vector<SplitCycleParams> joints(n, p);
        cs.push_back({{{"tail.links", n}},
                      {{"analytic", 5.0 + n}, {"mujoco", 6.0 + n}},
                      {{"analytic", simCsv(joints, 5.0 + n)}, {"mujoco", simCsv(joints, 6.0 + n)}}});
      }
      writeExperiment(root_ / "fig14_tail_dof", "fig14_tail_dof", {"tail.links"}, cs,
                      "name: fig14_tail_dof\nrobot: robot.yaml\ntail: {links: {range: [1, 6, 1]}}\n"
                      "trajectory: {rule: eq25, thetadot_max_dps: 600, w_ss: 0.25}\n");
    }
  }

  static std::vector<ExperimentResults> load() { return loadResultTree(root_.string()); }
  static const Finding& finding(const std::vector<Finding>& fs, const std::string& id) {
    for (const Finding& f : fs)
      if (f.id == id) return f;
    throw std::runtime_error("no finding " + id);
  }
  static Verdict verdict(const std::vector<Finding>& fs, const std::string& id, const std::string& model) {
    const ModelVerdict* v = finding(fs, id).verdictFor(model);
    if (!v) throw std::runtime_error("no verdict for " + model + " in " + id);
    return v->verdict;
  }
  static fs::path root_;
};
fs::path SyntheticSuite::root_;

TEST(CheckTrend, StrictMonotonicity) {
  EXPECT_TRUE(checkTrend({1, 2, 3}, +1).holds);
  EXPECT_FALSE(checkTrend({1, 2, 3}, -1).holds);
  EXPECT_TRUE(checkTrend({3, 2, 1}, -1).holds);
  const Trend flat = checkTrend({1, 2, 2, 3}, +1);
  EXPECT_TRUE(flat.complete);
  EXPECT_FALSE(flat.holds);  // a flat step is no rise
  EXPECT_EQ(flat.worst, 1u);
  const Trend dip = checkTrend({1, 3, 2.5, 4}, +1);
  EXPECT_FALSE(dip.holds);
  EXPECT_EQ(dip.worst, 1u);
  EXPECT_DOUBLE_EQ(dip.min_step, -0.5);
  EXPECT_FALSE(checkTrend({1, NAN, 3}, +1).complete);
  // Zero plateaus (static friction never broken) are skipped only when asked, and only at zero.
  EXPECT_FALSE(checkTrend({0, 0, 1, 2}, +1).holds);
  const Trend z = checkTrend({0, 0, 1, 2}, +1, 1e-9, true);
  EXPECT_TRUE(z.holds);
  EXPECT_EQ(z.zero_plateaus, 1);
  EXPECT_FALSE(checkTrend({1, 1, 2}, +1, 1e-9, true).holds);
  EXPECT_FALSE(checkTrend({0, 0, 0}, +1, 1e-9, true).holds);
  EXPECT_FALSE(checkTrend({0, 0, -1}, +1, 1e-9, true).holds);
}

TEST_F(SyntheticSuite, LoadsAxesSortedAndTyped) {
  const auto rs = load();
  ASSERT_EQ(rs.size(), 7u);
  const ExperimentResults* f09 = findExperiment(rs, "fig09");
  ASSERT_NE(f09, nullptr);
  ASSERT_EQ(f09->axes.size(), 2u);
  EXPECT_EQ(f09->axes[0].values.size(), 7u);  // string-valued d_Q2B parsed as numbers
  EXPECT_TRUE(f09->axes[0].numeric);
  EXPECT_DOUBLE_EQ(f09->axes[0].number(6), 0.15);
  EXPECT_EQ(f09->models, std::vector<std::string>{"analytic"});
  const ExperimentResults* f08 = findExperiment(rs, "fig08");
  ASSERT_NE(f08, nullptr);
  EXPECT_EQ(f08->kind, "pose");  // from experiment.yaml
  EXPECT_DOUBLE_EQ(f08->axes[0].number(0), -90);
  const ExperimentResults* f11 = findExperiment(rs, "fig11");
  ASSERT_NE(f11, nullptr);
  EXPECT_EQ(f11->models, (std::vector<std::string>{"analytic", "mujoco"}));
}

TEST_F(SyntheticSuite, FindingsMatchTheKnownAnswers) {
  const auto fs_ = computeFindings(load());
  // Monotone sweeps -> YES, the MuJoCo bump in fig11 -> NO naming the step.
  EXPECT_EQ(verdict(fs_, "fig11_wss_falls", "analytic"), Verdict::kYes);
  EXPECT_EQ(verdict(fs_, "fig11_wss_falls", "mujoco"), Verdict::kNo);
  EXPECT_NE(finding(fs_, "fig11_wss_falls").verdictFor("mujoco")->detail.find("0.5 and 0.6"), std::string::npos)
      << finding(fs_, "fig11_wss_falls").verdictFor("mujoco")->detail;
  EXPECT_EQ(verdict(fs_, "fig09_dQ2B_rises", "analytic"), Verdict::kYes);
  EXPECT_EQ(verdict(fs_, "fig09_dQ2B_rises", "mujoco"), Verdict::kNotAvailable);
  // Argmax at 60 for d = 0.025 .. 0.125 (5 of 6 values > 0), at 75 for 0.15.
  EXPECT_EQ(verdict(fs_, "fig09_max_at_60", "analytic"), Verdict::kYes);
  EXPECT_NE(finding(fs_, "fig09_max_at_60").verdictFor("analytic")->detail.find("5 of 6"), std::string::npos);
  EXPECT_EQ(verdict(fs_, "fig10_LF_variation", "analytic"), Verdict::kYes);
  EXPECT_NE(finding(fs_, "fig10_LF_variation").verdictFor("analytic")->detail.find("2.00 %"), std::string::npos)
      << finding(fs_, "fig10_LF_variation").verdictFor("analytic")->detail;
  EXPECT_EQ(verdict(fs_, "fig14_links_rises", "analytic"), Verdict::kYes);
  EXPECT_EQ(verdict(fs_, "fig14_links_rises", "mujoco"), Verdict::kYes);
  // Trajectories built from the real profiles satisfy Eqs. (20)-(23) and (25); a 20 ms lag does not.
  EXPECT_EQ(verdict(fs_, "split_cycle_peak", "analytic"), Verdict::kYes)
      << finding(fs_, "split_cycle_peak").verdictFor("analytic")->detail;
  EXPECT_EQ(verdict(fs_, "split_cycle_peak", "mujoco"), Verdict::kNo);
  // The synthetic phi(t) rises monotonically: no phase B-C (turning back), so Fig. 7's phases fail.
  EXPECT_EQ(verdict(fs_, "fig07_phases", "analytic"), Verdict::kNo);
  EXPECT_NE(finding(fs_, "fig07_phases").verdictFor("analytic")->detail.find("B-C no"), std::string::npos);
  EXPECT_EQ(verdict(fs_, "eq25_table", "analytic"), Verdict::kYes)
      << finding(fs_, "eq25_table").verdictFor("analytic")->detail;
  // Closed-form pose data matches Eq. (24) with the robot file's numbers; peaks at 0 and +-90.
  EXPECT_EQ(verdict(fs_, "eq24_closed_form", "analytic"), Verdict::kYes)
      << finding(fs_, "eq24_closed_form").verdictFor("analytic")->detail;
  EXPECT_EQ(verdict(fs_, "fig08_peaks", "analytic"), Verdict::kYes);
  EXPECT_EQ(verdict(fs_, "fig06_contact_rotates_more", "mujoco vs analytic"), Verdict::kYes);
  // Missing experiments are listed as n/a, not dropped.
  EXPECT_EQ(verdict(fs_, "fig12_dT_falls", "analytic"), Verdict::kNotAvailable);
  EXPECT_EQ(verdict(fs_, "fig13_larger_dtheta_wins", "analytic"), Verdict::kNotAvailable);
}

TEST_F(SyntheticSuite, WrongEq24DataIsRejected) {
  auto rs = load();
  // Same folder but with a d_Q2B the data was not made with: I_eff off by 20 %.
  const fs::path dir = root_ / "fig08_moment_contributions";
  std::string yaml;
  {
    std::ifstream in(dir / "experiment.yaml");
    std::stringstream ss;
    ss << in.rdbuf();
    yaml = ss.str();
  }
  const std::string bad = std::regex_replace(yaml, std::regex("d_Q2B_m: 0.125"), "d_Q2B_m: 0.15");
  writeFileAtomic((dir / "experiment.yaml").string(), bad);
  const auto fs_ = computeFindings(loadResultTree(root_.string()));
  writeFileAtomic((dir / "experiment.yaml").string(), yaml);
  EXPECT_EQ(verdict(fs_, "eq24_closed_form", "analytic"), Verdict::kNo);
}

// The findings read the folder, never the inputs it was made from: a changed source file (the
// live experiment) or a folder whose experiment.yaml cannot be loaded changes no verdict to YES.
TEST_F(SyntheticSuite, FindingsIgnoreTheLiveInputs) {
  const fs::path dir = root_ / "fig08_moment_contributions";
  std::ifstream in(dir / "source.yaml");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string yaml = ss.str();
  writeFileAtomic((dir / "source.yaml").string(),
                  std::regex_replace(yaml, std::regex("d_Q2B_m: 0.125"), "d_Q2B_m: 0.15"));
  const auto live_changed = computeFindings(loadResultTree(root_.string()));
  writeFileAtomic((dir / "source.yaml").string(), yaml);
  EXPECT_EQ(verdict(live_changed, "eq24_closed_form", "analytic"), Verdict::kYes);
  // Without its robot copy the folder's cases cannot be resolved: n/a saying why, not a guess.
  fs::rename(dir / "robot.yaml", dir / "robot.yaml.away");
  const auto rs = loadResultTree(root_.string());
  const auto no_robot = computeFindings(rs);
  fs::rename(dir / "robot.yaml.away", dir / "robot.yaml");
  EXPECT_EQ(verdict(no_robot, "eq24_closed_form", "analytic"), Verdict::kNotAvailable);
  const ExperimentResults* f08 = findExperiment(rs, "fig08");
  ASSERT_NE(f08, nullptr);
  EXPECT_TRUE(f08->resolved.empty());
  EXPECT_NE(f08->resolve_error.find("robot.yaml"), std::string::npos) << f08->resolve_error;
}

TEST_F(SyntheticSuite, PlotsAndReportAreWritten) {
  const std::vector<PlotFile> plots = plotResults(root_.string());
  std::set<std::string> stems;
  for (const PlotFile& p : plots) {
    const fs::path png(p.png), svg = fs::path(p.png).replace_extension(".svg");
    ASSERT_TRUE(fs::exists(png)) << p.png;
    ASSERT_TRUE(fs::exists(svg)) << svg;
    EXPECT_GT(fs::file_size(png), 5000u) << p.png;
    EXPECT_GT(fs::file_size(svg), 3000u) << svg;
    EXPECT_TRUE(fs::exists(fs::path(p.png).replace_extension(".gp")));
    stems.insert(png.stem().string());
  }
  // Each plots/ manifest names only files that are there, with the content it names (gnuplot's
  // empty log, which is removed, is not named).
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(root_)) {
    if (e.path().filename() != ".tailsim-manifest" || e.path().parent_path().filename() != "plots") continue;
    const std::string dir = e.path().parent_path().string();
    std::ifstream man(e.path());
    int lines = 0;
    for (std::string line; std::getline(man, line); ++lines) {
      const std::string name = line.substr(line.find("  ") + 2);
      ASSERT_TRUE(fs::exists(fs::path(dir) / name)) << dir << ": the manifest names " << name << ", which is not there";
      std::ifstream f(fs::path(dir) / name, std::ios::binary);
      std::stringstream ss;
      ss << f.rdbuf();
      EXPECT_TRUE(manifestNames(dir, name, ss.str())) << dir << "/" << name;
    }
    EXPECT_GT(lines, 0) << e.path();
  }
  for (const char* s : {"fig06a_model_comparison_1dof_phi", "fig06a_model_comparison_1dof_moments",
                        "fig07_loading_phi", "fig08_moment_contributions_contributions",
                        "fig08_moment_contributions_LF", "fig09_theta0_dQ2B_phi_net_map",
                        "fig09_theta0_dQ2B_phi_net_lines", "fig10_LF_LF_map", "fig11_wss_phi_net", "fig11_wss_phi_t",
                        "fig14_tail_dof_phi_net"})
    EXPECT_TRUE(stems.count(s)) << "missing figure " << s;

  const std::string path = writeReport(root_.string(), /*draw_plots=*/false);
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string md = ss.str();
  EXPECT_NE(md.find("## Paper claims, model by model"), std::string::npos);
  EXPECT_NE(md.find("](fig09_theta0_dQ2B/plots/fig09_theta0_dQ2B_phi_net_map.png)"), std::string::npos);
  EXPECT_NE(md.find("mujoco: Sec. 4.5, Fig. 11"), std::string::npos);  // listed under "Not reproduced"
  EXPECT_NE(md.find("| fig06a_model_comparison_1dof | mujoco | +14.000 |"), std::string::npos);
}

// Width and height from a PNG's IHDR chunk (bytes 16-23, big-endian); {0, 0} if not a PNG.
std::pair<unsigned, unsigned> pngSize(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  unsigned char b[24] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  if (!in || b[0] != 0x89 || b[1] != 'P' || b[2] != 'N' || b[3] != 'G' || std::string(b + 12, b + 16) != "IHDR")
    return {0, 0};
  auto be = [&](int o) { return (unsigned(b[o]) << 24) | (unsigned(b[o + 1]) << 16) | (unsigned(b[o + 2]) << 8) | b[o + 3]; };
  return {be(16), be(20)};
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Every figure is drawn at the size its script asks for, titled in words (never the experiment's
// name), and DIR/figures.html shows each one once, in paper order, with its caption.
TEST_F(SyntheticSuite, FiguresAreSizedTitledAndListedOnTheSheet) {
  const std::vector<PlotFile> plots = plotResults(root_.string());
  ASSERT_GE(plots.size(), 11u);
  const std::string sheet = readText(root_ / "figures.html");
  size_t last_pos = 0;
  for (const PlotFile& p : plots) {
    const std::string gp = readText(fs::path(p.png).replace_extension(".gp"));
    std::smatch m;
    ASSERT_TRUE(std::regex_search(gp, m, std::regex(R"(set terminal pngcairo .*size (\d+),(\d+))"))) << p.png;
    EXPECT_EQ(pngSize(p.png), std::make_pair(unsigned(std::stoul(m[1])), unsigned(std::stoul(m[2])))) << p.png;
    const std::string experiment = fs::path(p.png).parent_path().parent_path().filename().string();
    // titles of the figure, its panels and its legend entries
    const std::regex title_re(R"(title '([^']*)')");
    for (auto it = std::sregex_iterator(gp.begin(), gp.end(), title_re); it != std::sregex_iterator(); ++it) {
      const std::string t = (*it)[1].str();
      EXPECT_EQ(t.find(experiment), std::string::npos) << p.png << ": title '" << t << "'";
    }
    EXPECT_EQ(p.title.find(experiment), std::string::npos) << p.title;
    EXPECT_FALSE(p.caption.empty());
    // listed once, with a relative link, in the order drawn (experiments in figure order here)
    const std::string rel = fs::relative(p.png, root_).generic_string();
    const std::string img = "<img src=\"" + rel + "\"";
    const size_t pos = sheet.find(img);
    ASSERT_NE(pos, std::string::npos) << rel << " not on the sheet";
    EXPECT_EQ(sheet.find(img, pos + 1), std::string::npos) << rel << " twice on the sheet";
    EXPECT_GT(pos, last_pos) << rel << " out of order";
    last_pos = pos;
  }
  size_t figures = 0;
  for (size_t i = sheet.find("<figcaption>"); i != std::string::npos; i = sheet.find("<figcaption>", i + 1)) ++figures;
  EXPECT_EQ(figures, plots.size());
}

TEST(FigureWords, KeysValuesAndFigureNames) {
  EXPECT_EQ(gpValueLabel("quadruped.d_Q2B_m", "0.025"), "d_{Q2B} = 25 mm");
  EXPECT_EQ(gpValueLabel("trajectory.dtheta_deg", "-90"), "Δθ = -90°");
  EXPECT_EQ(gpValueLabel("effects.friction", "stiction"), "stiction");
  EXPECT_EQ(gpValueLabel("analytic.coupling", "exact"), "exact coupling");
  EXPECT_EQ(gpValueLabel("tail.links", "3"), "3 links");
  EXPECT_EQ(gpAxisLabel("quadruped.d_Q2B_m"), "d_{Q2B} [mm]");
  // keys without a symbol of their own: words, with what they belong to; symbol-like names stay
  EXPECT_EQ(gpAxisLabel("mujoco.foot_shape"), "MuJoCo foot shape");
  EXPECT_EQ(gpAxisLabel("quadruped.mass_kg"), "body mass [kg]");
  EXPECT_EQ(gpAxisLabel("mujoco.body_height_m"), "MuJoCo body height [m]");
  EXPECT_EQ(gpValueLabel("mujoco.foot_shape", "box"), "MuJoCo foot shape = box");
  EXPECT_EQ(gpText("case d_Q2B_m=0.1"), "case d\\_Q2B\\_m=0.1");
  EXPECT_EQ(gpSymbols("phi_net over theta0 and M_zT"), "φ_{net} over θ_0 and M_{z,T}");
  EXPECT_EQ(figureName("Fig. 6(a): phi(t), analytic vs MuJoCo", "fig06a"), "Fig. 6a");
  EXPECT_EQ(figureName("", "my_run"), "my run");
  EXPECT_LT(figureOrder("Fig. 6(b): x"), figureOrder("Fig. 6 1-link case: y"));
  EXPECT_LT(figureOrder("Fig. 7: x"), figureOrder("Fig. 7 case with mu_s and mu_d swapped"));
  EXPECT_LT(figureOrder("Fig. 9: x"), figureOrder("Fig. 10: x"));
  EXPECT_EQ(modelColor("analytic"), "#0072B2");
  EXPECT_EQ(modelColor("mujoco"), "#D55E00");
}

TEST(ResultFolder, FallsBackToCaseResultFiles) {
  const fs::path dir = fs::path(TAILSIM_BINARY_DIR) / "test_plotting_partial";
  fs::remove_all(dir);
  fs::create_directories(dir / "cases" / "w_ss=0.1");
  fs::create_directories(dir / "cases" / "w_ss=0.2");
  writeFileAtomic((dir / "experiment.yaml").string(), "name: partial\nkind: simulate\n");
  for (const char* w : {"0.1", "0.2"}) {
    json j = {{"name", std::string("w_ss=") + w},
              {"dir", std::string("w_ss=") + w},
              {"experiment", "partial"},
              {"sweep", {{"trajectory.w_ss", w}}},
              {"runs", {{"analytic", {{"phi_net_deg", 3.0}, {"ok", true}}}}}};
    writeFileAtomic((dir / "cases" / (std::string("w_ss=") + w) / "result.json").string(), j.dump());
  }
  const ExperimentResults r = loadResults(dir.string());
  EXPECT_EQ(r.name, "partial");
  ASSERT_EQ(r.axes.size(), 1u);
  EXPECT_EQ(r.axes[0].values, (std::vector<std::string>{"0.1", "0.2"}));
  EXPECT_DOUBLE_EQ(r.phiNet(r.cases[1], "analytic"), 3.0);
  EXPECT_THROW(loadResults((dir / "nothing").string()), std::runtime_error);
}

// A suite folder that already has its result page (DIR/page/cases/e<i>c<k>.js): `tailsim plot DIR`
// again finds the experiments, not "page" as one more (empty) experiment; a run whose cases/ has
// case folders but no summary.json yet is still one.
TEST(ResultFolder, TheResultPageFolderIsNotAnExperiment) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_pagedir_" + std::to_string(::getpid()));
  fs::remove_all(root);
  writeExperiment(root / "sweep", "sweep", {"trajectory.dT_s"},
                  {{{{"trajectory.dT_s", 0.2}}, {{"analytic", 1.0}}, {}}, {{{"trajectory.dT_s", 0.3}}, {{"analytic", 2.0}}, {}}},
                  "name: sweep\n");
  fs::create_directories(root / "partial" / "cases" / "w_ss=0.1");
  fs::create_directories(root / "page" / "cases");
  writeFileAtomic((root / "page" / "cases" / "e0c0.js").string(), "tailsim.caseLoaded({});\n");
  writeFileAtomic((root / "page" / "data.js").string(), "tailsim.dataLoaded({});\n");
  std::vector<std::string> dirs;
  for (const ExperimentResults& r : loadResultTree(root.string())) dirs.push_back(fs::path(r.dir).filename().string());
  EXPECT_EQ(dirs, (std::vector<std::string>{"partial", "sweep"}));
  fs::remove_all(root);
}

// configs/paper/all.yaml: every figure's experiment loads, with the grids the paper states.
TEST(PaperConfigs, SuiteLoadsWithThePaperGrids) {
  const std::vector<Experiment> ex = loadExperimentSuite(std::string(TAILSIM_SOURCE_DIR) + "/configs/paper/all.yaml");
  std::map<std::string, const Experiment*> by;
  for (const Experiment& e : ex) by[e.name] = &e;
  const std::map<std::string, size_t> cases = {
      {"fig06a_model_comparison_1dof", 1}, {"fig06b_model_comparison_6dof", 1}, {"fig07_loading", 1},
      {"fig08_moment_contributions", 37},  {"fig09_theta0_dQ2B", 49},          {"fig10_LF", 91},
      {"fig11_wss", 9},                    {"fig12_dT_dtheta", 55},            {"fig13_equal_peak_speed", 5},
      {"fig14_tail_dof", 6},               {"mu_swapped", 1},                  {"model_bridge_n1", 4},
      {"model_bridge_n6", 4}};
  ASSERT_EQ(ex.size(), cases.size());
  for (const auto& [name, n] : cases) {
    ASSERT_TRUE(by.count(name)) << name;
    EXPECT_EQ(by[name]->cases.size(), n) << name;
  }
  // Fig. 6(b): six links of -30 deg each at d_Q2B = 0.1405 m.
  const ExperimentCase& b = by["fig06b_model_comparison_6dof"]->cases[0];
  ASSERT_EQ(b.joints.size(), 6u);
  for (const auto& j : b.joints) EXPECT_NEAR(j.dtheta_rad, -30 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(b.robot.quadruped.d_Q2B_m, 0.1405);
  // Fig. 13: peak 600 deg/s -> dT = |dtheta| / 300 deg/s, a Fig. 12 grid point (0.2 .. 0.6 s).
  for (const ExperimentCase& c : by["fig13_equal_peak_speed"]->cases) {
    const auto& j = c.joints[0];
    EXPECT_NEAR(j.dT_s, std::fabs(j.dtheta_rad) / (300 * kDeg), 1e-12) << c.name;
    EXPECT_NEAR(j.theta0_rad, 90 * kDeg, 1e-12);
  }
  // Fig. 14: Eq. (25) per n; mu_swapped: the Fig. 7 case with mu_s and mu_d exchanged.
  for (const ExperimentCase& c : by["fig14_tail_dof"]->cases) {
    const int n = c.robot.numLinks();
    const SplitCycleParams want = equalPeakSpeedParams(n, 600 * kDeg, 0.25);
    for (const auto& j : c.joints) {
      EXPECT_NEAR(j.dtheta_rad, want.dtheta_rad, 1e-12);
      EXPECT_NEAR(j.dT_s, want.dT_s, 1e-12);
    }
  }
  const ExperimentCase& mu = by["mu_swapped"]->cases[0];
  const ExperimentCase& f7 = by["fig07_loading"]->cases[0];
  EXPECT_DOUBLE_EQ(mu.robot.friction.mu_s, f7.robot.friction.mu_d);
  EXPECT_DOUBLE_EQ(mu.robot.friction.mu_d, f7.robot.friction.mu_s);
  EXPECT_EQ(by["fig10_LF"]->cases[0].kind, CaseKind::kPose);
}

TEST(AxisLabel, UnitsFromNames) {
  EXPECT_EQ(axisLabel("trajectory.theta0_deg"), "θ0 [deg]");
  EXPECT_EQ(axisLabel("quadruped.d_Q2B_m"), "d_Q2B [m]");
  EXPECT_EQ(axisLabel("trajectory.dtheta_deg[2]"), "Δθ [deg] (joint 2)");
  EXPECT_EQ(axisLabel("foo.bar_Nm"), "bar [N m]");
  EXPECT_EQ(leafKey("a.b.c_s"), "c_s");
}

}  // namespace
}  // namespace tailsim

namespace tailsim {
namespace {

// Fig. 9 draws seven curves (d_Q2B) in one panel: no two series may share colour, dash and point.
TEST(FigureStyle, SeriesStylesAreDistinctAndNeverAModelColour) {
  std::set<std::tuple<std::string, int, int>> seen;
  for (size_t i = 0; i < 20; ++i) {
    EXPECT_TRUE(seen.emplace(seriesColor(i), seriesDash(i), seriesPoint(i)).second) << "series " << i;
    EXPECT_NE(seriesColor(i), modelColor("analytic"));
    EXPECT_NE(seriesColor(i), modelColor("mujoco"));
  }
  // the first five are five different colours, solid
  std::set<std::string> first;
  for (size_t i = 0; i < numSeriesColors(); ++i) {
    first.insert(seriesColor(i));
    EXPECT_EQ(seriesDash(i), 1);
  }
  EXPECT_EQ(first.size(), numSeriesColors());
  EXPECT_NE(seriesDash(numSeriesColors()), 1);
  // Fig. 14 (six tails) and a six-case ladder: no colour twice among the curves of one figure.
  EXPECT_GE(numSeriesColors(), 10u);
}

TEST(FigureTitles, VisibleWidthIgnoresMarkup) {
  EXPECT_EQ(gpTextWidth("φ_{net} over θ_0"), std::string("φnet over θ0").size() - 2);  // φ, θ: 2 bytes each
  EXPECT_EQ(gpTextWidth("d\\_Q2B"), 5u);
  EXPECT_EQ(gpTextWidth("φ̇"), 1u);  // combining dot above
}

TEST(FigureTitles, LongTitlesAreWrappedAtSpacesOutsideGroups) {
  const std::string t =
      "Fig. 7 case with μ_s and μ_d swapped (μ_s 0.30, μ_d 0.25) — body yaw φ(t), 1-link tail: analytic vs MuJoCo";
  EXPECT_EQ(wrapGpText(t, 200), t);  // fits: unchanged
  const std::string w = wrapGpText(t, 80);
  // broken after the dash between the figure's name and what it shows
  EXPECT_EQ(w, "Fig. 7 case with μ_s and μ_d swapped (μ_s 0.30, μ_d 0.25) —\nbody yaw φ(t), 1-link tail: analytic vs MuJoCo");
  for (size_t max : {10u, 20u, 35u}) {
    const std::string n = wrapGpText(t, max);
    std::string joined = n;
    std::replace(joined.begin(), joined.end(), '\n', ' ');
    EXPECT_EQ(joined, t) << "only spaces become line breaks";
    std::istringstream lines(n);
    for (std::string l; std::getline(lines, l);)
      if (l.find(' ') != std::string::npos) {  // a single long word may exceed
        EXPECT_LE(gpTextWidth(l), max) << l;
      }
  }
  EXPECT_EQ(wrapGpText("a M_{z, T} b", 3), "a\nM_{z, T}\nb");  // never inside a {group}
  // the quoted title is one gnuplot string expression
  EXPECT_EQ(gpQuote("a\nb's"), "'a'.\"\\n\".'b'.\"'\".'s'");
  EXPECT_EQ(gpTitle("short", 1000), "'short'");
  EXPECT_GT(titleChars(1000, 15), 80u);
  EXPECT_LT(titleChars(1000, 15), 100u);
  EXPECT_EQ(gpFigureName("Fig. 7 case with mu_s and mu_d swapped (mu_s 0.30)", "x"),
            "Fig. 7 case with μ_s and μ_d swapped (μ_s 0.30)");
}

SweepAxis axis(const std::string& key, std::vector<std::string> values) {
  SweepAxis a;
  a.key = key;
  a.values = std::move(values);
  for (const std::string& v : a.values) a.numeric = a.numeric && parseNumber(v).has_value();
  return a;
}

TEST(FigureTitles, PanelTitlesSayWhatTheyCompare) {
  const SweepAxis coupling = axis("analytic.coupling", {"paper", "exact"});
  const SweepAxis friction = axis("effects.friction", {"stiction", "continuous"});
  EXPECT_EQ(gpPanelTitle("analytic", {friction, coupling}), "analytic: stiction vs continuous × paper vs exact coupling");
  EXPECT_EQ(gpPanelTitle("mujoco", {friction, coupling}), "MuJoCo (contact): stiction vs continuous; coupling not used");
  // numeric keys are on the axes: the model's title alone
  EXPECT_EQ(gpPanelTitle("analytic", {axis("quadruped.d_Q2B_m", {"0", "0.025"}), axis("trajectory.theta0_deg", {"0", "15"})}),
            "analytic (stiction)");
}

TEST(HeatMap, LayoutKeepsSmallGridsAndShrinksLargeOnes) {
  const HeatMapLayout f9 = heatMapLayout(7, 7);  // Fig. 9: as before, values in the cells
  EXPECT_EQ(f9.cell_w, 105);
  EXPECT_EQ(f9.cell_h, 82);
  EXPECT_TRUE(f9.values_in_cells);
  EXPECT_EQ(f9.panel_w, 7 * 105 + 420);
  for (auto [nx, ny] : {std::pair<size_t, size_t>{100, 50}, {50, 100}, {1000, 100}, {10000, 10000}}) {
    const HeatMapLayout l = heatMapLayout(nx, ny);
    EXPECT_FALSE(l.values_in_cells) << nx << "x" << ny;
    EXPECT_LE(l.panel_w, 2 * 10000 + 420);
    EXPECT_LT(2 * l.panel_w, 32767) << "two panels side by side within cairo's limit";
    EXPECT_LT(2 * l.panel_h, 32767);
    EXPECT_GE(l.cell_w * l.xtic_every, 80) << "tic labels do not overlap";
    EXPECT_GE(l.cell_h * l.ytic_every, 24);
  }
}

// A 100 x 50 sweep (5,000 cases) and a 10 x 400 sweep (wider than cairo's 32767 px at the old
// 105 px cells: gnuplot failed and `tailsim plot` stopped): each gets its phi_net map, with every
// case in its own cell.
TEST(HeatMap, LargeSweepsGetTheirMap) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_large_" + std::to_string(::getpid()));
  fs::remove_all(root);
  for (auto [ny, nx] : {std::pair<int, int>{50, 100}, {10, 400}}) {
    const std::string name = "grid_" + std::to_string(ny) + "x" + std::to_string(nx);
    std::vector<SynthCase> cs;
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix)
        cs.push_back({{{"trajectory.theta0_deg", -49 + 2 * iy}, {"trajectory.dtheta_deg", -150.5 + 3 * ix}},
                      {{"analytic", 0.01 * (iy * nx + ix)}},
                      {}});
    // cases in reverse order: the grid comes from the values, not from the order of summary.json
    std::reverse(cs.begin(), cs.end());
    writeExperiment(root / name, name, {"trajectory.theta0_deg", "trajectory.dtheta_deg"}, cs, "name: " + name + "\n");
    const ExperimentResults r = loadResults((root / name).string());
    ASSERT_EQ(r.axes.size(), 2u);
    const auto grid = caseGrid(r, r.axes[0], r.axes[1]);
    ASSERT_EQ(grid.size(), size_t(ny));
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix) {
        ASSERT_NE(grid[iy][ix], nullptr);
        ASSERT_NEAR(r.phiNet(*grid[iy][ix], "analytic"), 0.01 * (iy * nx + ix), 1e-9) << iy << " " << ix;
      }
    const std::vector<PlotFile> plots = plotExperiment(r);
    const fs::path map = root / name / "plots" / (name + "_phi_net_map.png");
    ASSERT_TRUE(fs::exists(map)) << name;
    const auto [w, h] = pngSize(map);
    EXPECT_GT(w, 1000u);
    EXPECT_LT(w, 3000u) << "one readable picture";
    EXPECT_LT(h, 2000u);
    // the data file holds every cell with its value
    std::ifstream dat(root / name / "plots" / (name + "_phi_net_map_analytic.dat"));
    std::string line;
    std::getline(dat, line);  // header
    int rows = 0;
    double ix, iy, v;
    while (dat >> ix >> iy >> v) {
      EXPECT_NEAR(v, 0.01 * (iy * nx + ix), 1e-9);
      ++rows;
    }
    EXPECT_EQ(rows, nx * ny);
  }
  fs::remove_all(root);
}

// A figure's script draws it twice (PNG, then SVG): the PNG's commands.
std::string pngCommands(const std::string& gp) { return gp.substr(0, gp.find("set terminal svg")); }

// A synthetic sweep of every combination of `axes` (key -> values), phi_net of each model from f.
void writeGridExperiment(const fs::path& dir, const std::string& name,
                         const std::vector<std::pair<std::string, std::vector<json>>>& axes,
                         const std::vector<std::string>& models,
                         const std::function<double(const std::string&, const std::vector<double>&)>& f) {
  std::vector<SynthCase> cs;
  std::vector<size_t> idx(axes.size(), 0);
  while (true) {
    SynthCase c;
    std::vector<double> x;
    for (size_t k = 0; k < axes.size(); ++k) {
      const json& v = axes[k].second[idx[k]];
      c.sweep[axes[k].first] = v;
      x.push_back(v.is_number() ? v.get<double>() : static_cast<double>(idx[k]));
    }
    for (const std::string& m : models) c.phi[m] = f(m, x);
    cs.push_back(c);
    size_t k = axes.size();
    while (k > 0 && ++idx[k - 1] == axes[k - 1].second.size()) idx[--k] = 0;
    if (k == 0) break;
  }
  std::vector<std::string> keys;
  for (const auto& a : axes) keys.push_back(a.first);
  writeExperiment(dir, name, keys, cs, "name: " + name + "\n");
}

// Colour by meaning: a phi_net map whose values all have one sign is drawn with the sequential
// map over their range, not the diverging one (Fig. 12 used half of a blue-orange scale); values of
// both signs get the diverging map centred on zero; two models get a difference panel, diverging.
TEST(HeatMap, SequentialForOneSignDivergingForBothAndForTheDifference) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_colours_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::vector<std::pair<std::string, std::vector<json>>> axes = {
      {"trajectory.dtheta_deg", {-60, -120, -180}}, {"trajectory.dT_s", {0.2, 0.4, 0.6}}};
  writeGridExperiment(root / "positive", "positive", axes, {"analytic", "mujoco"},
                      [](const std::string& m, const std::vector<double>& x) {
                        return 1.0 + x[1] - 0.01 * x[0] + (m == "mujoco" ? 0.5 : 0.0);
                      });
  writeGridExperiment(root / "both", "both", axes, {"analytic"},
                      [](const std::string&, const std::vector<double>& x) { return x[1] - 0.4; });
  plotExperiment(loadResults((root / "positive").string()));
  plotExperiment(loadResults((root / "both").string()));
  const std::string pos = pngCommands(readText(root / "positive" / "plots" / "positive_phi_net_map.gp"));
  const std::string both = pngCommands(readText(root / "both" / "plots" / "both_phi_net_map.gp"));
  const std::string seq = sequentialPalette(), div = divergingPalette();
  // positive: two model panels on the sequential map, then the difference on the diverging one
  ASSERT_NE(pos.find(seq), std::string::npos) << pos;
  const size_t first_div = pos.find(div);
  ASSERT_NE(first_div, std::string::npos) << "no difference panel:\n" << pos;
  EXPECT_GT(first_div, pos.rfind(seq));
  EXPECT_NE(pos.find("positive_phi_net_map_difference.dat"), std::string::npos);
  EXPECT_TRUE(fs::exists(root / "positive" / "plots" / "positive_phi_net_map_difference.dat"));
  // the models' colour range is the values' range, not +-max centred on zero
  EXPECT_EQ(pos.find("set cbrange [-"), pos.rfind("set cbrange [-")) << "only the difference is centred on zero";
  EXPECT_NE(both.find(div), std::string::npos);
  EXPECT_EQ(both.find(seq), std::string::npos);
  fs::remove_all(root);
}

// Three models (analytic, per-foot, MuJoCo): a difference panel for each model after the first,
// that model minus the first, with the values of the results (a 3-model sweep had none).
TEST(HeatMap, EveryModelAfterTheFirstGetsADifferencePanel) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_diff3_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::vector<std::pair<std::string, std::vector<json>>> axes = {
      {"trajectory.dtheta_deg", {-60, -120, -180}}, {"trajectory.dT_s", {0.2, 0.4, 0.6, 0.8}}};
  auto phi = [](const std::string& m, const std::vector<double>& x) {
    return 1.0 + x[1] - 0.01 * x[0] + (m == "mujoco" ? 0.5 : m == "perfoot" ? -0.25 * x[1] : 0.0);
  };
  writeGridExperiment(root / "three", "three", axes, {"analytic", "perfoot", "mujoco"}, phi);
  plotExperiment(loadResults((root / "three").string()));
  const std::string gp = pngCommands(readText(root / "three" / "plots" / "three_phi_net_map.gp"));
  EXPECT_NE(gp.find("set multiplot layout 3,2"), std::string::npos) << "each model beside its difference:\n" << gp;
  EXPECT_NE(gp.find("set multiplot next"), std::string::npos) << "the first model has no difference beside it";
  for (const char* m : {"perfoot", "mujoco"}) {
    const fs::path dat = root / "three" / "plots" / (std::string("three_phi_net_map_difference_") + m + ".dat");
    ASSERT_TRUE(fs::exists(dat)) << dat;
    EXPECT_NE(gp.find(dat.filename().string()), std::string::npos);
    std::ifstream in(dat);
    std::string header;
    std::getline(in, header);
    double ix, iy, v;
    int cells = 0;
    while (in >> ix >> iy >> v) {
      const std::vector<double> x = {axes[0].second[size_t(iy)].get<double>(), axes[1].second[size_t(ix)].get<double>()};
      EXPECT_NEAR(v, phi(m, x) - phi("analytic", x), 1e-9) << m << " " << ix << " " << iy;
      ++cells;
    }
    EXPECT_EQ(cells, 12);
  }
  fs::remove_all(root);
}

// One numeric key, three models: the legend is outside the plot (inside, at top left, it hid the
// curves where phi_net is largest) and each model has its own marker (per-foot and MuJoCo shared one).
TEST(OneKey, LegendOutsideThePlotAndAMarkerPerModel) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_onekey_" + std::to_string(::getpid()));
  fs::remove_all(root);
  writeGridExperiment(root / "one", "one", {{"trajectory.dtheta_deg", {-120, -100, -80, -60}}},
                      {"analytic", "perfoot", "mujoco"},
                      [](const std::string&, const std::vector<double>& x) { return -0.1 * x[0]; });
  plotExperiment(loadResults((root / "one").string()));
  const std::string gp = pngCommands(readText(root / "one" / "plots" / "one_phi_net.gp"));
  const size_t plot = gp.find("\nplot ");
  ASSERT_NE(plot, std::string::npos) << gp;
  const size_t key = gp.rfind("set key", plot);
  ASSERT_NE(key, std::string::npos);
  const std::string key_line = gp.substr(key, gp.find('\n', key) - key);
  EXPECT_TRUE(key_line.find("below") != std::string::npos || key_line.find("outside") != std::string::npos) << key_line;
  std::set<std::string> points;
  std::smatch m;
  for (auto it = gp.cbegin() + plot; std::regex_search(it, gp.cend(), m, std::regex(R"( pt (\d+))")); it = m.suffix().first)
    points.insert(m[1]);
  EXPECT_EQ(points.size(), 3u) << gp.substr(plot);
  fs::remove_all(root);
}

// phi(t) for each value of one key: a curve that lies on an earlier one is dashed, so both show (a
// 1-link and a 2-link tail that did not turn the body drew one line, the 1-link one hidden).
TEST(OneKey, ACurveOnAnEarlierOneIsDashed) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_phit_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const SplitCycleParams p{0.0, -90 * kDeg, 0.25, 0.25, 0.0};
  std::vector<SynthCase> cs;
  for (auto [dtheta, phi] : {std::pair<int, double>{-40, 0.0}, {-60, 0.0}, {-80, 3.0}, {-100, 6.0}})
    cs.push_back({{{"trajectory.dtheta_deg", dtheta}}, {{"analytic", phi}}, {{"analytic", simCsv({p}, phi)}}});
  writeExperiment(root / "phit", "phit", {"trajectory.dtheta_deg"}, cs, "name: phit\n");
  plotExperiment(loadResults((root / "phit").string()));
  const std::string gp = pngCommands(readText(root / "phit" / "plots" / "phit_phi_t.gp"));
  std::vector<std::string> dashes;
  std::smatch m;
  for (auto it = gp.cbegin(); std::regex_search(it, gp.cend(), m, std::regex(R"(with lines lw 2 dt (\S+))")); it = m.suffix().first)
    dashes.push_back(m[1]);
  ASSERT_EQ(dashes.size(), 4u) << gp;
  std::sort(dashes.begin(), dashes.end());
  EXPECT_EQ(std::count(dashes.begin(), dashes.end(), "1"), 3) << gp;
  EXPECT_EQ(std::count(dashes.begin(), dashes.end(), "(12,9)"), 1) << "the second zero curve, dashed:\n" << gp;
  fs::remove_all(root);
}

// A model whose values span far more than another's (MuJoCo's spikes) does not squash the other's
// curves: the phi_net curves get one y range per panel when the ranges differ more than threefold,
// one shared range otherwise.
TEST(Lines, ModelPanelsShareAScaleUnlessTheirRangesAreFarApart) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_lines_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::vector<std::pair<std::string, std::vector<json>>> axes = {
      {"trajectory.dtheta_deg", {-60, -120, -180}}, {"trajectory.dT_s", {0.2, 0.4, 0.6}}};
  writeGridExperiment(root / "apart", "apart", axes, {"analytic", "mujoco"},
                      [](const std::string& m, const std::vector<double>& x) {
                        return (m == "mujoco" ? -250.0 : 1.0) * x[1] - 0.01 * x[0];
                      });
  writeGridExperiment(root / "close", "close", axes, {"analytic", "mujoco"},
                      [](const std::string& m, const std::vector<double>& x) {
                        return (m == "mujoco" ? 1.5 : 1.0) * x[1] - 0.01 * x[0];
                      });
  for (const char* exp : {"apart", "close"}) plotExperiment(loadResults((root / exp).string()));
  auto yranges = [&](const char* exp) {
    const std::string gp = pngCommands(readText(root / exp / "plots" / (std::string(exp) + "_phi_net_lines.gp")));
    std::set<std::string> out;
    std::smatch m;
    for (auto it = gp.cbegin(); std::regex_search(it, gp.cend(), m, std::regex(R"(set yrange \[[^\]]*\])")); it = m.suffix().first)
      out.insert(m.str());
    return out;
  };
  EXPECT_EQ(yranges("apart").size(), 2u) << "one y range per model panel";
  EXPECT_EQ(yranges("close").size(), 1u) << "one shared y range";
  // the model panels are stacked: the figure fits figures.html's 1100 px column without shrinking
  // its text to a third (side by side, three models drew 3300 x 720 px)
  const auto [w, h] = pngSize(root / "apart" / "plots" / "apart_phi_net_lines.png");
  EXPECT_LE(w, 1200u);
  EXPECT_GT(h, w / 2) << w << " x " << h;
  fs::remove_all(root);
}

// Three or more swept keys: small multiples per model with the keys on the axes, in panel titles
// and in the legend, never a case index (the 198-case sweep drew phi_net over "case index").
TEST(Facets, ThreeAndFourKeysAreDrawnAsSmallMultiples) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_facets_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::vector<std::pair<std::string, std::vector<json>>> three = {
      {"trajectory.dtheta_deg", {-60, -120, -180}},
      {"trajectory.dT_s", {0.15, 0.2, 0.25, 0.3, 0.35, 0.4}},
      {"trajectory.w_ss", {0.1, 0.25, 0.5}}};
  auto f = [](const std::string& m, const std::vector<double>& x) {
    return -0.05 * x[0] * x[1] + x[2] + (m == "mujoco" ? 1.0 : 0.0);
  };
  writeGridExperiment(root / "three", "three", three, {"analytic", "mujoco"}, f);
  auto four = three;
  four.push_back({"effects.friction", {"stiction", "continuous"}});
  writeGridExperiment(root / "four", "four", four, {"analytic"}, f);

  const FacetKeys fk = facetKeys(loadResults((root / "three").string()).axes);
  const ExperimentResults r3 = loadResults((root / "three").string());
  EXPECT_EQ(r3.axes[fk.x].key, "trajectory.dT_s");  // the numeric key with the most values
  ASSERT_EQ(fk.facets.size(), 1u);
  for (const char* exp : {"three", "four"}) {
    const ExperimentResults r = loadResults((root / exp).string());
    const std::vector<PlotFile> plots = plotExperiment(r);
    ASSERT_EQ(plots.size(), r.models.size()) << exp << ": one figure per model";
    for (const std::string& m : r.models) {
      const fs::path gp = root / exp / "plots" / (std::string(exp) + "_phi_net_facets_" + m + ".gp");
      ASSERT_TRUE(fs::exists(gp)) << gp;
      const std::string text = readText(gp);
      EXPECT_EQ(text.find("case"), std::string::npos) << text;
      EXPECT_NE(text.find("set xlabel 'ΔT [s]'"), std::string::npos) << text;
      EXPECT_NE(text.find("set ylabel 'φ_{net} [deg]'"), std::string::npos);
    }
  }
  // three keys: curves per Δθ (the first key with the fewest values), panels per w_ss
  const std::string three_gp = readText(root / "three" / "plots" / "three_phi_net_facets_mujoco.gp");
  EXPECT_NE(three_gp.find("title 'Δθ'"), std::string::npos) << "the legend names the series key";
  EXPECT_NE(three_gp.find("set title 'w_{ss} = 0.25'"), std::string::npos) << three_gp;
  // four keys: curves per friction law (2 values), panels Δθ x w_ss, 3 x 3
  const std::string four_gp = pngCommands(readText(root / "four" / "plots" / "four_phi_net_facets_analytic.gp"));
  size_t panels = 0;
  for (size_t p = four_gp.find("\nplot "); p != std::string::npos; p = four_gp.find("\nplot ", p + 1)) ++panels;
  EXPECT_EQ(panels, 9u);
  EXPECT_NE(four_gp.find("title 'friction law'"), std::string::npos) << four_gp;
  EXPECT_NE(four_gp.find("title 'continuous'"), std::string::npos) << four_gp;
  fs::remove_all(root);
}

// What any experiment's results say (figures.html, report.md), and no paper claims for an
// experiment that is not a paper figure.
TEST(SweepSummary, BestTrendsDifferencesAndWarningsForAnyExperiment) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_summary_" + std::to_string(::getpid()));
  fs::remove_all(root);
  writeGridExperiment(root / "mine", "mine",
                      {{"trajectory.dT_s", {0.2, 0.4, 0.6}}, {"trajectory.w_ss", {0.25, 0.5}}},
                      {"analytic", "mujoco"}, [](const std::string& m, const std::vector<double>& x) {
                        return 10 * x[0] + (m == "mujoco" ? 2.0 * x[1] : 0.0);
                      });
  ExperimentResults r = loadResults((root / "mine").string());
  EXPECT_FALSE(isPaperFigure(r));
  const SweepSummary s = summarizeSweep(r);
  ASSERT_EQ(s.best.size(), 2u);
  EXPECT_NE(s.best[0].find("largest |φ_net| +6.00° at ΔT = 0.6 s, w_ss = 0.25"), std::string::npos) << s.best[0];
  bool rises = false;
  for (const std::string& t : s.trends) rises = rises || t.find("rises with ΔT, from +2.") != std::string::npos;
  EXPECT_TRUE(rises) << s.trends[0];
  ASSERT_EQ(s.disagree.size(), 1u);
  EXPECT_NE(s.disagree[0].find("largest difference +1.00°"), std::string::npos) << s.disagree[0];
  EXPECT_NE(s.disagree[0].find("(No uncertainty is recorded for these results.)"), std::string::npos) << s.disagree[0];
  {
    // The largest turn either way (a turn of -6 deg is larger than one of +2), and the runs' own
    // uncertainties beside the largest difference where they have them.
    ExperimentResults neg = r;
    for (CaseRecord& c : neg.cases) {
      c.runs["analytic"].phi_net_deg = -c.runs["analytic"].phi_net_deg;
      c.runs["mujoco"].phi_net_uncertainty_deg = 0.25;
    }
    const SweepSummary n = summarizeSweep(neg);
    EXPECT_NE(n.best[0].find("largest |φ_net| -6.00° at ΔT = 0.6 s"), std::string::npos) << n.best[0];
    EXPECT_NE(n.disagree[0].find("uncertainty there ±0.250°)"), std::string::npos) << n.disagree[0];
    EXPECT_EQ(n.disagree[0].find("No uncertainty"), std::string::npos) << n.disagree[0];
  }
  const std::string md = reportMarkdown({r}, computeFindings({r}), {}, root.string());
  EXPECT_EQ(md.find("Paper claims"), std::string::npos);
  EXPECT_EQ(md.find("Rone"), std::string::npos);
  EXPECT_NE(md.find("Trend along each swept key"), std::string::npos);
  const std::string html = figureSheetHtml(root.string(), {r}, {});
  EXPECT_EQ(html.find("Rone"), std::string::npos);
  EXPECT_NE(html.find("Where the models differ"), std::string::npos);
  fs::remove_all(root);
}

// report.md and figures.html say what each model that ran is, and only those (a per-foot sweep was
// told "Analytic = ...; MuJoCo = ..."); the swept keys and the models are listed with separators.
TEST(SweepSummary, TheModelsThatRanAreNamedAndListed) {
  const fs::path root = fs::path(TAILSIM_BINARY_DIR) / ("test_plotting_glossary_" + std::to_string(::getpid()));
  fs::remove_all(root);
  writeGridExperiment(root / "mine", "mine", {{"trajectory.dT_s", {0.2, 0.4}}, {"trajectory.w_ss", {0.25, 0.5}}},
                      {"analytic", "perfoot"},
                      [](const std::string& m, const std::vector<double>& x) { return x[0] + (m == "perfoot"); });
  const ExperimentResults r = loadResults((root / "mine").string());
  const std::string md = reportMarkdown({r}, computeFindings({r}), {}, root.string());
  const std::string html = figureSheetHtml(root.string(), {r}, {});
  for (const std::string* t : {&md, &html}) {
    EXPECT_NE(t->find("per-foot = Coulomb friction at each foot"), std::string::npos) << *t;
    EXPECT_EQ(t->find("MuJoCo = the contact model"), std::string::npos) << "no MuJoCo run";
  }
  EXPECT_NE(md.find("dT_s (2 values, 0.2 .. 0.4); w_ss (2 values"), std::string::npos) << md;
  EXPECT_NE(md.find(" s wall time in the simulations); perfoot (4 ok"), std::string::npos) << md;
  fs::remove_all(root);
}

}  // namespace
}  // namespace tailsim
