// Tipping over: the MuJoCo model fails a run whose robot tips over, the two
// models agree on which cases tip, and a failed run has phi_net_deg = null in summary.json and
// result.json, which every reader (report, plots, findings, the CLI's case table) shows as failed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "analytic_test_util.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "models/mujoco/mujoco_simulation.h"
#include "random_robots.h"
#include "plotting/findings.h"
#include "plotting/plots.h"
#include "plotting/report.h"
#include "plotting/result_folder.h"
#include "common/atomic_file.h"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace tailsim;
using namespace tailsim::testing;

namespace {

// The paper robot with one custom tail link of this mass and length (COM at mid-length).
RobotParams heavyTail(double mass_kg, double length_m, double izz_kgm2, double d_Q2B_m) {
  RobotParams r = paperRobot(1, d_Q2B_m);
  r.tail[0].mass_kg = mass_kg;
  r.tail[0].length_m = length_m;
  r.tail[0].com_offset_m = 0.5 * length_m;
  r.tail[0].izz_kgm2 = izz_kgm2;
  return r;
}

struct TipCase {
  const char* what;
  RobotParams robot;
  TailTrajectory trajectory;
  bool tips;  // the expected answer of both models
};

// Cases on both sides of the tipping boundary, each with a clear margin (docs/mujoco-model.md
// "Tipping over" lists the measured sweeps they come from). Support rectangle: +-0.15 m x
// +-0.13 m around the foot centroid.
std::vector<TipCase> boundaryCases() {
  // Static: a straight tail behind the body (d_Q2B = 0.3 m, 0.3 m long) with a small wag; the
  // system COM crosses the rear edge at a tail mass of ~4.9 kg.
  const TailTrajectory wag = sameMove(1, 0, -5, 0.25, 0.25);
  // Dynamic: a 0.6 m tail at the COM (d_Q2B = 0) swings 90 deg to the side; the COM crosses the
  // side edge at ~6.5 kg during the swing. Slow (dT = 1 s) and fast (dT = 0.25 s) swings.
  const TailTrajectory slow = sameMove(1, 0, 90, 1.0, 0.25), fast = sameMove(1, 0, 90, 0.25, 0.25);
  return {{"static, tail 3 kg: COM 48 mm inside the rear edge", heavyTail(3, 0.3, 0.02, 0.3), wag, false},
          {"static, tail 8 kg: COM 53 mm outside the rear edge", heavyTail(8, 0.3, 0.02, 0.3), wag, true},
          {"slow side swing, tail 5 kg: COM stays 18 mm inside", heavyTail(5, 0.6, 0.1, 0.0), slow, false},
          {"slow side swing, tail 8 kg: COM ends 16 mm outside", heavyTail(8, 0.6, 0.1, 0.0), slow, true},
          {"fast side swing, tail 4 kg: COM stays 34 mm inside", heavyTail(4, 0.6, 0.1, 0.0), fast, false},
          {"fast side swing, tail 8 kg: COM ends 16 mm outside", heavyTail(8, 0.6, 0.1, 0.0), fast, true}};
}

TEST(Tipping, BothModelsAgreeWhichCasesTip) {
  for (const TipCase& c : boundaryCases()) {
    SCOPED_TRACE(c.what);
    const RunResult a = simulateAnalytic(c.robot, c.trajectory, {}, {}, {});
    const RunResult m = simulateMujoco(c.robot, c.trajectory, {}, {}, {});
    EXPECT_EQ(a.summary.ok, !c.tips) << a.summary.error;
    EXPECT_EQ(m.summary.ok, !c.tips) << m.summary.error;
    const double tilt = m.summary.extra.at("max_tilt_deg");
    if (c.tips) {
      EXPECT_NE(a.summary.error.find("tips over"), std::string::npos) << a.summary.error;
      EXPECT_NE(m.summary.error.find("robot fell over at t = "), std::string::npos) << m.summary.error;
      EXPECT_NE(m.summary.error.find("(limit max_tilt_deg = 5 deg)"), std::string::npos) << m.summary.error;
      EXPECT_NE(m.summary.error.find("analytic model reports this as tipping"), std::string::npos);
      EXPECT_TRUE(std::isnan(m.summary.phi_net_deg));
      EXPECT_GE(tilt, 5.0);
      // The run stops where the robot fell: the rows end there.
      ASSERT_GT(m.series.numRows(), 0u);
      EXPECT_LT(m.series.values("t_s").back(), c.trajectory.endTime() + OutputSettings{}.settle_s);
    } else {
      EXPECT_LT(tilt, 1.0);  // standing: far below the 5 deg limit
      EXPECT_TRUE(std::isfinite(m.summary.phi_net_deg));
    }
  }
}

// The worst paper case for contact chatter (Fig. 12, dtheta = -180 deg, dT = 0.15 s: the largest
// tilt, height change and all-feet-off interval of all paper cases) stands with a wide margin.
TEST(Tipping, PaperWorstCaseStandsWithMargin) {
  const RunResult m = simulateMujoco(paperRobot(1), sameMove(1, 90, -180, 0.15, 0.25), {}, {}, {});
  ASSERT_TRUE(m.summary.ok) << m.summary.error;
  const MujocoSettings s;
  EXPECT_LT(m.summary.extra.at("max_tilt_deg"), 0.1 * s.max_tilt_deg);
  EXPECT_GT(m.summary.extra.at("max_tilt_deg"), 0.0);
  EXPECT_LT(m.summary.extra.at("max_height_change_m"), 0.005);
  // The feet do leave the ground all at once (MuJoCo's soft contact chatters) but briefly.
  EXPECT_GT(m.summary.extra.at("longest_all_feet_off_s"), 0.0);
  EXPECT_LT(m.summary.extra.at("longest_all_feet_off_s"), 0.5 * s.max_all_feet_off_s);
}

TEST(Tipping, LimitsAreSettingsAndZeroTurnsACheckOff) {
  const RobotParams r = heavyTail(8, 0.3, 0.02, 0.3);
  const TailTrajectory wag = sameMove(1, 0, -5, 0.25, 0.25);
  MujocoSettings off;
  off.max_tilt_deg = 0;
  off.max_all_feet_off_s = 0;
  const RunResult free_fall = simulateMujoco(r, wag, off, {}, {});
  EXPECT_TRUE(free_fall.summary.ok) << free_fall.summary.error;
  EXPECT_GT(free_fall.summary.extra.at("max_tilt_deg"), 90.0);  // it fell all the same, and says so

  // All feet off: a limit shorter than the chatter of a standing robot trips that check, with its
  // own message.
  MujocoSettings strict;
  strict.max_all_feet_off_s = 0.001;
  const RunResult chatter = simulateMujoco(paperRobot(1), sameMove(1, 90, -180, 0.15, 0.25), strict, {}, {});
  EXPECT_FALSE(chatter.summary.ok);
  EXPECT_NE(chatter.summary.error.find("no foot has touched the ground for"), std::string::npos)
      << chatter.summary.error;
  EXPECT_NE(chatter.summary.error.find("max_all_feet_off_s = 0.001 s"), std::string::npos) << chatter.summary.error;

  // Without ground contact nothing stands, so nothing can tip: no check.
  Effects no_ground;
  no_ground.ground_contact = false;
  EXPECT_TRUE(simulateMujoco(r, wag, {}, no_ground, {}).summary.ok);
}

// A diverging integration (explicit Euler with a timestep too large for the servo gains) throws
// the body over a few steps before MuJoCo warns: the run names the timestep, not a fall.
TEST(Tipping, DivergingIntegrationIsNotReportedAsAFall) {
  MujocoSettings s;
  s.integrator = MujocoIntegrator::kEuler;
  s.timestep_s = 5e-4;
  s.kp = 76360;
  const RunResult r = simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), s, {}, {});
  ASSERT_FALSE(r.summary.ok);
  EXPECT_NE(r.summary.error.find("timestep_s=0.0005 too large"), std::string::npos) << r.summary.error;
  EXPECT_EQ(r.summary.error.find("fell over"), std::string::npos) << r.summary.error;
}

