// Experiment-file loader: schema, sweeps, validation messages (file:line:col: key: what).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "experiments/experiment_loader.h"
#include "experiments/keyword_args.h"
#include "experiments/settings_json.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

const std::string kSourceDir = TAILSIM_SOURCE_DIR;

// A fresh directory with robots/paper_quadruped.yaml copied in; experiments are written beside it.
class LoaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "tailsim_loader_XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
    fs::create_directories(dir_ / "robots");
    fs::copy_file(kSourceDir + "/configs/robots/paper_quadruped.yaml", dir_ / "robots/paper_quadruped.yaml");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& rel, const std::string& text) {
    const fs::path p = dir_ / rel;
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }
  // A valid experiment header (lines 1-3) followed by `rest` (which starts on line 4).
  static std::string exp(const std::string& rest) {
    return "name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 1}\n" + rest;
  }
  static constexpr const char* kTraj = "trajectory: {dtheta_deg: -90, dT_s: 0.25}\n";

  // Loads `text`; expects a ConfigError "<file>:<line>:<col>: <key>: ..." containing `what`.
  void expectError(const std::string& text, int line, const std::string& key, const std::string& what = "",
                   const std::string& file = "exp.yaml", int col = 0) {
    const std::string path = write("exp.yaml", text);
    try {
      loadExperiment(path);
      ADD_FAILURE() << "no ConfigError for:\n" << text;
    } catch (const ConfigError& e) {
      const std::string msg = e.what();
      const std::string f = (dir_ / file).string();
      const std::string prefix = f + ":" + std::to_string(line) + ":";
      EXPECT_EQ(msg.rfind(prefix, 0), 0u) << "message: " << msg << "\nexpected prefix: " << prefix;
      if (col > 0) {
        EXPECT_NE(msg.find(prefix + std::to_string(col) + ": "), std::string::npos) << msg;
      }
      const std::regex re("^" + std::regex_replace(f, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") +
                          R"(:\d+:\d+: )" + std::regex_replace(key, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") +
                          ": ");
      if (!key.empty()) {
        EXPECT_TRUE(std::regex_search(msg, re)) << "message: " << msg << "\nexpected key: " << key;
      }
      EXPECT_NE(msg.find(what), std::string::npos) << "message: " << msg << "\nexpected to contain: " << what;
    }
  }

  fs::path dir_;
};

// ---------------------------------------------------------------------------------------------

TEST_F(LoaderTest, DefaultConfigLoadsWithPaperNumbers) {
  const Experiment e = loadExperiment(kSourceDir + "/configs/default.yaml");
  EXPECT_EQ(e.name, "fig07_default");
  EXPECT_EQ(e.source_file, fs::path(kSourceDir + "/configs/default.yaml").lexically_normal().string());
  EXPECT_TRUE(fs::path(e.source_file).is_absolute());
  EXPECT_TRUE(e.swept_keys.empty());
  ASSERT_EQ(e.cases.size(), 1u);
  const ExperimentCase& c = e.cases[0];
  EXPECT_EQ(c.name, "base");
  EXPECT_EQ(c.experiment, "fig07_default");
  EXPECT_EQ(c.kind, CaseKind::kSimulate);
  // Table 1.
  EXPECT_DOUBLE_EQ(c.robot.quadruped.mass_kg, 8.458);
  EXPECT_DOUBLE_EQ(c.robot.quadruped.izz_kgm2, 0.1916);
  EXPECT_DOUBLE_EQ(c.robot.quadruped.d_Q2C_m, -0.0155);
  EXPECT_DOUBLE_EQ(c.robot.quadruped.d_Q2B_m, 0.125);
  EXPECT_DOUBLE_EQ(c.robot.quadruped.l_F_m, 0.30);
  EXPECT_DOUBLE_EQ(c.robot.quadruped.w_F_m, 0.26);
  EXPECT_DOUBLE_EQ(c.robot.friction.mu_s, 0.25);
  EXPECT_DOUBLE_EQ(c.robot.friction.mu_d, 0.30);
  EXPECT_DOUBLE_EQ(c.robot.gravity_mps2, 9.81);
  // Table 2, 1-link tail; COM at mid-length by default.
  ASSERT_EQ(c.robot.numLinks(), 1);
  EXPECT_DOUBLE_EQ(c.robot.tail[0].mass_kg, 2.40);
  EXPECT_DOUBLE_EQ(c.robot.tail[0].izz_kgm2, 2.236e-2);
  EXPECT_DOUBLE_EQ(c.robot.tail[0].length_m, 0.300);
  EXPECT_DOUBLE_EQ(c.robot.tail[0].com_offset_m, 0.150);
  // Fig. 7 trajectory, in radians.
  ASSERT_EQ(c.joints.size(), 1u);
  EXPECT_DOUBLE_EQ(c.joints[0].theta0_rad, 0.0);
  EXPECT_DOUBLE_EQ(c.joints[0].dtheta_rad, -M_PI / 2);
  EXPECT_DOUBLE_EQ(c.joints[0].dT_s, 0.25);
  EXPECT_DOUBLE_EQ(c.joints[0].w_ss, 0.25);
  EXPECT_DOUBLE_EQ(c.joints[0].t0_s, 0.0);
  EXPECT_EQ(c.models, std::vector<std::string>{"analytic"});
  // Unset sections keep their defaults; no render section, no video.
  EXPECT_EQ(c.analytic.solver, AnalyticSolver::kAdaptive);
  EXPECT_EQ(c.effects.friction, FrictionLaw::kStiction);
  EXPECT_DOUBLE_EQ(c.output.sample_dt_s, 1e-3);
  EXPECT_FALSE(c.render.enabled);
  // The tail ends at theta0 + dtheta = -90 deg at t0 + dT (trajectory() uses the loaded params).
  EXPECT_NEAR(c.trajectory().joints[0].at(1.0).theta, -M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(c.simDuration(), 0.25 + 0.5);
}

TEST_F(LoaderTest, RobotTailsMatchTable2ForEveryN) {
  const std::string p = write("exp.yaml", "name: t\nrobot: robots/paper_quadruped.yaml\n"
                                          "tail: {links: {range: [1, 6, 1]}}\n" + std::string(kTraj));
  const Experiment e = loadExperiment(p);
  ASSERT_EQ(e.cases.size(), 6u);
  EXPECT_EQ(e.swept_keys, std::vector<std::string>{"tail.links"});
  for (int n = 1; n <= 6; ++n) {
    const ExperimentCase& c = e.cases[n - 1];
    EXPECT_EQ(c.name, "links=" + std::to_string(n));
    const TailLink ref = paperTailLink(n);  // Table 2 as coded in robot_params.cc
    ASSERT_EQ(c.robot.numLinks(), n);
    ASSERT_EQ(c.joints.size(), static_cast<size_t>(n));
    for (const TailLink& l : c.robot.tail) {
      EXPECT_DOUBLE_EQ(l.mass_kg, ref.mass_kg);
      EXPECT_DOUBLE_EQ(l.izz_kgm2, ref.izz_kgm2);
      EXPECT_DOUBLE_EQ(l.length_m, ref.length_m);
      EXPECT_DOUBLE_EQ(l.com_offset_m, ref.com_offset_m);
    }
    EXPECT_NEAR(c.robot.tailMass(), 2.4, 1e-12);  // every paper tail weighs 2.4 kg
  }
}

// paper-notes "Checks that follow from the text": Eq. (25) with thetadot_max = 10.47 rad/s.
TEST_F(LoaderTest, Eq25RuleGivesPaperNotesNumbers) {
  const double dtheta_deg[] = {-180, -120, -90, -72, -60, -51.43};
  const double dT_s[] = {0.600, 0.400, 0.300, 0.240, 0.200, 0.171};
  for (const char* speed : {"thetadot_max_radps: 10.47", "thetadot_max_dps: 600"}) {
    const std::string p = write("exp.yaml", "name: eq25\nrobot: robots/paper_quadruped.yaml\n"
                                            "tail: {links: {sweep: [1, 2, 3, 4, 5, 6]}}\n"
                                            "trajectory: {rule: eq25, w_ss: 0.3, " +
                                                std::string(speed) + "}\n");
    const Experiment e = loadExperiment(p);
    ASSERT_EQ(e.cases.size(), 6u);
    for (int n = 1; n <= 6; ++n) {
      const ExperimentCase& c = e.cases[n - 1];
      ASSERT_EQ(c.joints.size(), static_cast<size_t>(n)) << speed;
      for (const SplitCycleParams& j : c.joints) {
        EXPECT_NEAR(j.dtheta_rad / kDeg, dtheta_deg[n - 1], 0.005) << speed << " n=" << n;
        EXPECT_NEAR(j.dT_s, dT_s[n - 1], 0.0006) << speed << " n=" << n;
        EXPECT_NEAR(j.theta0_rad / kDeg, 180.0 / (n + 1), 1e-9) << "each joint starts at +180/(n+1) deg";
        EXPECT_DOUBLE_EQ(j.w_ss, 0.3);
        // The profile's own peak speed (Eq. 20 integrated) is thetadot_max.
        const SplitCycleProfile prof(j);
        EXPECT_NEAR(std::abs(prof.at(prof.t1()).theta_dot), 10.47, 0.01);
      }
    }
  }
}

TEST_F(LoaderTest, TwoDimensionalSweepIsAProductInFileOrder) {
  const std::string p = write("exp.yaml", exp("trajectory:\n"
                                              "  theta0_deg: {sweep: [0, 15, 30]}\n"
                                              "  dtheta_deg: -90\n"
                                              "  dT_s: 0.25\n"
                                              "quadruped:\n"
                                              "  d_Q2B_m: {sweep: [0.05, 0.1405]}\n"));
  const Experiment e = loadExperiment(p);
  EXPECT_EQ(e.swept_keys, (std::vector<std::string>{"trajectory.theta0_deg", "quadruped.d_Q2B_m"}));
  ASSERT_EQ(e.cases.size(), 6u);
  const double th[] = {0, 15, 30};
  const double d[] = {0.05, 0.1405};
  const char* dtext[] = {"0.05", "0.1405"};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 2; ++k) {
      const ExperimentCase& c = e.cases[i * 2 + k];  // first swept key varies slowest
      EXPECT_EQ(c.name, "theta0_deg=" + std::to_string(static_cast<int>(th[i])) + ",d_Q2B_m=" + dtext[k]);
      EXPECT_DOUBLE_EQ(c.joints[0].theta0_rad, th[i] * kDeg);
      EXPECT_DOUBLE_EQ(c.robot.quadruped.d_Q2B_m, d[k]);
      EXPECT_DOUBLE_EQ(c.robot.quadruped.mass_kg, 8.458);  // not overridden: from the robot file
      ASSERT_EQ(c.sweep_values.size(), 2u);
      EXPECT_EQ(c.sweep_values.at("trajectory.theta0_deg"), std::to_string(static_cast<int>(th[i])));
      EXPECT_EQ(c.sweep_values.at("quadruped.d_Q2B_m"), dtext[k]);
    }
}

TEST_F(LoaderTest, RangeIsInclusiveAndRobustToFloatSteps) {
  const std::string p = write("exp.yaml", exp("quadruped: {d_Q2B_m: {range: [0, 0.15, 0.025]}}\n") + kTraj);
  const Experiment e = loadExperiment(p);
  ASSERT_EQ(e.cases.size(), 7u);  // 0.15 / 0.025 = 5.999999999999999 in floating point
  const char* names[] = {"0", "0.025", "0.05", "0.075", "0.1", "0.125", "0.15"};
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(e.cases[i].name, std::string("d_Q2B_m=") + names[i]);
    EXPECT_EQ(e.cases[i].sweep_values.at("quadruped.d_Q2B_m"), names[i]);
    EXPECT_NEAR(e.cases[i].robot.quadruped.d_Q2B_m, 0.025 * i, 1e-15);
  }
  EXPECT_EQ(e.cases.back().robot.quadruped.d_Q2B_m, 0.15);  // the stop value exactly

  // Descending ranges, and 0..0.3 by 0.1 (0.3/0.1 = 2.9999999999999996): 4 values.
  const std::string q = write("exp.yaml", exp("trajectory: {theta0_deg: {range: [90, 0, -30]}, dtheta_deg: "
                                              "{range: [-0.1, -0.3, -0.1]}, dT_s: 0.25}\n"));
  const Experiment f = loadExperiment(q);
  ASSERT_EQ(f.cases.size(), 4u * 3u);
  EXPECT_EQ(f.cases.front().name, "theta0_deg=90,dtheta_deg=-0.1");
  EXPECT_EQ(f.cases.back().name, "theta0_deg=0,dtheta_deg=-0.3");
  EXPECT_DOUBLE_EQ(f.cases.back().joints[0].dtheta_rad, -0.3 * kDeg);
  const std::string r = write("exp.yaml", exp("output: {sample_dt_s: {range: [0.1, 0.7, 0.1]}}\n") + kTraj);
  EXPECT_EQ(loadExperiment(r).cases.size(), 7u);
}

