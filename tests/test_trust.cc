// An answer a user can trust: every MuJoCo run carries its own uncertainty and says
// when it is too large to read as a plain number; each case has a verdict across its models;
// `tailsim trust` writes the convergence and sensitivity study of an experiment.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "analytic_test_util.h"
#include "models/analytic/analytic_simulation.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/trust_study.h"
#include "experiments/verdict.h"
#include "models/mujoco/mujoco_simulation.h"
#include "plotting/result_folder.h"
#include "plotting/trust_report.h"
#include "common/atomic_file.h"

namespace fs = std::filesystem;
using namespace tailsim;
using namespace tailsim::testing;

namespace {

OutputSettings noSeries() {
  OutputSettings o;
  o.time_series = TimeSeriesOutput::kNone;
  return o;
}

MujocoSettings atPaperHeight() {
  MujocoSettings s;
  s.body_height_m = 0.15;
  return s;
}

// The Fig. 7 stroke on the 1-link paper robot.
TailTrajectory fig7() { return sameMove(1, 0, -90, 0.25, 0.25); }

}  // namespace

TEST(Uncertainty, EveryMujocoRunCarriesABoundOnItsErrorAgainstTheConvergedReference) {
  const RunResult r = simulateMujoco(paperRobot(1), fig7(), atPaperHeight(), {}, noSeries());
  ASSERT_TRUE(r.summary.ok) << r.summary.error;
  ASSERT_TRUE(r.summary.extra.count("phi_net_uncertainty_deg"));
  const double u = r.summary.extra.at("phi_net_uncertainty_deg");
  EXPECT_GE(u, 0.005 * std::abs(r.summary.phi_net_deg) - 1e-12);  // the 0.5 % floor
  EXPECT_GT(r.summary.extra.at("uncertainty_solver_steps"), 0.4 * r.summary.solver_steps);
  // The reference of docs/mujoco-model.md: timestep / 8 (servo w_n kept), impratio 100, noslip 3.
  MujocoSettings ref = atPaperHeight();
  ref.timestep_s /= 8;
  ref.servo_wn_dt /= 8;
  ref.noslip_iterations = 3;
  ref.uncertainty = false;
  const RunResult f = simulateMujoco(paperRobot(1), fig7(), ref, {}, noSeries());
  ASSERT_TRUE(f.summary.ok) << f.summary.error;
  EXPECT_FALSE(f.summary.extra.count("phi_net_uncertainty_deg"));  // off: no check run
  EXPECT_LE(std::abs(r.summary.phi_net_deg - f.summary.phi_net_deg), u)
      << "phi " << r.summary.phi_net_deg << " ref " << f.summary.phi_net_deg;
  // The paper's case is well converged: no warning at the default share.
  for (const std::string& w : r.summary.warnings) EXPECT_EQ(w.find(kUncertainWarning), std::string::npos) << w;
}

TEST(Uncertainty, AResultBeyondItsShareIsWarnedAndNotPrintedAsAPlainNumber) {
  MujocoSettings s = atPaperHeight();
  s.uncertainty_warn_share = 1e-6;  // any result is "uncertain" at this share
  const RunResult r = simulateMujoco(paperRobot(1), fig7(), s, {}, noSeries());
  ASSERT_TRUE(r.summary.ok) << r.summary.error;
  bool warned = false;
  for (const std::string& w : r.summary.warnings) warned = warned || w.rfind(kUncertainWarning, 0) == 0;
  EXPECT_TRUE(warned);
  const RunRecord rec = readRunRecord(summaryJson(r.summary));
  EXPECT_NE(rec.phiText().find("+-"), std::string::npos) << rec.phiText();
  EXPECT_NE(rec.phiText().find("(uncertain)"), std::string::npos) << rec.phiText();
}

namespace {

RunSummary standing(const char* model, double phi, double u = NAN) {
  RunSummary s;
  s.model = model;
  s.phi_net_deg = phi;
  if (std::isfinite(u)) s.extra["phi_net_uncertainty_deg"] = u;
  return s;
}

RunSummary fallen(const char* model, const std::string& error) {
  RunSummary s;
  s.model = model;
  s.ok = false;
  s.phi_net_deg = NAN;
  s.error = error;
  s.extra["max_tilt_deg"] = 7.5;
  return s;
}

}  // namespace

