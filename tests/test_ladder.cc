// The per-foot model as a registered model (`models: [.., perfoot, ..]`, the
// `perfoot:` section) and the gap ladder (configs/ladder/, `tailsim ladder`).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <sstream>

#include "models/perfoot/per_foot_model.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "plotting/ladder.h"
#include "plotting/result_folder.h"
#include "results/columns.h"
#include "scratch_dir.h"

using namespace tailsim;
using tailsim::testing::ScratchDir;
namespace fs = std::filesystem;

namespace {

// Fig. 7's case with the given extra lines.
fs::path writeCase(const fs::path& dir, const std::string& extra, const std::string& quadruped = "{d_Q2B_m: 0.125}") {
  const fs::path f = dir / "case.yaml";
  std::ofstream(f) << "name: pf\nrobot: paper\ntail: {links: 1}\nquadruped: " << quadruped << "\n"
                   << "trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n"
                   << extra;
  return f;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(PerFootRegistered, YamlRunsTheSameModelAsTheLibraryCall) {
  const ScratchDir dir("ladder_yaml");
  const Experiment e = loadExperiment(
      writeCase(dir, "models: [analytic, perfoot]\nperfoot: {normal_loads: load_transfer}\n",
               "{d_Q2B_m: 0.125, com_height_m: 0.2}")
          .string());
  ASSERT_EQ(e.cases.size(), 1u);
  const ExperimentCase& c = e.cases[0];
  EXPECT_EQ(c.perfoot.normal_loads, NormalLoadModel::kLoadTransfer);
  EXPECT_DOUBLE_EQ(c.robot.quadruped.com_height_m, 0.2);
  EXPECT_DOUBLE_EQ(c.mujoco.body_height_m, 0.2);  // MuJoCo's body follows the robot's COM height
  const std::vector<RunResult> runs = runCase(c);
  const RunResult* pf = nullptr;
  for (const RunResult& r : runs)
    if (r.summary.model == "perfoot") pf = &r;
  ASSERT_NE(pf, nullptr);
  ASSERT_TRUE(pf->summary.ok) << pf->summary.error;
  PerFootSettings s;
  s.normal_loads = NormalLoadModel::kLoadTransfer;
  const RunResult direct = simulatePerFoot(c.robot, c.trajectory(), s, c.effects, c.output);
  EXPECT_DOUBLE_EQ(pf->summary.phi_net_deg, direct.summary.phi_net_deg);
  // Load transfer at another height gives another answer (the setting reaches the model).
  RobotParams low = c.robot;
  low.quadruped.com_height_m = 0.05;
  EXPECT_NE(simulatePerFoot(low, c.trajectory(), s, c.effects, c.output).summary.phi_net_deg,
            pf->summary.phi_net_deg);
  // Its own columns are in the registry's column order, after the shared ones.
  const std::vector<std::string> order = modelColumnOrder(1);
  for (const std::string& k : col::perfootOnly()) {
    EXPECT_NE(std::find(order.begin(), order.end(), k), order.end()) << k;
    EXPECT_TRUE(pf->series.has(k)) << k;
  }
  ASSERT_NE(findModel("perfoot"), nullptr);
}

TEST(PerFootRegistered, BadPerfootKeyNamesFileLineAndKey) {
  const ScratchDir dir("ladder_bad");
  const fs::path f = writeCase(dir, "models: [perfoot]\nperfoot: {normal_loads: sideways}\n");
  try {
    loadExperiment(f.string());
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("case.yaml:7:"), std::string::npos) << m;
    EXPECT_NE(m.find("normal_loads"), std::string::npos) << m;
    EXPECT_NE(m.find("quasi_static, load_transfer"), std::string::npos) << m;
  }
  const fs::path g = writeCase(dir, "models: [perfoot]\nperfoot: {v_stop_mps: 0}\n");
  EXPECT_THROW(loadExperiment(g.string()), ConfigError);
}

// configs/ladder/fig07_loading.yaml run and read back: one figure case, four ladder cases.
TEST(GapLadder, Fig7RungsAreTheRunsPhiNetAndTheReportIsWritten) {
  const ScratchDir out("ladder_fig7");
  const Experiment e = loadExperiment(std::string(TAILSIM_SOURCE_DIR) + "/configs/ladder/fig07_loading.yaml");
  ASSERT_EQ(e.cases.size(), 4u);  // coupling x friction law
  RunOptions o;
  o.out_dir = out.string();
  o.progress = false;
  o.threads = 2;
  runExperiment(e, o);

  const std::vector<LadderCase> L = loadLadder(out.string());
  ASSERT_EQ(L.size(), 1u);
  EXPECT_EQ(L[0].name, "base");
  const ExperimentResults r = loadResults(out.string());
  auto phi = [&](const std::string& coupling, const std::string& law, const std::string& model) {
    for (const CaseRecord& c : r.cases)
      if (c.name == "coupling=" + coupling + ",friction=" + law) return r.phiNet(c, model);
    return std::nan("");
  };
  EXPECT_EQ(L[0].paper, phi("paper", "stiction", "analytic"));
  EXPECT_EQ(L[0].exact, phi("exact", "stiction", "analytic"));
  EXPECT_EQ(L[0].perfoot_coulomb, phi("paper", "stiction", "perfoot"));
  EXPECT_EQ(L[0].perfoot_adams, phi("paper", "continuous", "perfoot"));
  EXPECT_EQ(L[0].mujoco_adams, phi("paper", "continuous", "mujoco"));
  EXPECT_EQ(L[0].mujoco_const, phi("paper", "stiction", "mujoco"));
  EXPECT_EQ(L[0].paper_adams, phi("paper", "continuous", "analytic"));
  // The per-foot model and MuJoCo ignore analytic.coupling: the duplicate runs agree.
  EXPECT_EQ(phi("exact", "stiction", "perfoot"), L[0].perfoot_coulomb);
  EXPECT_EQ(phi("exact", "stiction", "mujoco"), L[0].mujoco_const);
  // Every rung a finite, distinct-model number; the paper model turns least (Sec. 4.2).
  for (double v : {L[0].paper, L[0].exact, L[0].perfoot_coulomb, L[0].perfoot_adams, L[0].mujoco_adams,
                   L[0].mujoco_const})
    EXPECT_TRUE(std::isfinite(v) && v > 0);
  EXPECT_LT(L[0].paper, L[0].mujoco_adams);

  const std::vector<std::string> files = writeLadder(out.string());
  const std::string md = slurp(out / "ladder.md");
  char b[32];
  std::snprintf(b, sizeof b, "| base | %.2f |", L[0].paper);
  EXPECT_NE(md.find(b), std::string::npos) << md;
  EXPECT_NE(md.find("Per-foot model vs MuJoCo, same friction law (1 cases)"), std::string::npos);
  EXPECT_TRUE(fs::file_size(out / "plots" / "ladder_fig07_loading.png") > 1000);
  // Its script names its files as "./<file>" (gpFileName): no name can be read as a pipe or datablock.
  const std::string gp = slurp(out / "plots" / "ladder_fig07_loading.gp");
  EXPECT_NE(gp.find("set output './ladder_fig07_loading.png'"), std::string::npos) << gp;
  EXPECT_NE(gp.find("'./ladder_fig07_loading.dat' using"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("'ladder_fig07_loading."), std::string::npos) << gp;
  EXPECT_NE(slurp(out / "ladder.csv").find("ladder_fig07_loading,\"base\","), std::string::npos);
  fs::remove_all(out);
}

TEST(GapLadder, AFolderWithoutTheLadderAxesIsRefused) {
  const ScratchDir dir("ladder_notladder");
  const Experiment e = loadExperiment(writeCase(dir, "models: [analytic]\n").string());
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  runExperiment(e, o);
  try {
    loadLadder(o.out_dir);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& x) {
    EXPECT_NE(std::string(x.what()).find("not a ladder experiment"), std::string::npos) << x.what();
  }
  fs::remove_all(dir);
}

// ladder.md and ladder.csv were written over the user's own files of those names: refused before
// anything is written, naming the file; tailsim's own (and an earlier tailsim's, by its first line)
// are replaced.
TEST(UserFiles, LadderTablesReplaceOnlyTailsimsOwn) {
  const ScratchDir out("ladder_userfiles");
  RunOptions o;
  o.out_dir = out.string();
  o.progress = false;
  o.threads = 2;
  runExperiment(loadExperiment(std::string(TAILSIM_SOURCE_DIR) + "/configs/ladder/fig07_loading.yaml"), o);
  for (const std::string name : {"ladder.md", "ladder.csv"}) {
    std::ofstream(out / name) << "mine";
    try {
      writeLadder(out.string());
      ADD_FAILURE() << "the user's " << name << " was replaced";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find((out / name).string() + " was not written by tailsim"), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(slurp(out / name), "mine");
    EXPECT_FALSE(fs::exists(out / "plots" / "ladder_fig07_loading.png")) << "written before the refusal";
    fs::remove(out / name);
  }
  writeLadder(out.string());
  writeLadder(out.string());  // over its own files
  const std::string md = slurp(out / "ladder.md");
  {  // an earlier tailsim's ladder.md: not in the manifest, recognised by its first line
    std::istringstream in(slurp(out / ".tailsim-manifest"));
    std::string keep;
    for (std::string l; std::getline(in, l);)
      if (l.size() < 11 || l.compare(l.size() - 11, 11, "  ladder.md") != 0) keep += l + "\n";
    std::ofstream(out / ".tailsim-manifest", std::ios::trunc) << keep;
  }
  std::ofstream(out / "ladder.md", std::ios::trunc) << "# The gap ladder\n\nolder\n";
  writeLadder(out.string());
  EXPECT_EQ(slurp(out / "ladder.md"), md);
  fs::remove_all(out);
}