TEST_F(LoaderTest, SweepValuesArePrintedAsWritten) {
  const std::string p = write("exp.yaml", exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.10, 2.5e-1]}}\n"
                                              "effects: {friction: {sweep: [stiction, continuous]}}\n"));
  const Experiment e = loadExperiment(p);
  ASSERT_EQ(e.cases.size(), 4u);
  EXPECT_EQ(e.cases[0].name, "w_ss=0.10,friction=stiction");
  EXPECT_EQ(e.cases[3].name, "w_ss=2.5e-1,friction=continuous");
  EXPECT_DOUBLE_EQ(e.cases[3].joints[0].w_ss, 0.25);
  EXPECT_EQ(e.cases[3].effects.friction, FrictionLaw::kContinuous);
}

TEST_F(LoaderTest, SharedLeafNamesUseTheDottedKey) {
  const std::string p = write("exp.yaml", "name: t\nrobot: robots/paper_quadruped.yaml\n"
                                          "tail: {custom: [{mass_kg: {sweep: [1, 2]}, izz_kgm2: 0.01, length_m: 0.3}]}\n"
                                          "quadruped: {mass_kg: {sweep: [8, 9]}}\n"
                                          "friction: {mu_s: {sweep: [0.2, 0.3]}}\n" +
                                          std::string(kTraj));
  const Experiment e = loadExperiment(p);
  ASSERT_EQ(e.cases.size(), 8u);
  EXPECT_EQ(e.swept_keys,
            (std::vector<std::string>{"tail.custom[0].mass_kg", "quadruped.mass_kg", "friction.mu_s"}));
  EXPECT_EQ(e.cases[5].name, "tail.custom[0].mass_kg=2,quadruped.mass_kg=8,mu_s=0.3");
  EXPECT_DOUBLE_EQ(e.cases[5].robot.tail[0].mass_kg, 2.0);
  EXPECT_DOUBLE_EQ(e.cases[5].robot.tail[0].com_offset_m, 0.15);  // 0.5 length_m by default
  EXPECT_DOUBLE_EQ(e.cases[5].robot.quadruped.mass_kg, 8.0);
  EXPECT_DOUBLE_EQ(e.cases[5].robot.friction.mu_s, 0.3);
}

TEST_F(LoaderTest, PerJointListsAndSweptListElements) {
  const std::string p = write("exp.yaml", "name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 2}\n"
                                          "trajectory:\n"
                                          "  theta0_deg: [0, {sweep: [10, 20]}]\n"
                                          "  dtheta_deg: [-90, -45]\n"
                                          "  peak_speed_dps: 720\n"
                                          "  w_ss: [0.25, 0.5]\n"
                                          "  t0_s: [0, 0.1]\n");
  const Experiment e = loadExperiment(p);
  EXPECT_EQ(e.swept_keys, std::vector<std::string>{"trajectory.theta0_deg[1]"});
  ASSERT_EQ(e.cases.size(), 2u);
  EXPECT_EQ(e.cases[1].name, "theta0_deg[1]=20");
  const auto& j = e.cases[1].joints;
  ASSERT_EQ(j.size(), 2u);
  EXPECT_DOUBLE_EQ(j[0].theta0_rad, 0.0);
  EXPECT_DOUBLE_EQ(j[1].theta0_rad, 20 * kDeg);
  EXPECT_DOUBLE_EQ(j[1].dtheta_rad, -45 * kDeg);
  EXPECT_DOUBLE_EQ(j[1].w_ss, 0.5);
  EXPECT_DOUBLE_EQ(j[1].t0_s, 0.1);
  // peak_speed_dps: the integrated profile really peaks at 720 deg/s, at t1 = t0 + w_ss dT.
  for (const SplitCycleParams& q : j) {
    const SplitCycleProfile prof(q);
    EXPECT_NEAR(std::abs(prof.at(prof.t1()).theta_dot), 720 * kDeg, 1e-9);
    EXPECT_LT(std::abs(prof.at(prof.t1() - 1e-3).theta_dot), 720 * kDeg);
  }
  EXPECT_DOUBLE_EQ(j[0].dT_s, 0.25);   // 2 * 90 / 720
  EXPECT_DOUBLE_EQ(j[1].dT_s, 0.125);  // 2 * 45 / 720
}