TEST(Verdict, ModelsAgreeWithinTheirUncertainties) {
  const std::string v = caseVerdict({standing("analytic", 6.95), standing("perfoot", 6.96), standing("mujoco", 7.0, 0.1)});
  EXPECT_EQ(v.rfind("agree:", 0), 0u) << v;
  EXPECT_EQ(caseVerdict({standing("mujoco", 7.0, 0.1)}), "");  // one model: no verdict
}

TEST(Verdict, AGapIsAssignedToTheLadderStepBetweenTheModels) {
  // analytic and per-foot agree, MuJoCo differs by more than both uncertainties: the contact step.
  std::string v = caseVerdict({standing("analytic", 6.0), standing("perfoot", 6.01), standing("mujoco", 7.0, 0.1)});
  EXPECT_EQ(v.rfind("differ:", 0), 0u) << v;
  EXPECT_NE(v.find("contact model"), std::string::npos) << v;
  EXPECT_EQ(v.find("coupling"), std::string::npos) << v;
  // per-foot and MuJoCo agree, the analytic model differs: coupling and per-foot friction.
  v = caseVerdict({standing("analytic", 5.0), standing("perfoot", 6.99), standing("mujoco", 7.0, 0.1)});
  EXPECT_NE(v.find("coupling and per-foot friction"), std::string::npos) << v;
  EXPECT_EQ(v.find("contact model"), std::string::npos) << v;
  // A large MuJoCo uncertainty covers the gap, and the verdict says MuJoCo is uncertain.
  RunSummary wide = standing("mujoco", 7.0, 2.0);
  wide.warnings.push_back(std::string(kUncertainWarning) + ": +-2 deg");
  v = caseVerdict({standing("perfoot", 6.0), wide});
  EXPECT_EQ(v.rfind("uncertain:", 0), 0u) << v;
  EXPECT_NE(v.find("agree:"), std::string::npos) << v;
}

// A MuJoCo run of the user's robot from its model file (the articulated run: its summary has the
// standing tilt figures) differs from the planar models by its legs, feet and contact, and a fall of
// it is a fall, with its tilt from the stance quoted.
TEST(Verdict, TheArticulatedRobotsGapAndFallAreNamedAsSuch) {
  RunSummary art = standing("mujoco", 7.0, 0.1);
  art.extra["stand_max_tilt_from_stance_deg"] = 0.3;
  std::string v = caseVerdict({standing("analytic", 6.0), standing("perfoot", 6.01), art});
  EXPECT_NE(v.find("per-foot - MuJoCo = -0.990 deg (14.1 %): the articulated robot"), std::string::npos) << v;
  EXPECT_EQ(v.find("contact model (the ladder's contact step"), std::string::npos) << v;
  RunSummary fell = art;
  fell.ok = false;
  fell.phi_net_deg = NAN;
  fell.error = "the robot fell over: its body tilted 60 deg from its stance (limit 45 deg) during the stroke";
  fell.extra["stroke_max_tilt_from_stance_deg"] = 60.0;
  v = caseVerdict({standing("perfoot", 6.0), fell});
  EXPECT_EQ(v.rfind("falls: MuJoCo falls", 0), 0u) << v;
  RunSummary standingArt = art;
  standingArt.extra["stroke_max_tilt_from_stance_deg"] = 3.25;
  RunSummary tipped;
  tipped.model = "perfoot";
  tipped.ok = false;
  tipped.phi_net_deg = NAN;
  tipped.error = std::string(kPlanarTipText) + " (test)";
  v = caseVerdict({tipped, standingArt});
  EXPECT_NE(v.find("MuJoCo's largest tilt 3.25 deg"), std::string::npos) << v;
}

