// The model registry owns everything about a model: a model registered from this file alone (no
// other file of tailsim names it) runs from an experiment file, is sharded, plotted, written to
// results.csv and named in the report. The files it needed: this one.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/sharding.h"
#include "experiments/work_estimate.h"
#include "plotting/plots.h"
#include "plotting/report.h"
#include "results/columns.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tailsim_registry_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A closed-form model: feet that never slip (infinite friction). The tail follows its trajectory,
// the body stays where it stands, so phi(t) = 0 and phi_net = 0 exactly.
RunResult runHeld(const ExperimentCase& c, RunContext*) {
  RunResult r;
  r.summary.model = "held";
  const int n = c.robot.numLinks();
  for (const std::string& name : col::shared(n)) r.series.addColumn(name);
  const TailTrajectory traj = c.trajectory();
  const double dt = c.output.sample_dt_s, t_end = c.simDuration();
  std::vector<JointState> js;
  const double deg = 180.0 / M_PI;
  for (long k = 0; k * dt <= t_end; ++k) {
    const double t = k * dt;
    traj.evaluate(t, js);
    std::vector<double> row = {t};
    for (const JointState& j : js) row.push_back(j.theta * deg);
    for (const JointState& j : js) row.push_back(j.theta_dot * deg);
    for (const JointState& j : js) row.push_back(j.theta_ddot * deg);
    row.resize(r.series.numColumns(), 0.0);  // x, y, phi and their rates, the loads: the body is held
    r.series.appendRow(row);
  }
  r.summary.phi_net_deg = 0.0;
  r.summary.t_stop_s = 0.0;
  r.summary.solver_steps = static_cast<long>(r.series.numRows());
  return r;
}

ModelEntry heldModel() {
  ModelEntry m;
  m.name = "held";
  m.title = "held (feet never slip)";
  m.color = "#CC79A7";
  m.glossary = "held = feet that never slip (the body does not turn)";
  m.run = runHeld;
  m.columns = col::shared;
  m.cost_fixed_s = 1e-4;
  m.cost_per_row_s = 1e-7;
  return m;
}

}  // namespace

TEST(ModelRegistry, ATestOnlyModelRunsShardsPlotsAndIsReported) {
  const ModelRegistration held(heldModel());
  EXPECT_THROW(ModelRegistration{heldModel()}, std::invalid_argument);  // one entry per name
  const fs::path dir = tempDir("held");
  const fs::path yaml = dir / "held.yaml";
  std::ofstream(yaml) << "name: held_sweep\nrobot: " << TAILSIM_SOURCE_DIR << "/configs/robots/paper_quadruped.yaml\n"
                      << "tail: {links: 1}\ntrajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.3, 0.6]}}\n"
                      << "models: [analytic, held]\n";
  const Experiment e = loadExperiment(yaml.string());
  ASSERT_EQ(e.cases.size(), 2u);

  // Sharded: its cost counts, and the two shards hold every case once.
  const WorkEstimate w = estimateWork(e.cases[0]);
  ASSERT_EQ(w.models.size(), 2u);
  EXPECT_EQ(w.models[1]->name, "held");
  WorkEstimate analytic_only = w;
  analytic_only.models.pop_back();
  EXPECT_GT(expectedCaseCostS(w), expectedCaseCostS(analytic_only));
  const std::vector<std::vector<char>> a = shardMembership({e}, {1, 2}), b = shardMembership({e}, {2, 2});
  for (size_t i = 0; i < e.cases.size(); ++i) EXPECT_NE(a[0][i], b[0][i]) << i;

  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  o.threads = 1;
  const RunStats s = runExperiment(e, o);
  EXPECT_EQ(s.ran, 2);

  // results.csv: one row per case and model, phi_net 0 for the held body.
  const std::string csv = slurp(dir / "out" / "results.csv");
  EXPECT_NE(csv.find("held_sweep,w_ss=0.3,held,0.3,0.0,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("held_sweep,w_ss=0.6,held,0.6,0.0,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("held_sweep,w_ss=0.3,analytic,"), std::string::npos) << csv;
  const std::string series = slurp(dir / "out" / "cases" / "w_ss=0.3" / "held.csv");
  EXPECT_EQ(series.rfind("t_s,theta1_deg,", 0), 0u) << series.substr(0, 200);

  // Plotted: phi_net over the swept key in its colour and title, and its own panel of phi(t).
  plotResults((dir / "out").string());
  const fs::path plots = dir / "out" / "plots";
  EXPECT_NE(slurp(plots / "held_sweep_phi_net.gp").find("lc rgb '#CC79A7' title 'held (feet never slip)'"),
            std::string::npos);
  EXPECT_NE(slurp(plots / "held_sweep_phi_t.gp").find("set title 'held (feet never slip)'"), std::string::npos);
  EXPECT_TRUE(fs::exists(plots / "held_sweep_phi_t_held_0.dat"));
  EXPECT_GT(fs::file_size(plots / "held_sweep_phi_net.png"), 1000u);

  // Reported: the model's runs and its phi_net column.
  writeReport((dir / "out").string(), false);
  const std::string md = slurp(dir / "out" / "report.md");
  EXPECT_NE(md.find("held phi_net [deg]"), std::string::npos) << md;
  EXPECT_NE(md.find("held (2 ok"), std::string::npos) << md;
  fs::remove_all(dir);
}

// Every model's CSV size counts in the work estimate: a per-foot run alone writes its own columns
// (it was estimated at 0 bytes, so no byte limit bounded it).
TEST(ModelRegistry, WorkEstimateCountsEveryModelsColumns) {
  const Experiment e = loadExperimentText(
      "name: pf\nrobot: paper\ntail: {links: 2}\ntrajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25}\n"
      "models: [perfoot]\n",
      "pf.yaml");
  const ExperimentCase& c = e.cases.at(0);
  const WorkEstimate w = estimateWork(c);
  EXPECT_EQ(w.csv_bytes, w.rows * static_cast<double>(findModel(kPerFootModel)->columns(2).size()) * 12.0);
  EXPECT_GT(w.csv_bytes, 0.0);
}

// Each planar model's registry columns are the columns its run writes, in that order.
TEST(ModelRegistry, ColumnsAreTheColumnsTheRunWrites) {
  for (const char* m : {kAnalyticModel, kPerFootModel}) {
    const Experiment e = loadExperimentText(
        "name: cols\nrobot: paper\ntail: {links: 2}\ntrajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25}\n"
        "models: [" + std::string(m) + "]\n",
        "cols.yaml");
    const RunResult r = findModel(m)->run(e.cases.at(0), nullptr);
    ASSERT_TRUE(r.summary.ok) << r.summary.error;
    EXPECT_EQ(r.series.names(), findModel(m)->columns(2)) << m;
  }
}