TEST_F(LoaderTest, PoseKindNeedsNoTrajectory) {
  const std::string p = write("exp.yaml", "name: fig08\nrobot: robots/paper_quadruped.yaml\nkind: pose\n"
                                          "tail: {links: 3}\n"
                                          "pose: {theta_deg: [30, {sweep: [0, 45]}, -30], thetadot_radps: 2, "
                                          "thetaddot_radps2: [1, 2, 3]}\n");
  const Experiment e = loadExperiment(p);
  ASSERT_EQ(e.cases.size(), 2u);
  const ExperimentCase& c = e.cases[1];
  EXPECT_EQ(c.kind, CaseKind::kPose);
  EXPECT_TRUE(c.joints.empty());
  ASSERT_EQ(c.pose.theta_rad.size(), 3u);
  EXPECT_DOUBLE_EQ(c.pose.theta_rad[0], 30 * kDeg);
  EXPECT_DOUBLE_EQ(c.pose.theta_rad[1], 45 * kDeg);
  EXPECT_DOUBLE_EQ(c.pose.thetadot_radps[2], 2.0);
  EXPECT_DOUBLE_EQ(c.pose.thetaddot_radps2[2], 3.0);
  // No pose section: all zero.
  const std::string q = write("exp.yaml", "name: p\nrobot: robots/paper_quadruped.yaml\nkind: pose\n");
  const Experiment f = loadExperiment(q);
  EXPECT_EQ(f.cases[0].pose.theta_rad, std::vector<double>{0.0});
}

TEST_F(LoaderTest, AllSectionsAreRead) {
  const std::string p = write(
      "exp.yaml",
      exp(std::string(kTraj) +
          "friction: {mu_s: 0.3, mu_d: 0.25, v_d_mps: 0.6}\n"
          "gravity_mps2: 9.8\n"
          "models: [mujoco, analytic]\n"
          "analytic: {solver: fixed, rel_tol: 1e-6, abs_tol: 1e-9, fixed_dt_s: 1e-5, event_tol_s: 1e-10,\n"
          "           max_step_s: 0.001, v_stop_mps: 1e-6, coupling: exact}\n"
          "mujoco: {timestep_s: 5e-5, integrator: RK4, solver: PGS, iterations: 50, tolerance: 1e-8,\n"
          "         cone: pyramidal, noslip_iterations: 3, condim: 4, impratio: 2, solref: [0.004, 0.9],\n"
          "         solimp: [0.9, 0.95, 0.002, 0.4, 3], mu: 0.3, kp: 50, kv: 2,\n"
          "         velocity_feedforward: false, inverse_dynamics_feedforward: no, servo_wn_dt: 0.3,\n"
          "         foot_radius_m: 0.02, settle_s: 0.3, stop_phidot_radps: 1e-4}\n"
          "quadruped: {com_height_m: 0.2}\n"
          "effects: {friction: none, translation: false, gravity: false, ground_contact: false,\n"
          "          foot_loads: constant, load_decomposition: false}\n"
          "output: {sample_dt_s: 0.002, duration_s: 1.5, settle_s: 0.2}\n"
          "render: {width: 320, height: 240, fps: 60, slowmo: 2, duration_s: 0.5, camera: perspective,\n"
          "         shadows: true, reflections: true, msaa: 4, ghost: false,\n"
          "         crf: 30, preset: slow}\n"));
  const ExperimentCase c = loadExperiment(p).cases.at(0);
  EXPECT_DOUBLE_EQ(c.robot.friction.mu_s, 0.3);
  EXPECT_DOUBLE_EQ(c.robot.friction.mu_d, 0.25);
  EXPECT_DOUBLE_EQ(c.robot.friction.v_d_mps, 0.6);
  EXPECT_DOUBLE_EQ(c.robot.friction.v_s_mps, 0.05);
  EXPECT_DOUBLE_EQ(c.robot.gravity_mps2, 9.8);
  EXPECT_EQ(c.models, (std::vector<std::string>{"mujoco", "analytic"}));
  EXPECT_EQ(c.analytic.solver, AnalyticSolver::kFixed);
  EXPECT_DOUBLE_EQ(c.analytic.rel_tol, 1e-6);
  EXPECT_DOUBLE_EQ(c.analytic.abs_tol, 1e-9);
  EXPECT_DOUBLE_EQ(c.analytic.fixed_dt_s, 1e-5);
  EXPECT_DOUBLE_EQ(c.analytic.event_tol_s, 1e-10);
  EXPECT_DOUBLE_EQ(c.analytic.max_step_s, 0.001);
  EXPECT_DOUBLE_EQ(c.analytic.v_stop_mps, 1e-6);
  EXPECT_EQ(c.analytic.coupling, Coupling::kExact);
  EXPECT_DOUBLE_EQ(c.mujoco.timestep_s, 5e-5);
  EXPECT_EQ(c.mujoco.integrator, MujocoIntegrator::kRK4);
  EXPECT_EQ(c.mujoco.solver, MujocoSolver::kPGS);
  EXPECT_EQ(c.mujoco.iterations, 50);
  EXPECT_DOUBLE_EQ(c.mujoco.tolerance, 1e-8);
  EXPECT_EQ(c.mujoco.cone, MujocoCone::kPyramidal);
  EXPECT_EQ(c.mujoco.noslip_iterations, 3);
  EXPECT_EQ(c.mujoco.condim, 4);
  EXPECT_DOUBLE_EQ(c.mujoco.impratio, 2.0);
  EXPECT_DOUBLE_EQ(c.mujoco.solref[0], 0.004);
  EXPECT_DOUBLE_EQ(c.mujoco.solref[1], 0.9);
  EXPECT_DOUBLE_EQ(c.mujoco.solimp[2], 0.002);
  EXPECT_DOUBLE_EQ(c.mujoco.solimp[4], 3.0);
  EXPECT_DOUBLE_EQ(c.mujoco.mu, 0.3);
  EXPECT_DOUBLE_EQ(c.mujoco.kp, 50.0);
  EXPECT_DOUBLE_EQ(c.mujoco.kv, 2.0);
  EXPECT_FALSE(c.mujoco.velocity_feedforward);
  EXPECT_FALSE(c.mujoco.inverse_dynamics_feedforward);
  EXPECT_DOUBLE_EQ(c.mujoco.servo_wn_dt, 0.3);
  EXPECT_DOUBLE_EQ(c.mujoco.body_height_m, 0.2);
  EXPECT_DOUBLE_EQ(c.mujoco.foot_radius_m, 0.02);
  EXPECT_DOUBLE_EQ(c.mujoco.settle_s, 0.3);
  EXPECT_DOUBLE_EQ(c.mujoco.stop_phidot_radps, 1e-4);
  EXPECT_EQ(c.effects.friction, FrictionLaw::kNone);
  EXPECT_FALSE(c.effects.translation);
  EXPECT_FALSE(c.effects.gravity);
  EXPECT_FALSE(c.effects.ground_contact);
  EXPECT_EQ(c.effects.foot_loads, FootLoadModel::kConstant);
  EXPECT_FALSE(c.effects.load_decomposition);
  EXPECT_DOUBLE_EQ(c.output.sample_dt_s, 0.002);
  EXPECT_DOUBLE_EQ(c.output.duration_s, 1.5);
  EXPECT_DOUBLE_EQ(c.output.settle_s, 0.2);
  EXPECT_DOUBLE_EQ(c.simDuration(), 1.5);
  EXPECT_TRUE(c.render.enabled);
  EXPECT_EQ(c.render.width, 320);
  EXPECT_EQ(c.render.height, 240);
  EXPECT_EQ(c.render.fps, 60);
  EXPECT_DOUBLE_EQ(c.render.slowmo, 2.0);
  EXPECT_DOUBLE_EQ(c.render.duration_s, 0.5);
  EXPECT_EQ(c.render.camera, RenderCamera::kPerspective);
  EXPECT_TRUE(c.render.shadows);
  EXPECT_TRUE(c.render.reflections);
  EXPECT_EQ(c.render.msaa, 4);
  EXPECT_FALSE(c.render.ghost);
  EXPECT_EQ(c.render.crf, 30);
  EXPECT_EQ(c.render.preset, "slow");

  const std::string q = write("exp.yaml", exp(std::string(kTraj) + "render: {}\n"));
  const ExperimentCase d = loadExperiment(q).cases.at(0);
  EXPECT_TRUE(d.render.enabled);  // presence alone asks for a video
  EXPECT_EQ(d.render.width, RenderSettings{}.width);
}