// The verdict quotes "+- U" only for an uncertainty the run estimated itself: the planar models
// (which estimate none) and a MuJoCo run without its check run are quoted bare, and the verdict
// says what each model was compared with (its own estimate, or the 0.5 % floor).
TEST(Verdict, QuotesOnlyTheUncertaintiesTheRunsEstimated) {
  auto count = [](const std::string& s, const std::string& what) {
    int n = 0;
    for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
    return n;
  };
  // MuJoCo with its estimate: its +- U only.
  std::string v = caseVerdict({standing("analytic", 0.0), standing("perfoot", 0.0), standing("mujoco", 0.301, 0.012)});
  EXPECT_NE(v.find("[analytic +0.000, per-foot +0.000, MuJoCo +0.301 +- 0.012 deg]"), std::string::npos) << v;
  EXPECT_EQ(count(v, "+-"), 1) << v;
  EXPECT_NE(v.find("MuJoCo its own estimate"), std::string::npos) << v;
  EXPECT_NE(v.find("analytic and per-foot none estimated, the floor 0.5 %"), std::string::npos) << v;
  // MuJoCo without one (mujoco.uncertainty: false): no "+-" at all; compared with the floor, said so.
  v = caseVerdict({standing("analytic", 0.0), standing("perfoot", 0.0), standing("mujoco", 0.301)});
  EXPECT_EQ(count(v, "+-"), 0) << v;
  EXPECT_NE(v.find("MuJoCo +0.301 (uncertainty not estimated)"), std::string::npos) << v;
  EXPECT_NE(v.find("the floor is the least it could be"), std::string::npos) << v;
  // Its check run failed (phi_net_uncertainty_deg NaN): the same, and why.
  RunSummary failed = standing("mujoco", 7.0);
  failed.extra["phi_net_uncertainty_deg"] = NAN;
  v = caseVerdict({standing("perfoot", 6.0), failed});
  EXPECT_EQ(count(v, "+-"), 0) << v;
  EXPECT_NE(v.find("its check run failed"), std::string::npos) << v;
}

TEST(Verdict, FallsAreFallsAndADisagreementNamesItsReason) {
  const std::string tip = "system COM 0.01 m beyond its rear edge: the robot tips over at t = 0.2 s";
  const std::string fell = "robot fell over at t = 0.3 s: body tilt 5.01 deg (limit max_tilt_deg = 5 deg)";
  std::string v = caseVerdict({standing("perfoot", 6.0), fallen("mujoco", fell)});
  EXPECT_EQ(v.rfind("falls:", 0), 0u) << v;
  EXPECT_NE(v.find("MuJoCo falls"), std::string::npos) << v;
  EXPECT_NE(v.find("dynamic load transfer"), std::string::npos) << v;
  v = caseVerdict({fallen("analytic", tip), standing("mujoco", 6.0, 0.1)});
  EXPECT_NE(v.find("support margin"), std::string::npos) << v;
  EXPECT_EQ(caseVerdict({fallen("analytic", tip), fallen("mujoco", fell)}).rfind("fall:", 0), 0u);
  EXPECT_EQ(caseVerdict({fallen("analytic", "analytic model failed: NaN"), standing("mujoco", 6.0, 0.1)}).rfind("no-verdict", 0),
            0u);
}

// A planar model tips and MuJoCo stands, but MuJoCo's run nearly fell: the "support margin" (MuJoCo
// comes back) is then in doubt, and the verdict says so. On the tippy corpus (docs/mujoco-model.md
// "Tipping over") six robots the converged reference sees fall stand uncertain at the defaults,
// and the per-foot model tips in each.
TEST(Verdict, AMujocoRunThatNearlyFellLeavesTheSupportMarginInDoubt) {
  const RunSummary tipped = fallen("perfoot", std::string(kPlanarTipText) + " at t = 0.1 s (test)");
  RunSummary rocked = standing("mujoco", -11.9, 0.32);
  rocked.extra["max_tilt_deg"] = 1.66;
  std::string v = caseVerdict({tipped, rocked});
  EXPECT_EQ(v.rfind("falls:", 0), 0u) << v;
  EXPECT_NE(v.find("support margin"), std::string::npos) << v;
  EXPECT_EQ(v.find("may see it fall"), std::string::npos) << v;  // no warning: MuJoCo's stand is not in doubt
  rocked.warnings.push_back(std::string(kUncertainWarning) + ": the robot nearly fell (body tilt up to 1.66 deg)");
  v = caseVerdict({tipped, rocked});
  EXPECT_EQ(v.rfind("falls:", 0), 0u) << v;
  EXPECT_NE(v.find("MuJoCo's largest tilt 1.66 deg"), std::string::npos) << v;
  EXPECT_NE(v.find("MuJoCo's own result is uncertain"), std::string::npos) << v;
  EXPECT_NE(v.find("a converged MuJoCo run may see it fall too"), std::string::npos) << v;
}