TEST(Tipping, StaticTipIsCaughtWhileSettling) {
  // COM 0.1 m behind the rear edge: the robot falls during the settling pre-roll.
  const RunResult m = simulateMujoco(heavyTail(30, 0.3, 0.02, 0.3), sameMove(1, 0, -5, 0.25, 0.25), {}, {}, {});
  EXPECT_FALSE(m.summary.ok);
  EXPECT_NE(m.summary.error.find("while settling"), std::string::npos) << m.summary.error;
  EXPECT_NE(m.summary.error.find("robot fell over at t = -"), std::string::npos) << m.summary.error;
  EXPECT_EQ(m.series.numRows(), 0u);
  EXPECT_TRUE(m.summary.extra.count("max_tilt_deg"));
}

// A random robot's MuJoCo settings at the defaults (its COM height as the body's), and an output
// without time series.
MujocoSettings defaultsFor(const RandomRobotCase& c) {
  MujocoSettings s;
  s.body_height_m = c.robot.quadruped.com_height_m;
  return s;
}

OutputSettings noSeries() {
  OutputSettings o;
  o.time_series = TimeSeriesOutput::kNone;
  return o;
}

// A robot the converged reference sees fall is never a plain turn at the defaults. Case 11 of the
// tippy corpus, seed 31 (tests/bench_trust.cc --corpus tippy --falls; 44 kg, 0.27 m x 0.09 m,
// COM 0.15 m high, a 13.8 kg 3-link tail flicked 49 deg in 0.13 s): the reference (timestep / 8,
// noslip 3) tilts past max_tilt_deg, the default run rocks to 1.66 deg and its check run agrees
// with it within 0.3 deg, so only the tilt can tell.
TEST(Tipping, AFallInTheReferenceIsNotAPlainTurnAtTheDefaults) {
  const RandomRobotCase c = randomRobotCase(31, 11, RandomCorpus::kTippy);
  const OutputSettings o = noSeries();
  const MujocoSettings s = defaultsFor(c);
  MujocoSettings ref = s;
  ref.timestep_s /= 8.0;
  ref.servo_wn_dt /= 8.0;
  ref.noslip_iterations = 3;
  ref.uncertainty = false;
  const RunResult f = simulateMujoco(c.robot, c.trajectory, ref, Effects{}, o);
  ASSERT_FALSE(f.summary.ok) << describe(c);
  EXPECT_NE(f.summary.error.find("robot fell over"), std::string::npos) << f.summary.error;

  const RunResult d = simulateMujoco(c.robot, c.trajectory, s, Effects{}, o);
  ASSERT_TRUE(d.summary.ok) << d.summary.error;
  const double tilt = d.summary.extra.at("max_tilt_deg");
  EXPECT_GT(tilt, 1.5);
  EXPECT_LT(tilt, 0.5 * s.max_tilt_deg);  // below the near-fall share this test was found with
  bool near_fall = false;
  for (const std::string& w : d.summary.warnings)
    near_fall |= w.rfind(kUncertainWarning, 0) == 0 && w.find("nearly fell") != std::string::npos;
  EXPECT_TRUE(near_fall) << "tilt " << tilt << " deg, phi_net " << d.summary.phi_net_deg << " deg, "
                         << d.summary.warnings.size() << " warnings";
}