// render.size: the frame-size presets (render_settings.h), 1280x720 for talks.
TEST_F(LoaderTest, RenderSizePresetSetsWidthAndHeight) {
  const ExperimentCase hd = loadExperiment(write("hd.yaml", exp(std::string(kTraj) + "render: {size: 1280x720}\n"))).cases.at(0);
  EXPECT_EQ(hd.render.width, 1280);
  EXPECT_EQ(hd.render.height, 720);
  const ExperimentCase sd = loadExperiment(write("sd.yaml", exp(std::string(kTraj) + "render: {size: 640x480}\n"))).cases.at(0);
  EXPECT_EQ(sd.render.width, 640);
  EXPECT_EQ(sd.render.height, 480);
  expectError(exp(std::string(kTraj) + "render: {size: 1280x720, height: 480}\n"), 5, "render.size",
              "either size or width/height");
  expectError(exp(std::string(kTraj) + "render: {size: 1920x1080}\n"), 5, "render.size", "allowed: 640x480, 1280x720");
}

TEST_F(LoaderTest, RobotPathIsRelativeToTheExperimentFile) {
  const std::string p = write("sub/dir/exp.yaml", "name: t\nrobot: ../../robots/paper_quadruped.yaml\n" +
                                                      std::string(kTraj));
  const Experiment e = loadExperiment(p);
  EXPECT_EQ(e.cases[0].robot.numLinks(), 1);  // tail defaults to {links: 1}
  EXPECT_EQ(e.source_file, p);
}

// `robot: paper` is the packaged robot file, wherever the experiment is saved (README example).
TEST_F(LoaderTest, BuiltinRobotNameIsThePackagedFile) {
  const Experiment named = loadExperiment(write("far/away/exp.yaml", "name: t\nrobot: paper\n" + std::string(kTraj)));
  const Experiment path = loadExperiment(write("exp.yaml", exp(kTraj)));
  EXPECT_EQ(fs::path(named.cases[0].robot_file),
            fs::path(kSourceDir + "/configs/robots/paper_quadruped.yaml").lexically_normal());
  const RobotParams& a = named.cases[0].robot;
  const RobotParams& b = path.cases[0].robot;
  EXPECT_EQ(a.quadruped.mass_kg, b.quadruped.mass_kg);
  EXPECT_EQ(a.quadruped.d_Q2B_m, b.quadruped.d_Q2B_m);
  EXPECT_EQ(a.friction.mu_s, b.friction.mu_s);
  EXPECT_EQ(a.friction.mu_d, b.friction.mu_d);
  ASSERT_EQ(a.numLinks(), 1);
  EXPECT_EQ(a.tail[0].mass_kg, b.tail[0].mass_kg);
  // A value with '/' or '.' stays a path relative to the experiment file; a file named like a
  // built-in is not picked up by the name.
  write("paper", "not a robot file");
  EXPECT_EQ(loadExperiment(write("exp2.yaml", "name: t\nrobot: paper\n" + std::string(kTraj))).cases[0].robot_file,
            named.cases[0].robot_file);
  try {
    loadExperiment(write("exp3.yaml", "name: t\nrobot: ./paper\n" + std::string(kTraj)));
    ADD_FAILURE() << "./paper is the local (bad) file";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir_ / "paper").string() + ":", 0), 0u) << e.what();
  }
  expectError("name: t\n\nrobot: papr\n" + std::string(kTraj), 3, "robot",
              "unknown built-in robot 'papr' (built-in: paper)", "exp.yaml", 8);
}

// ---------------------------------------------------------------------------------------------
// Every kind of bad input: a ConfigError naming file:line, the dotted key and what is wrong.

TEST_F(LoaderTest, UnknownKeys) {
  expectError(exp(std::string(kTraj) + "colour: red\n"), 5, "colour", "unknown key", "exp.yaml", 1);
  expectError(exp(std::string(kTraj) + "quadruped:\n  mass: 3\n"), 6, "quadruped.mass", "allowed here: mass_kg");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, dT: 1}\n"), 4, "trajectory.dT", "unknown key", "exp.yaml",
              43);
  expectError(exp(std::string(kTraj) + "render: {resolution: 3}\n"), 5, "render.resolution", "unknown key");
  expectError(exp(std::string(kTraj) + "quadruped: {mass_kg: 1, mass_kg: 2}\n"), 5, "quadruped.mass_kg", "duplicate");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 1, lenght: 2}\n" + std::string(kTraj), 3,
              "tail.lenght", "unknown key");
}

TEST_F(LoaderTest, WrongTypes) {
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: abc}\n"), 4, "trajectory.dT_s", "expected a number, got 'abc'");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: \"0.25\"}\n"), 4, "trajectory.dT_s", "string");
  expectError(exp(std::string(kTraj) + "effects:\n  translation: abc\n"), 6, "effects.translation", "true or false");
  expectError(exp(std::string(kTraj) + "mujoco: {iterations: 2.5}\n"), 5, "mujoco.iterations", "integer");
  expectError(exp(std::string(kTraj) + "models: analytic\n"), 5, "models", "expected a list");
  expectError(exp("trajectory: 5\n"), 4, "trajectory", "expected a map");
  expectError(exp("trajectory:\n  dtheta_deg:\n  dT_s: 0.25\n"), 5, "trajectory.dtheta_deg", "empty");
  expectError("name: [a]\nrobot: robots/paper_quadruped.yaml\n" + std::string(kTraj), 1, "name", "expected a string");
}

TEST_F(LoaderTest, NonFiniteNumbers) {
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: .nan}\n"), 4, "trajectory.w_ss", "finite");
  expectError(exp("trajectory:\n  dtheta_deg: -.inf\n  dT_s: 0.25\n"), 5, "trajectory.dtheta_deg", "finite");
  expectError(exp(std::string(kTraj) + "quadruped: {izz_kgm2: .inf}\n"), 5, "quadruped.izz_kgm2", "finite");
}

TEST_F(LoaderTest, BadLinkCountsAndListLengths) {
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 0}\n" + std::string(kTraj), 3, "tail.links",
              "1..6");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 7}\n" + std::string(kTraj), 3, "tail.links",
              "1..6");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {custom: []}\n" + std::string(kTraj), 3,
              "tail.custom", "n >= 1");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 1, custom: []}\n" + std::string(kTraj), 3,
              "tail.custom", "not both");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 2}\n"
              "trajectory:\n  theta0_deg: [0, 10, 20]\n  dtheta_deg: -90\n  dT_s: 0.25\n",
              5, "trajectory.theta0_deg", "3 values but the tail has 2");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\nkind: pose\ntail: {links: 3}\npose: {theta_deg: [1, 2]}\n",
              5, "pose.theta_deg", "2 values but the tail has 3");
}