TEST(Verdict, TheModelsFailureTextsAreTheOnesTheVerdictReads) {
  // A robot that falls in every model (tests/test_tipping.cc's static tip, 30 kg tail): the
  // planar support check and MuJoCo's standing monitor say so in the words caseVerdict looks for.
  RobotParams r = paperRobot(1, 0.3);
  r.tail[0].mass_kg = 30;
  r.tail[0].length_m = 0.3;
  r.tail[0].com_offset_m = 0.15;
  r.tail[0].izz_kgm2 = 0.02;
  const TailTrajectory t = sameMove(1, 0, -5, 0.25, 0.25);
  const RunResult m = simulateMujoco(r, t, atPaperHeight(), {}, noSeries());
  const RunResult a = simulateAnalytic(r, t, {}, {}, noSeries());
  ASSERT_FALSE(m.summary.ok);
  ASSERT_FALSE(a.summary.ok);
  EXPECT_NE(m.summary.error.find(kMujocoFallText), std::string::npos) << m.summary.error;
  EXPECT_NE(a.summary.error.find(kPlanarTipText), std::string::npos) << a.summary.error;
  EXPECT_EQ(caseVerdict({a.summary, m.summary}).rfind("fall:", 0), 0u);
}

TEST(Verdict, IsInEveryCaseOfSummaryJsonAndResultsCsv) {
  const fs::path dir = fs::path(TAILSIM_BINARY_DIR) / "test_trust_verdict";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path yaml = dir / "v.yaml";
  std::ofstream(yaml) << "name: v\nrobot: " << TAILSIM_SOURCE_DIR
                      << "/configs/robots/paper_quadruped.yaml\nmodels: [analytic, perfoot, mujoco]\n"
                         "trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n"
                         "output: {time_series: none}\n";
  const Experiment e = loadExperiment(yaml.string());
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.threads = 1;
  o.progress = false;
  runExperiment(e, o);
  std::ifstream in(dir / "out" / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  const std::string v = s["cases"][0]["verdict"].get<std::string>();
  EXPECT_FALSE(v.empty());
  std::ifstream csv(dir / "out" / "results.csv");
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  EXPECT_NE(header.find(",verdict,"), std::string::npos) << header;
  EXPECT_NE(header.find("phi_net_uncertainty_deg"), std::string::npos) << header;
  EXPECT_NE(row.find(v.substr(0, 20)), std::string::npos) << row;
}

TEST(TrustStudy, WritesItsTableCsvAndFigureIntoTheFolder) {
  const fs::path dir = fs::path(TAILSIM_BINARY_DIR) / "test_trust_study";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path yaml = dir / "t.yaml";
  std::ofstream(yaml) << "name: t\nrobot: " << TAILSIM_SOURCE_DIR
                      << "/configs/robots/paper_quadruped.yaml\nmodels: [mujoco]\n"
                         "trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n"
                         "output: {settle_s: 0.1}\n";
  const Experiment e = loadExperiment(yaml.string());
  const std::vector<TrustStudy> st = runTrustStudy(e, {});
  ASSERT_EQ(st.size(), 1u);
  int timestep = 0, contact = 0, jitter = 0, planar = 0;
  for (const TrustRow& r : st[0].rows) {
    timestep += r.group == "timestep";
    contact += r.group == "contact";
    jitter += r.group == "jitter";
    planar += r.group == "planar";
    EXPECT_TRUE(r.ok) << r.group << " " << r.setting << ": " << r.failure;
    EXPECT_GT(r.wall_s, 0.0) << r.setting;
  }
  EXPECT_EQ(timestep, 3);
  EXPECT_EQ(contact, 6);
  EXPECT_EQ(jitter, 3);
  EXPECT_EQ(planar, 2);
  ASSERT_NE(st[0].row("reference"), nullptr);
  EXPECT_TRUE(std::isfinite(st[0].row("default")->uncertainty_deg));
  EXPECT_FALSE(st[0].verdict.empty());
  const std::string out = (dir / "out").string();
  const std::vector<std::string> files = writeTrust(st, e, out);
  for (const std::string& f : trustOutputs()) {
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / f)) << f;
    EXPECT_GT(fs::file_size(fs::path(out) / f), 0u) << f;
  }
  std::ifstream md(fs::path(out) / "trust.md");
  std::stringstream text;
  text << md.rdbuf();
  EXPECT_NE(text.str().find("| timestep | timestep_s = 5e-05 s |"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("Verdict across the models"), std::string::npos);
  EXPECT_TRUE(hasManifest(out));
  std::ifstream csvf(fs::path(out) / "trust.csv");
  std::stringstream csv;
  csv << csvf.rdbuf();
  EXPECT_TRUE(manifestNames(out, "trust.csv", csv.str()));
}