// The check run at twice the step runs its own pre-roll: a robot at the edge of standing meets the
// coarser step from the start. Tippy seed 33, case 38 falls in the converged reference but stands
// at the defaults, tilted 0.42 deg only (no tilt threshold can tell it from a robot that stands);
// its check run falls, and that failure is what marks the result uncertain. A check run started
// from the run's own pre-roll stood and left a plain turn of +48 deg.
TEST(Tipping, ACheckRunThatFallsMarksTheResultUncertain) {
  const RandomRobotCase c = randomRobotCase(33, 38, RandomCorpus::kTippy);
  const MujocoSettings s = defaultsFor(c);
  const RunResult d = simulateMujoco(c.robot, c.trajectory, s, Effects{}, noSeries());
  ASSERT_TRUE(d.summary.ok) << d.summary.error;
  EXPECT_LT(d.summary.extra.at("max_tilt_deg"), 0.25 * s.max_tilt_deg) << describe(c);
  EXPECT_TRUE(std::isnan(d.summary.extra.at("phi_net_uncertainty_deg")));
  bool failed_check = false;
  for (const std::string& w : d.summary.warnings)
    failed_check |= w.rfind(kUncertainWarning, 0) == 0 && w.find("check run") != std::string::npos;
  EXPECT_TRUE(failed_check) << "phi_net " << d.summary.phi_net_deg << " deg, " << d.summary.warnings.size()
                            << " warnings";
}