TEST_F(LoaderTest, TrajectoryRanges) {
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: 1.0}\n"), 4, "trajectory.w_ss", "(0, 1)");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: [0]}\n"), 4, "trajectory.w_ss[0]", "(0, 1)");
  expectError(exp("trajectory:\n  dtheta_deg: -90\n  dT_s: 0\n"), 6, "trajectory.dT_s", "> 0");
  expectError(exp("trajectory:\n  dtheta_deg: -90\n  dT_s: -0.1\n"), 6, "trajectory.dT_s", "> 0");
  expectError(exp("trajectory:\n  dtheta_deg: -90\n"), 4, "trajectory.dT_s", "dT_s or peak_speed_dps");
  expectError(exp("trajectory:\n  dtheta_deg: -90\n  dT_s: 1\n  peak_speed_dps: 100\n"), 7,
              "trajectory.peak_speed_dps", "not both");
  expectError(exp("trajectory:\n  dtheta_deg: 0\n  peak_speed_dps: 100\n"), 6, "trajectory.peak_speed_dps", "dT_s = 0");
  expectError(exp("trajectory:\n  dT_s: 1\n"), 4, "trajectory.dtheta_deg", "required");
  expectError(exp("trajectory:\n  dT_s: 1\n  dtheta_deg: -90\n  t0_s: -1\n"), 7, "trajectory.t0_s", ">= 0");
  expectError(exp("trajectory:\n  rule: eq25\n  thetadot_max_dps: 600\n  dtheta_deg: -90\n"), 7,
              "trajectory.dtheta_deg", "rule: eq25");
  expectError(exp("trajectory:\n  rule: eq25\n"), 4, "trajectory.thetadot_max_dps", "needs");
  expectError(exp("trajectory:\n  rule: eq26\n  thetadot_max_dps: 600\n"), 5, "trajectory.rule", "allowed: eq25");
  expectError(exp("trajectory:\n  rule: eq25\n  thetadot_max_radps: -1\n"), 6, "trajectory.thetadot_max_radps", "> 0");
  expectError(exp(""), 1, "trajectory", "required for kind: simulate");
  expectError(exp(std::string(kTraj) + "pose: {theta_deg: 0}\n"), 5, "pose", "kind: pose");
}

TEST_F(LoaderTest, BadRobotValues) {
  expectError(exp(std::string(kTraj) + "quadruped:\n  mass_kg: -1\n"), 6, "quadruped.mass_kg", "> 0");
  expectError(exp(std::string(kTraj) + "quadruped: {izz_kgm2: 0}\n"), 5, "quadruped.izz_kgm2", "> 0");
  expectError(exp(std::string(kTraj) + "friction:\n  mu_d: 0.3\n  mu_s: -0.1\n"), 7, "friction.mu_s", ">= 0");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\n"
              "tail:\n  custom:\n    - {mass_kg: 1, izz_kgm2: 0.01, length_m: 0.1}\n"
              "    - {mass_kg: 1, izz_kgm2: 0, length_m: 0.1}\n" +
                  std::string(kTraj),
              6, "tail.custom[1].izz_kgm2", "> 0");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\n"
              "tail: {custom: [{mass_kg: 1, izz_kgm2: 0.01, length_m: -0.1}]}\n" + std::string(kTraj),
              3, "tail.custom[0].length_m", "> 0");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\n"
              "tail: {custom: [{mass_kg: 0, izz_kgm2: 0.01, length_m: 0.1}]}\n" + std::string(kTraj),
              3, "tail.custom[0].mass_kg", "> 0");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\n"
              "tail: {custom: [{izz_kgm2: 0.01, length_m: 0.1}]}\n" + std::string(kTraj),
              3, "tail.custom[0].mass_kg", "required");
}

// trajectory: {family: spline, ...}: per joint a clamped cubic spline through its knots; the case
// keeps the knots (radians) and its resume key and resolved JSON include them.
TEST_F(LoaderTest, SplineTrajectory) {
  const std::string text =
      "name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 2}\n"
      "trajectory: {family: spline, knots_deg: [[30, 10, -40], [0, 20, 5, -15]], dT_s: [0.3, 0.4], t0_s: 0.05}\n";
  const Experiment e = loadExperiment(write("exp.yaml", text));
  ASSERT_EQ(e.cases.size(), 1u);
  const ExperimentCase& c = e.cases[0];
  EXPECT_TRUE(c.joints.empty());
  ASSERT_EQ(c.splines.size(), 2u);
  ASSERT_EQ(c.splines[0].knots_rad.size(), 3u);
  ASSERT_EQ(c.splines[1].knots_rad.size(), 4u);
  EXPECT_DOUBLE_EQ(c.splines[0].knots_rad[2], -40 * kDeg);
  EXPECT_DOUBLE_EQ(c.splines[1].knots_rad[1], 20 * kDeg);
  EXPECT_EQ(c.splines[1].dT_s, 0.4);
  EXPECT_EQ(c.splines[0].t0_s, 0.05);
  const TailTrajectory t = c.trajectory();
  ASSERT_EQ(t.joints.size(), 2u);
  EXPECT_TRUE(t.joints[1].isSpline());
  EXPECT_NEAR(t.joints[1].at(0.05 + 0.4 / 3).theta, 20 * kDeg, 1e-12);  // through its knot
  EXPECT_NEAR(t.endTime(), 0.45, 1e-12);
  // One list of knots for every joint.
  const Experiment same = loadExperiment(
      write("exp.yaml", "name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 2}\n"
                        "trajectory: {family: spline, knots_deg: [30, -30], dT_s: 0.3}\n"));
  ASSERT_EQ(same.cases[0].splines.size(), 2u);
  EXPECT_EQ(same.cases[0].splines[1].knots_rad, same.cases[0].splines[0].knots_rad);
  // The resolved case round-trips, and a different knot is a different resume key.
  const ExperimentCase back = caseFromResolved(resolvedJson(c));
  ASSERT_EQ(back.splines.size(), 2u);
  EXPECT_EQ(back.splines[1].knots_rad, c.splines[1].knots_rad);
  EXPECT_EQ(caseKeyText(back, false), caseKeyText(c, false));
  ExperimentCase other = c;
  other.splines[1].knots_rad[1] += 1e-9;
  EXPECT_NE(caseKeyText(other, false), caseKeyText(c, false));
  // A split-cycle case's resolved JSON has no "splines" (its resume key is unchanged).
  const Experiment sc = loadExperiment(write("exp.yaml", exp(kTraj)));
  EXPECT_FALSE(resolvedJson(sc.cases[0]).contains("splines"));
}

TEST_F(LoaderTest, BadSplineTrajectory) {
  const std::string head = "name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: 2}\n";
  expectError(head + "trajectory: {family: spline, knots_deg: [[30, 10], [0, 500]], dT_s: 0.3}\n", 4,
              "trajectory.knots_deg[1][1]", "must lie in [-360, 360] deg", "exp.yaml", 56);
  expectError(head + "trajectory: {family: spline, knots_deg: [[30, 10]], dT_s: 0.3}\n", 4, "trajectory.knots_deg",
              "has 1 knot lists but the tail has 2 joints");
  expectError(head + "trajectory: {family: spline, knots_deg: [30], dT_s: 0.3}\n", 4, "trajectory.knots_deg",
              "needs 2..64 knots");
  expectError(head + "trajectory: {family: spline, knots_deg: [30, 0], dT_s: 0.0001}\n", 4, "trajectory.dT_s",
              "must be >= 0.001 s");
  expectError(head + "trajectory: {family: spline, knots_deg: [30, 0]}\n", 4, "trajectory.dT_s", "required key is missing");
  expectError(head + "trajectory: {family: spline, knots_deg: [30, 0], dT_s: 0.3, w_ss: 0.2}\n", 4, "trajectory.w_ss",
              "not used with family: spline");
  expectError(head + "trajectory: {dtheta_deg: -90, dT_s: 0.25, knots_deg: [1, 2]}\n", 4, "trajectory.knots_deg",
              "only used with family: spline");
  expectError(head + "trajectory: {family: bezier, knots_deg: [1, 2], dT_s: 0.3}\n", 4, "trajectory.family");
}

TEST_F(LoaderTest, BadSettings) {
  expectError(exp(std::string(kTraj) + "output:\n  sample_dt_s: 0\n"), 6, "output.sample_dt_s", "> 0");
  // A grid with fewer than 2 rows (spacing longer than the 0.25 + 0.5 s run) is an error, not phi_net = 0.
  expectError(exp(std::string(kTraj) + "output:\n  sample_dt_s: 10\n"), 6, "output.sample_dt_s",
              "longer than the run (0.75 s)");
  expectError(exp(std::string(kTraj) + "output: {sample_dt_s: 0.2, duration_s: 0.1}\n"), 5, "output.sample_dt_s",
              "at least 2 rows");
  expectError(exp(std::string(kTraj) + "mujoco:\n  timestep_s: -1e-4\n"), 6, "mujoco.timestep_s", "> 0");
  expectError(exp(std::string(kTraj) + "mujoco: {condim: 2}\n"), 5, "mujoco.condim", "1, 3, 4, 6");
  expectError(exp(std::string(kTraj) + "mujoco: {body_height_m: 0.2}\n"), 5, "mujoco.body_height_m",
              "one key for both");
  expectError(exp(std::string(kTraj) + "quadruped: {com_height_m: 0}\n"), 5, "quadruped.com_height_m", "> 0");
  expectError(exp(std::string(kTraj) + "mujoco: {solref: [0.002]}\n"), 5, "mujoco.solref", "2 values");
  expectError(exp(std::string(kTraj) + "mujoco: {solimp: [0.9, 1.5, 0.001, 0.5, 2]}\n"), 5, "mujoco.solimp[1]", "(0, 1)");
}

TEST_F(LoaderTest, UnknownEnumValuesListTheAllowedOnes) {
  expectError(exp(std::string(kTraj) + "analytic:\n  solver: rk45\n"), 6, "analytic.solver", "allowed: adaptive, fixed");
  expectError(exp(std::string(kTraj) + "analytic: {coupling: loose}\n"), 5, "analytic.coupling", "allowed: paper, exact");
  expectError(exp(std::string(kTraj) + "mujoco: {integrator: RK45}\n"), 5, "mujoco.integrator",
              "allowed: Euler, RK4, implicit");
  expectError(exp(std::string(kTraj) + "effects: {friction: coulomb}\n"), 5, "effects.friction",
              "allowed: none, stiction, continuous");
  expectError(exp(std::string(kTraj) + "models: [analytic, adams]\n"), 5, "models[1]", "allowed: analytic, perfoot, mujoco");
  expectError(exp(std::string(kTraj) + "models: []\n"), 5, "models", "at least one");
  expectError(exp(std::string(kTraj) + "models: [mujoco, mujoco]\n"), 5, "models[1]", "twice");
  expectError(exp(std::string(kTraj) + "render: {camera: side}\n"), 5, "render.camera", "allowed: top, perspective");
  expectError(exp(std::string(kTraj) + "render: {preset: quick}\n"), 5, "render.preset", "allowed: ultrafast");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\nkind: replay\n" + std::string(kTraj), 3, "kind",
              "allowed: simulate, pose");
}

TEST_F(LoaderTest, MissingFilesAndRequiredKeys) {
  expectError("name: t\n\nrobot: robots/nothere.yaml\n" + std::string(kTraj), 3, "robot", "robot file not found",
              "exp.yaml", 8);
  expectError("robot: robots/paper_quadruped.yaml\n" + std::string(kTraj), 1, "name", "required");
  expectError("name: t\n" + std::string(kTraj), 1, "robot", "required");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntrajectory: {dtheta_deg: [-90, dT_s: 0.25}\n", 3, "",
              "YAML syntax error");
  EXPECT_THROW(loadExperiment((dir_ / "nothere.yaml").string()), ConfigError);
}

TEST_F(LoaderTest, ErrorsInsideTheRobotFileNameTheRobotFile) {
  const std::string good = "quadruped: {mass_kg: 8.458, izz_kgm2: 0.1916, d_Q2C_m: -0.0155, d_Q2B_m: 0.125, "
                           "l_F_m: 0.3, w_F_m: 0.26}\n"
                           "friction: {mu_s: 0.25, mu_d: 0.3, phidot_s_radps: 0.05, phidot_d_radps: 0.5, "
                           "v_s_mps: 0.05, v_d_mps: 0.5}\n"
                           "gravity_mps2: 9.81\n";
  const std::string experiment = "name: t\nrobot: robots/r.yaml\n" + std::string(kTraj);
  write("robots/r.yaml", good + "tails:\n  1: {mass_kg: 2.4, izz_kgm2: -0.02, length_m: 0.3}\n");
  expectError(experiment, 5, "tails.1.izz_kgm2", "> 0", "robots/r.yaml");
  write("robots/r.yaml", good + "tails:\n  1: {mass_kg: 2.4, izz_kgm2: 0.02, length_m: 0.3, colour: red}\n");
  expectError(experiment, 5, "tails.1.colour", "unknown key", "robots/r.yaml");
  write("robots/r.yaml", good + "tails:\n  7: {mass_kg: 2.4, izz_kgm2: 0.02, length_m: 0.3}\n");
  expectError(experiment, 5, "tails.7", "unknown key", "robots/r.yaml");
  write("robots/r.yaml", good);
  expectError(experiment, 1, "tails", "required", "robots/r.yaml");
  write("robots/r.yaml", "quadruped: {mass_kg: 8}\n" + good.substr(good.find("friction")) + "tails: {}\n");
  expectError(experiment, 1, "quadruped.izz_kgm2", "required", "robots/r.yaml");
  write("robots/r.yaml", good + "gravity: 9\ntails:\n  1: {mass_kg: 2.4, izz_kgm2: 0.02, length_m: 0.3}\n");
  expectError(experiment, 4, "gravity", "unknown key", "robots/r.yaml");
  write("robots/r.yaml", good + "tails:\n  1: {mass_kg: {sweep: [1, 2]}, izz_kgm2: 0.02, length_m: 0.3}\n");
  expectError(experiment, 5, "tails.1.mass_kg", "experiment files only", "robots/r.yaml");
  // A tail the robot file lacks: the error is at the experiment's links value.
  write("robots/r.yaml", good + "tails:\n  1: {mass_kg: 2.4, izz_kgm2: 0.02, length_m: 0.3}\n");
  expectError("name: t\nrobot: robots/r.yaml\ntail: {links: 2}\n" + std::string(kTraj), 3, "tail.links", "no tails.2");
  // The friction thresholds must be ordered (tailsim::validate), at the robot file's line.
  write("robots/r.yaml", good.substr(0, good.find("friction")) +
                             "friction:\n  mu_s: 0.25\n  mu_d: 0.3\n  phidot_s_radps: 0.5\n  phidot_d_radps: 0.05\n"
                             "  v_s_mps: 0.05\n  v_d_mps: 0.5\ngravity_mps2: 9.81\n"
                             "tails:\n  1: {mass_kg: 2.4, izz_kgm2: 0.02, length_m: 0.3}\n");
  expectError(experiment, 6, "friction.phidot_d_radps", "must exceed", "robots/r.yaml");
  // Overridden in the experiment: the error moves to the experiment file.
  expectError(exp(std::string(kTraj) + "friction: {phidot_d_radps: 0.01}\n"), 5, "friction.phidot_d_radps",
              "must exceed");
}

TEST_F(LoaderTest, BadSweepsAndRanges) {
  // The bad value is the second sweep element, on its own line: that line is named.
  expectError(exp("trajectory:\n  dtheta_deg: -90\n  dT_s:\n    sweep:\n      - 0.1\n      - -0.2\n"), 9,
              "trajectory.dT_s", "> 0", "exp.yaml", 9);
  expectError(exp("trajectory:\n  dtheta_deg: -90\n  dT_s: 0.1\n  w_ss: {sweep: [0.5, 0.7, abc]}\n"), 7,
              "trajectory.w_ss", "expected a number, got 'abc'", "exp.yaml", 28);
  // A range with bad values: the range node is named.
  expectError(exp("trajectory:\n  dtheta_deg: -90\n  dT_s: 0.1\n  w_ss: {range: [0.5, 1.5, 0.5]}\n"), 7,
              "trajectory.w_ss", "(0, 1)");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {range: [0, 1, -0.1]}}\n"), 5, "output.settle_s",
              "moves away");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {range: [0, 1, 0]}}\n"), 5, "output.settle_s", "step");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {range: [0, 1, 1e-5]}}\n"), 5, "output.settle_s",
              "more than 10000");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {range: [0, 1]}}\n"), 5, "output.settle_s",
              "[start, stop, step]");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {sweep: []}}\n"), 5, "output.settle_s", "non-empty");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {sweep: [1, 1]}}\n"), 5, "output.settle_s", "twice");
  expectError(exp(std::string(kTraj) + "output: {settle_s: {sweep: [1], step: 2}}\n"), 5, "output.settle_s",
              "no other keys");
  expectError(exp(std::string(kTraj) + "quadruped: {sweep: [1, 2]}\n"), 5, "quadruped", "single value");
  expectError(exp(std::string(kTraj) + "effects: {gravity: {range: [0, 1, 1]}}\n"), 5, "effects.gravity",
              "true or false");
  expectError("name: {sweep: [a, b]}\nrobot: robots/paper_quadruped.yaml\n" + std::string(kTraj), 1, "name",
              "cannot be swept");
  // Per-joint lengths are checked per case: links = 2 breaks the 1-element list.
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail: {links: {sweep: [1, 2]}}\n"
              "trajectory: {dtheta_deg: [-90], dT_s: 0.25}\n",
              4, "trajectory.dtheta_deg", "1 values but the tail has 2");
}