fs::path writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p;
}

TEST(Tipping, SettingsLoadFromYamlWithUnitsChecked) {
  const fs::path dir = fs::path(TAILSIM_BINARY_DIR) / "test_tipping_yaml";
  const std::string head = "name: t\nrobot: " + std::string(TAILSIM_SOURCE_DIR) +
                           "/configs/robots/paper_quadruped.yaml\nmodels: [mujoco]\n"
                           "trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n";
  const Experiment e =
      loadExperiment(writeFile(dir / "ok.yaml", head + "mujoco: {max_tilt_deg: 12.5, max_all_feet_off_s: 0}\n").string());
  EXPECT_DOUBLE_EQ(e.cases.at(0).mujoco.max_tilt_deg, 12.5);
  EXPECT_DOUBLE_EQ(e.cases.at(0).mujoco.max_all_feet_off_s, 0.0);
  try {
    loadExperiment(writeFile(dir / "bad.yaml", head + "mujoco: {max_tilt_deg: -1}\n").string());
    ADD_FAILURE() << "negative max_tilt_deg accepted";
  } catch (const std::exception& ex) {
    const std::string msg = ex.what();
    EXPECT_NE(msg.find("bad.yaml:5:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("max_tilt_deg"), std::string::npos) << msg;
  }
}

// A result folder with a tipped case: null in the JSON files, "failed" in every reader.
TEST(Tipping, FailedRunIsNullInJsonAndFailedInEveryReader) {
  const fs::path dir = fs::path(TAILSIM_BINARY_DIR) / "test_tipping_run";
  fs::remove_all(dir);
  const fs::path yaml =
      writeFile(dir / "tip.yaml", "name: tip\nrobot: " + std::string(TAILSIM_SOURCE_DIR) +
                                      "/configs/robots/paper_quadruped.yaml\n"
                                      "tail: {custom: [{mass_kg: {sweep: [3, 8]}, izz_kgm2: 0.02, length_m: 0.3}]}\n"
                                      "quadruped: {d_Q2B_m: 0.3}\n"
                                      "trajectory: {theta0_deg: 0, dtheta_deg: -5, dT_s: 0.25, w_ss: 0.25}\n"
                                      "models: [analytic, mujoco]\n");
  const fs::path out = dir / "out";
  // Through the CLI: its case table says FAILED with the reason.
  const auto console = [&](const char* flags) {
    const std::string cmd = std::string(TAILSIM_BINARY_DIR) + "/tailsim run " + yaml.string() + " --out " +
                            out.string() + " " + flags + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string text;
    if (p == nullptr) return text;
    char buf[512];
    while (fgets(buf, sizeof buf, p)) text += buf;
    pclose(p);
    return text;
  };
  std::string text = console("");
  EXPECT_NE(text.find("mujoco: FAILED (robot fell over at t = "), std::string::npos) << text;
  EXPECT_NE(text.find("analytic: FAILED ("), std::string::npos) << text;
  EXPECT_NE(text.find("mujoco: phi_net "), std::string::npos) << text;  // the 3 kg case stands
  // --quiet (the same folder, resumed): the failed runs are errors, so they are still printed; the
  // standing case's result is not.
  text = console("--quiet");
  EXPECT_NE(text.find(": mujoco: FAILED (robot fell over at t = "), std::string::npos) << text;
  EXPECT_NE(text.find(": analytic: FAILED ("), std::string::npos) << text;
  EXPECT_EQ(text.find("phi_net "), std::string::npos) << text;

  std::ifstream in(out / "summary.json");
  const json s = json::parse(in);
  ASSERT_EQ(s["cases"].size(), 2u);
  const json& tipped = s["cases"][1];
  ASSERT_EQ(tipped["name"], "mass_kg=8");
  for (const char* m : {"analytic", "mujoco"}) {
    EXPECT_EQ(tipped["runs"][m]["ok"], false) << m;
    EXPECT_TRUE(tipped["runs"][m]["phi_net_deg"].is_null()) << m << ": " << tipped["runs"][m]["phi_net_deg"];
    EXPECT_TRUE(s["cases"][0]["runs"][m]["phi_net_deg"].is_number()) << m;
  }
  EXPECT_GE(tipped["runs"]["mujoco"]["extra"]["max_tilt_deg"].get<double>(), 5.0);
  std::ifstream rin(out / "cases" / "mass_kg=8" / "result.json");
  const json r = json::parse(rin);
  EXPECT_TRUE(r["runs"]["mujoco"]["phi_net_deg"].is_null());
  EXPECT_TRUE(r["runs"]["analytic"]["phi_net_deg"].is_null());

  // Readers: the result folder, the report, the plots.
  const ExperimentResults res = loadResults(out.string());
  ASSERT_EQ(res.cases.size(), 2u);
  EXPECT_FALSE(res.cases[1].runs.at("mujoco").ok);
  EXPECT_TRUE(std::isnan(res.cases[1].runs.at("mujoco").phi_net_deg));
  EXPECT_TRUE(std::isnan(res.phiNet(res.cases[1], "mujoco")));
  EXPECT_TRUE(std::isfinite(res.phiNet(res.cases[0], "mujoco")));
  const std::vector<PlotFile> plots = plotResults(out.string());
  EXPECT_FALSE(plots.empty());
  const std::string md = reportMarkdown({res}, computeFindings({res}), plots, out.string());
  EXPECT_NE(md.find("- failed: mass_kg=8 / mujoco: robot fell over at t = "), std::string::npos) << md;
  EXPECT_NE(md.find("mujoco (1 ok, 1 FAILED"), std::string::npos) << md;
  std::ifstream dat(out / "plots" / "tip_phi_net.dat");
  ASSERT_TRUE(dat) << "no phi_net plot data";
  std::string dtext((std::istreambuf_iterator<char>(dat)), std::istreambuf_iterator<char>());
  EXPECT_NE(dtext.find("NaN"), std::string::npos) << dtext;  // the failed runs are gaps, not 0
}

// Findings read a null phi_net as a failed run: the trend is "incomplete", never a number.
TEST(Tipping, FindingsCallAFailedRunIncomplete) {
  const fs::path dir = fs::path(TAILSIM_BINARY_DIR) / "test_tipping_findings" / "fig11_wss";
  fs::remove_all(dir.parent_path());
  json s = {{"experiment", "fig11_wss"}, {"kind", "simulate"}, {"swept_keys", {"trajectory.w_ss"}}, {"cases", json::array()}};
  const double phis[] = {10.0, 8.0, 6.0};
  for (int i = 0; i < 3; ++i) {
    const std::string w = "0." + std::to_string(i + 1);
    json mj = {{"ok", i != 1}, {"phi_net_deg", i == 1 ? json(nullptr) : json(phis[i])}};
    if (i == 1) mj["error"] = "robot fell over at t = 0.1 s";
    s["cases"].push_back({{"name", "w_ss=" + w},
                          {"dir", "w_ss=" + w},
                          {"sweep", {{"trajectory.w_ss", w}}},
                          {"runs", {{"analytic", {{"ok", true}, {"phi_net_deg", phis[i]}}}, {"mujoco", mj}}}});
  }
  fs::create_directories(dir);
  writeFileAtomic((dir / "summary.json").string(), s.dump());
  const std::vector<Finding> f = computeFindings({loadResults(dir.string())});
  const Finding* wss = nullptr;
  for (const Finding& x : f)
    if (x.id == "fig11_wss_falls") wss = &x;
  ASSERT_NE(wss, nullptr);
  ASSERT_NE(wss->verdictFor("analytic"), nullptr);
  EXPECT_EQ(wss->verdictFor("analytic")->verdict, Verdict::kYes);
  ASSERT_NE(wss->verdictFor("mujoco"), nullptr);
  EXPECT_EQ(wss->verdictFor("mujoco")->verdict, Verdict::kNo);
  EXPECT_NE(wss->verdictFor("mujoco")->detail.find("incomplete (failed or missing runs)"), std::string::npos)
      << wss->verdictFor("mujoco")->detail;
  EXPECT_NE(wss->verdictFor("mujoco")->detail.find("NaN"), std::string::npos);
}

}  // namespace