// ---------------------------------------------------------------------------------------------

TEST_F(LoaderTest, SuiteLoadsEveryExperimentInOrder) {
  write("paper/fig07.yaml", "name: fig07\nrobot: ../robots/paper_quadruped.yaml\n" + std::string(kTraj));
  write("paper/more/fig09.yaml", "name: fig09\nrobot: ../../robots/paper_quadruped.yaml\n"
                                 "trajectory: {theta0_deg: {sweep: [0, 30, 60, 90]}, dtheta_deg: -90, dT_s: 0.25}\n");
  write("paper/sub.yaml", "experiments: [more/fig09.yaml]\n");
  const std::string all = write("paper/all.yaml", "description: all figures\nexperiments:\n  - fig07.yaml\n  - sub.yaml\n");
  const std::vector<Experiment> s = loadExperimentSuite(all);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "fig07");
  EXPECT_EQ(s[0].cases.size(), 1u);
  EXPECT_EQ(s[1].name, "fig09");
  EXPECT_EQ(s[1].cases.size(), 4u);
  EXPECT_EQ(s[1].source_file, (dir_ / "paper/more/fig09.yaml").string());
  EXPECT_EQ(s[1].cases[0].source_file, s[1].source_file);

  // A normal experiment file is a suite of one.
  const std::vector<Experiment> one = loadExperimentSuite((dir_ / "paper/fig07.yaml").string());
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].name, "fig07");

  // loadExperiment refuses a suite file.
  EXPECT_THROW(loadExperiment(all), ConfigError);
}

TEST_F(LoaderTest, SuiteErrors) {
  write("a.yaml", "name: a\nrobot: robots/paper_quadruped.yaml\n" + std::string(kTraj));
  auto expectSuiteError = [&](const std::string& text, const std::string& file, int line, const std::string& what) {
    const std::string p = write("all.yaml", text);
    try {
      loadExperimentSuite(p);
      ADD_FAILURE() << "no ConfigError for suite:\n" << text;
    } catch (const ConfigError& e) {
      const std::string prefix = (dir_ / file).string() + ":" + std::to_string(line) + ":";
      EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expectSuiteError("experiments:\n  - a.yaml\n  - b.yaml\n", "all.yaml", 3, "not found");
  expectSuiteError("experiments:\n  - a.yaml\n  - a.yaml\n", "all.yaml", 3, "already used");
  expectSuiteError("experiments: []\n", "all.yaml", 1, "at least one");
  expectSuiteError("experiments: [all.yaml]\n", "all.yaml", 1, "includes itself");
  expectSuiteError("experiments: [a.yaml]\nname: x\n", "all.yaml", 2, "unknown key");
  // An error inside a listed experiment names that experiment's file.
  write("bad.yaml", "name: bad\nrobot: robots/paper_quadruped.yaml\ntrajectory: {dtheta_deg: -90, dT_s: -1}\n");
  expectSuiteError("experiments: [a.yaml, bad.yaml]\n", "bad.yaml", 3, "trajectory.dT_s");
}

// Counts that overflowed a float-to-integer conversion (0 rows, phi_net 0,
// ok) are refused at load, at the key that makes them.
TEST_F(LoaderTest, Finding5OverflowingCountsAreRefusedAtLoad) {
  expectError(exp(std::string(kTraj) + "output: {sample_dt_s: 1e-20}\n"), 5, "output.sample_dt_s", "rows");
  expectError(exp(std::string(kTraj) + "output: {duration_s: 1e300}\n"), 5, "output.duration_s", "rows");
  expectError(exp(std::string(kTraj) + "output:\n  settle_s: 1e300\n"), 6, "output.settle_s", "rows");
  expectError(exp(std::string(kTraj) + "models: [mujoco]\nrender: {slowmo: 1e300}\n"), 6, "render.slowmo", "must lie in");
  // Inside the slowmo range, the frame count (sim time x fps x slowmo) is the limit that refuses.
  expectError(exp(std::string(kTraj) + "models: [mujoco]\nrender: {slowmo: 1000, fps: 240}\n"), 6, "render.slowmo", "frames");
}

// Accepted values that never finished or exhausted memory are refused at
// load with file:line:col at the offending key; the limits' own edges and the paper's extremes load.
TEST_F(LoaderTest, Finding7UnboundedWorkIsRefusedAtLoad) {
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 1e-9}\n"), 4, "trajectory.dT_s", ">= 0.001 s");
  expectError(exp("trajectory: {dtheta_deg: -90, peak_speed_dps: 1e9}\n"), 4, "trajectory.peak_speed_dps", "shorter");
  expectError(exp("trajectory: {rule: eq25, thetadot_max_dps: 1e9}\n"), 4, "trajectory.thetadot_max_dps", "shorter");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: 1e-8}\n"), 4, "trajectory.w_ss", "[0.01, 0.99]");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: 0.99999999}\n"), 4, "trajectory.w_ss");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, t0_s: 1e300}\n"), 4, "trajectory.t0_s", "rows");
  expectError(exp("trajectory: {dtheta_deg: -90, dT_s: 0.25, t0_s: 1e5}\noutput: {sample_dt_s: 1}\n"), 4,
              "trajectory.t0_s", "analytic model would take at least");
  expectError(exp(std::string(kTraj) + "analytic: {max_step_s: 5e-324}\n"), 5, "analytic.max_step_s", "steps");
  expectError(exp(std::string(kTraj) + "analytic: {solver: fixed, fixed_dt_s: 1e-12}\n"), 5, "analytic.fixed_dt_s");
  expectError(exp(std::string(kTraj) + "models: [mujoco]\nmujoco: {settle_s: 1e300}\n"), 6, "mujoco.settle_s",
              "MuJoCo would take");
  expectError(exp(std::string(kTraj) + "models: [mujoco]\nmujoco: {timestep_s: 1e-9}\n"), 6, "mujoco.timestep_s");
  expectError(exp(std::string(kTraj) + "output: {sample_dt_s: 1e-7}\n"), 5, "output.sample_dt_s", "1e+06 rows");
  expectError(exp(std::string(kTraj) + "output: {duration_s: 1e9}\n"), 5, "output.duration_s");
  // A sweep value is reported at the value itself.
  expectError(exp(std::string(kTraj) + "output: {sample_dt_s: {sweep: [1e-3, 1e-12]}}\n"), 5, "output.sample_dt_s");
  // Inside the limits: the paper's and the tests' extremes.
  const Experiment ok = loadExperiment(write(
      "ok.yaml", exp("trajectory: {dtheta_deg: -3600, theta0_deg: 360, dT_s: {sweep: [0.001, 0.05]}, "
                     "w_ss: {sweep: [0.01, 0.02, 0.98, 0.99]}}\nmodels: [analytic, mujoco]\n")));
  EXPECT_EQ(ok.cases.size(), 8u);
}

// Angles and masses are bounded at load (dtheta -1e300 deg gave NaN
// loads reported ok; a 1e-6 kg body disagreed between the models).
TEST_F(LoaderTest, Finding6AnglesAndMassesAreBoundedAtLoad) {
  expectError(exp("trajectory: {dtheta_deg: -1e300, dT_s: 0.25}\n"), 4, "trajectory.dtheta_deg", "[-3600, 3600]");
  expectError(exp("trajectory: {theta0_deg: 400, dtheta_deg: -90, dT_s: 0.25}\n"), 4, "trajectory.theta0_deg",
              "[-360, 360]");
  expectError(exp(std::string(kTraj) + "quadruped: {mass_kg: 1e-6}\n"), 5, "quadruped.mass_kg", "[0.001, 10000] kg");
  expectError("name: t\nrobot: robots/paper_quadruped.yaml\ntail:\n  custom:\n"
              "    - {mass_kg: 1e9, izz_kgm2: 0.01, length_m: 0.3}\n" + std::string(kTraj),
              5, "tail.custom[0].mass_kg", "kg");
}

// Every config shipped in the repository loads.
TEST(ShippedConfigs, AllLoad) {
  const fs::path configs = fs::path(kSourceDir) / "configs";
  int loaded = 0;
  for (const auto& entry : fs::recursive_directory_iterator(configs)) {
    if (entry.path().extension() != ".yaml") continue;
    if (entry.path().parent_path().filename() == "robots") continue;
    {  // kind: optimize files (configs/design) are read by src/design: tests/test_design.cc
      std::ifstream in(entry.path());
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (text.find("\nkind: optimize\n") != std::string::npos) continue;
      if (text.find("\nkind: maneuver\n") != std::string::npos) continue;  // tests/test_maneuver.cc
    }
    try {
      loadExperimentSuite(entry.path().string());
    } catch (const ConfigError& e) {
      ADD_FAILURE() << e.what();
    }
    ++loaded;
  }
  EXPECT_GE(loaded, 1);
}

// A robot given by its size (issue 34, item 3): a uniform box; the explicit numbers derived from it.
TEST_F(LoaderTest, RobotGivenByItsSize) {
  write("robots/box.yaml",
        "quadruped: {mass_kg: 12, size_m: [0.5, 0.3, 0.2], foot_inset_m: 0.03}\n"
        "friction: {mu_s: 0.5, mu_d: 0.4}\n"
        "gravity_mps2: 9.81\n"
        "tails:\n  1: {mass_kg: 1.2, izz_kgm2: 0.025, length_m: 0.5}\n");
  const std::string head = "name: t\nrobot: robots/box.yaml\ntail: {links: 1}\n";
  const ExperimentCase c = loadExperiment(write("exp.yaml", head + kTraj)).cases.at(0);
  const QuadrupedParams& q = c.robot.quadruped;
  EXPECT_DOUBLE_EQ(q.mass_kg, 12.0);
  EXPECT_NEAR(q.izz_kgm2, 12.0 * (0.25 + 0.09) / 12.0, 1e-15);  // m (l^2 + w^2) / 12
  EXPECT_NEAR(q.l_F_m, 0.44, 1e-15);
  EXPECT_NEAR(q.w_F_m, 0.24, 1e-15);
  EXPECT_EQ(q.d_Q2C_m, 0.0);
  EXPECT_NEAR(q.d_Q2B_m, 0.25, 1e-15);
  EXPECT_NEAR(q.com_height_m, 0.1, 1e-15);
  EXPECT_NEAR(c.mujoco.body_height_m, 0.1, 1e-15);  // one COM-height key
  // The experiment's size_m without mass_kg keeps the file's mass; the inset defaults to 0.02 m.
  const ExperimentCase d =
      loadExperiment(write("exp.yaml", head + kTraj + "quadruped: {size_m: [0.6, 0.3, 0.2]}\n")).cases.at(0);
  EXPECT_NEAR(d.robot.quadruped.izz_kgm2, 12.0 * (0.36 + 0.09) / 12.0, 1e-15);
  EXPECT_NEAR(d.robot.quadruped.l_F_m, 0.6 - 2 * QuadrupedBox{}.foot_inset_m, 1e-15);
  // On the paper robot (explicit numbers) too.
  const ExperimentCase e =
      loadExperiment(write("exp.yaml", exp(std::string(kTraj) + "quadruped: {mass_kg: 10, size_m: [0.4, 0.2, 0.3]}\n")))
          .cases.at(0);
  EXPECT_NEAR(e.robot.quadruped.izz_kgm2, 10.0 * (0.16 + 0.04) / 12.0, 1e-15);
  EXPECT_NEAR(e.robot.quadruped.com_height_m, 0.15, 1e-15);

  expectError(exp(std::string(kTraj) + "quadruped: {size_m: [0.4, 0.2, 0.3], izz_kgm2: 0.2}\n"), 5,
              "quadruped.izz_kgm2", "not both: size_m sets izz_kgm2");
  expectError(exp(std::string(kTraj) + "quadruped: {foot_inset_m: 0.01}\n"), 5, "quadruped.foot_inset_m",
              "only used with size_m");
  expectError(exp(std::string(kTraj) + "quadruped: {size_m: [0.4, 0.2, 0.3], foot_inset_m: 0.1}\n"), 5,
              "quadruped.foot_inset_m", "less than half");
  expectError(exp(std::string(kTraj) + "quadruped: {size_m: [0.4, 0, 0.3]}\n"), 5, "quadruped.size_m", "> 0");
  expectError(exp(std::string(kTraj) + "quadruped: {size_m: [0.4, 0.3]}\n"), 5, "quadruped.size_m", "3 values");
  // A robot file of explicit numbers still needs every one of them.
  write("robots/short.yaml",
        "quadruped: {mass_kg: 12, izz_kgm2: 0.3, d_Q2C_m: 0, d_Q2B_m: 0.2, l_F_m: 0.4}\n"
        "friction: {mu_s: 0.5, mu_d: 0.4}\ngravity_mps2: 9.81\n"
        "tails:\n  1: {mass_kg: 1.2, izz_kgm2: 0.025, length_m: 0.5}\n");
  try {
    loadExperiment(write("exp.yaml", "name: t\nrobot: robots/short.yaml\n" + std::string(kTraj)));
    ADD_FAILURE() << "no error for a robot file without w_F_m";
  } catch (const ConfigError& x) {
    EXPECT_NE(std::string(x.what()).find("short.yaml:1:1: quadruped.w_F_m: required key is missing (or give the size"),
              std::string::npos)
        << x.what();
  }
}

// The continuous law's thresholds are needed only when that law is used (issue 34, item 3).
TEST_F(LoaderTest, ContinuousThresholdsOnlyWithThatLaw) {
  write("robots/plain.yaml",
        "quadruped: {mass_kg: 12, size_m: [0.5, 0.3, 0.2]}\n"
        "friction: {mu_s: 0.5, mu_d: 0.4}\n"
        "gravity_mps2: 9.81\n"
        "tails:\n  1: {mass_kg: 1.2, izz_kgm2: 0.025, length_m: 0.5}\n");
  const std::string head = std::string("name: t\nrobot: robots/plain.yaml\ntail: {links: 1}\n") + kTraj;
  EXPECT_NO_THROW(loadExperiment(write("exp.yaml", head)));
  expectError(head + "effects: {friction: continuous}\n", 5, "effects.friction",
              "the continuous law needs friction.phidot_s_radps");
  expectError(head + "effects: {friction: continuous}\nfriction: {phidot_s_radps: 0.1, phidot_d_radps: 1}\n", 5,
              "effects.friction", "needs friction.v_s_mps");
  EXPECT_NO_THROW(loadExperiment(write(
      "exp.yaml", head + "effects: {friction: continuous, translation: false}\n"
                         "friction: {phidot_s_radps: 0.1, phidot_d_radps: 1}\n")));
  const ExperimentCase c = loadExperiment(write(
      "exp.yaml", head + "effects: {friction: continuous}\n"
                         "friction: {phidot_s_radps: 0.1, phidot_d_radps: 1, v_s_mps: 0.02, v_d_mps: 0.2}\n")).cases.at(0);
  EXPECT_DOUBLE_EQ(c.robot.friction.v_d_mps, 0.2);
}


// No input names a program to run: `render.ffmpeg` was a file key, and an experiment with
// `ffmpeg: ./evil.sh` (or a result folder's experiment.yaml, or tailsim.simulate(render=...)) ran that
// program. The encoder is ffmpeg on PATH, the user's choice; the key is refused at file:line:col.
using NoInputTextReachesAnInterpreterUnescaped = LoaderTest;
TEST_F(NoInputTextReachesAnInterpreterUnescaped, NoFileNamesAProgramToRun) {
  for (const char* v : {"./evil.sh", "/bin/sh", "sh", "ffmpeg"})
    expectError(exp(std::string(kTraj) + "render: {width: 64, height: 48, ffmpeg: " + v + "}\n"), 5, "render.ffmpeg",
                "unknown key");
  EXPECT_EQ(loadExperiment(write("ok.yaml", exp(std::string(kTraj) + "render: {width: 64, height: 48}\n")))
                .cases.at(0)
                .render.ffmpeg,
            "ffmpeg");
  // The Python keyword path builds its text for the same loader: refused there too.
  const std::string text = simulateExperimentText(
      "paper", nlohmann::ordered_json{{"dtheta_deg", -90}, {"dT_s", 0.25}}, "analytic",
      nlohmann::ordered_json{{"render", {{"ffmpeg", "/tmp/evil.sh"}}}});
  try {
    loadExperimentText(text, "<tailsim.simulate>");
    ADD_FAILURE() << "render.ffmpeg accepted from tailsim.simulate";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("render.ffmpeg: unknown key"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tailsim
