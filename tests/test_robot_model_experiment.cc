// A robot from its MuJoCo model file inside an experiment (`robot: {mjcf: PATH, ...}`,
// docs/your-robot.md "Experiments"): the loader's keys and errors (file, line and key, before any
// work), the derivation once per experiment before any case runs, and `tailsim run`'s three
// models with the articulated MuJoCo robot. The Menagerie models are read where the shared folder
// is (shared/robots/menagerie beside the source tree or beside one of its parents); the
// repository ships none.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <set>
#include <string>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/robot_compare.h"
#include "experiments/robot_model_cases.h"
#include "models/mujoco/robot_import.h"
#include "plotting/plots.h"
#include "plotting/result_folder.h"
#include "plotting/style.h"
#include "menagerie_models.h"
#include "series_compare.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

using tailsim_test::menagerieDir;

using tailsim_test::Scratch;

// A 10 kg box on four sphere feet; `key` its keyframe element ("" for none), `extra` more feet or geoms.
std::string boxRobot(const std::string& key, const std::string& feet = "") {
  const std::string fourFeet = feet.empty() ? R"(
      <geom name="f1" type="sphere" size="0.02" pos="0.2 0.12 -0.28"/>
      <geom name="f2" type="sphere" size="0.02" pos="0.2 -0.12 -0.28"/>
      <geom name="f3" type="sphere" size="0.02" pos="-0.2 -0.12 -0.28"/>
      <geom name="f4" type="sphere" size="0.02" pos="-0.2 0.12 -0.28"/>)"
                                            : feet;
  return R"(<mujoco model="box">
  <worldbody>
    <body name="trunk" pos="0 0 0.3">
      <freejoint/>
      <inertial pos="0 0 0" mass="10" diaginertia="0.1 0.2 0.25"/>
      <geom name="body_box" type="box" size="0.25 0.15 0.05"/>)" +
         fourFeet + R"(
    </body>
  </worldbody>
  )" + key + R"(
</mujoco>
)";
}
const char* kHome = R"(<keyframe><key name="home" qpos="0 0 0.3 1 0 0 0"/></keyframe>)";

std::string experiment(const std::string& robot, const std::string& tail = "{mount: {pos_m: [-0.25, 0, 0]}, links: 1}") {
  return "name: box_tail\nrobot: " + robot + "\ntail: " + tail +
         "\ntrajectory: {rule: eq25, thetadot_max_dps: 600}\nmodels: [analytic, perfoot, mujoco]\n"
         "output: {settle_s: 1.0, time_series: none}\n";
}

// The ConfigError of loading (and deriving) an experiment file, "" if none.
std::string errorOf(const std::string& path) {
  try {
    std::vector<Experiment> s = loadExperimentSuite(path);
    resolveRobotModels(s);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// "<file>:<line>:<col>: <key>: " at the start of a message.
void expectAt(const std::string& msg, const std::string& file, int line, const std::string& key) {
  const std::string head = file + ":" + std::to_string(line) + ":";
  EXPECT_EQ(msg.rfind(head, 0), 0u) << msg;
  EXPECT_NE(msg.find(": " + key + ": "), std::string::npos) << msg;
}

}  // namespace

// The loader reads the keys without MuJoCo: nothing is derived until resolveRobotModels.
TEST(RobotModelExperiment, LoaderReadsTheKeysAndDerivesNothing) {
  Scratch t("robot_model_exp");
  t.write("box.xml", boxRobot(kHome));
  const std::string f = t.write(
      "e.yaml", experiment("{mjcf: box.xml, mu: 0.4, stance: {keyframe: home, joints_deg: {}}, feet: [f1, f2, f3, f4]}"));
  // joints_deg: {} is an error (at least one joint, or leave it out)
  expectAt(errorOf(f), f, 2, "robot.stance.joints_deg");
  t.write("e.yaml", experiment("{mjcf: box.xml, mu: 0.4, stance: {keyframe: home}, feet: [f1, f2, f3, f4]}",
                               "{mount: {pos_m: [-0.25, 0, 0], yaw_deg: 0}, links: 2}") +
                        "trajectory_unused: 1\n");
  EXPECT_NE(errorOf(f).find("trajectory_unused: unknown key"), std::string::npos);
  t.write("e.yaml", experiment("{mjcf: box.xml, mu: {sweep: [0.4, 0.6]}, stance: {keyframe: home}, feet: [f1, f2, f3, f4]}",
                               "{mount: {pos_m: [-0.25, 0, 0]}, links: 2}"));
  std::vector<Experiment> s = loadExperimentSuite(f);
  ASSERT_EQ(s.front().cases.size(), 2u);
  const ExperimentCase& c = s.front().cases.front();
  ASSERT_TRUE(c.robot_model.has_value());
  EXPECT_EQ(c.robot_model->file, (t.dir / "box.xml").string());
  EXPECT_EQ(c.robot_model->keyframe, "home");
  EXPECT_EQ(c.robot_model->mu, 0.4);
  EXPECT_EQ(c.robot_model->feet.size(), 4u);
  EXPECT_EQ(c.robot_model_links, 2);
  EXPECT_FALSE(c.robot_derived);
  resolveRobotModels(s);
  const ExperimentCase& d = s.front().cases.front();
  ASSERT_TRUE(d.robot_derived);
  EXPECT_NEAR(d.robot.quadruped.mass_kg, 10.0, 1e-12);
  EXPECT_NEAR(d.robot.quadruped.d_Q2B_m, 0.25, 1e-4);
  EXPECT_EQ(d.robot.friction.mu_s, 0.4);
  EXPECT_EQ(s.front().cases[1].robot.friction.mu_s, 0.6);
  ASSERT_EQ(d.robot.tail.size(), 2u);  // 10 % of the mass, one body length, over 2 links
  EXPECT_NEAR(d.robot.tail[0].mass_kg, 0.5, 1e-12);
  EXPECT_NEAR(d.robot.tail[0].length_m, 0.5 * d.robot.quadruped.l_F_m, 1e-12);
  EXPECT_EQ(d.mujoco.body_height_m, d.robot.quadruped.com_height_m);
  // `tailsim robot EXP.yaml`: the derived robot and the tail of the first case.
  const std::string shown = describeYamlRobot(f);
  EXPECT_NE(shown.find("quadruped.mass_kg       10 "), std::string::npos) << shown;
  EXPECT_NE(shown.find("friction.mu_s = mu_d    0.4 "), std::string::npos) << shown;
  EXPECT_NE(shown.find("link 2: mass_kg 0.5,"), std::string::npos) << shown;
}

// Each error: a ConfigError naming the experiment file, the line and the key, before any case runs.
TEST(RobotModelExperiment, ErrorsNameFileLineAndKey) {
  Scratch t("robot_model_exp");
  t.write("box.xml", boxRobot(kHome));
  t.write("nokey.xml", boxRobot(""));
  t.write("three.xml", boxRobot(kHome, R"(
      <geom name="f1" type="sphere" size="0.02" pos="0.2 0.12 -0.28"/>
      <geom name="f2" type="sphere" size="0.02" pos="0.2 -0.12 -0.28"/>
      <geom name="f3" type="sphere" size="0.02" pos="-0.2 0 -0.28"/>)"));
  const std::string f = (t.dir / "e.yaml").string();
  auto run = [&](const std::string& robot, const std::string& tail = "{mount: {pos_m: [-0.25, 0, 0]}, links: 1}") {
    t.write("e.yaml", experiment(robot, tail));
    return errorOf(f);
  };
  // The model file: missing, a folder, a device, a FIFO, a control character in its path.
  std::string m = run("{mjcf: nothere.xml}");
  expectAt(m, f, 2, "robot.mjcf");
  EXPECT_NE(m.find("model file not found: " + (t.dir / "nothere.xml").string()), std::string::npos) << m;
  fs::create_directories(t.dir / "adir");
  m = run("{mjcf: adir}");
  expectAt(m, f, 2, "robot.mjcf");
  EXPECT_NE(m.find("is not a regular file"), std::string::npos) << m;
  m = run("{mjcf: /dev/zero}");
  expectAt(m, f, 2, "robot.mjcf");
  EXPECT_NE(m.find("is not a regular file"), std::string::npos) << m;
  ASSERT_EQ(::mkfifo((t.dir / "fifo.xml").c_str(), 0600), 0);
  m = run("{mjcf: fifo.xml}");
  expectAt(m, f, 2, "robot.mjcf");
  EXPECT_NE(m.find("is not a regular file"), std::string::npos) << m;
  m = run("{mjcf: \"box\\n.xml\"}");
  expectAt(m, f, 2, "robot.mjcf");
  EXPECT_NE(m.find("control character"), std::string::npos) << m;
  // Keys the model derives are not keys; a mount without a model file is refused.
  t.write("e.yaml", experiment("{mjcf: box.xml}") + "quadruped: {mass_kg: 3}\n");
  m = errorOf(f);
  expectAt(m, f, 7, "quadruped");
  EXPECT_NE(m.find("derived from the model file"), std::string::npos) << m;
  m = run("paper");
  expectAt(m, f, 3, "tail.mount");
  // No stance: no `home` keyframe and none given.
  m = run("{mjcf: nokey.xml}");
  expectAt(m, f, 2, "robot");
  EXPECT_NE(m.find("no stance: the model has no `home` keyframe"), std::string::npos) << m;
  m = run("{mjcf: box.xml, stance: {keyframe: crouch}}");
  expectAt(m, f, 2, "robot.stance");
  EXPECT_NE(m.find("no keyframe named 'crouch'"), std::string::npos) << m;
  // Unknown mount body.
  m = run("{mjcf: box.xml}", "{mount: {body: tailbone, pos_m: [-0.25, 0, 0]}, links: 1}");
  expectAt(m, f, 3, "tail.mount.body");
  EXPECT_NE(m.find("no body named 'tailbone'"), std::string::npos) << m;
  // 3 feet (named, or standing): only the articulated MuJoCo model runs on them, so asking the planar
  // models is an error naming the feet; an unknown foot geom.
  m = run("{mjcf: box.xml, feet: [f1, f2, f3]}");  // f4 stands too: named feet are the ones standing
  expectAt(m, f, 2, "robot.feet");
  EXPECT_NE(m.find("feet: 'f4' also touches the floor after standing but is not named"), std::string::npos) << m;
  m = run("{mjcf: box.xml, feet: [f1, f2, f3, body_box]}");
  expectAt(m, f, 2, "robot.feet");
  EXPECT_NE(m.find("feet: 'body_box' does not touch the floor after standing"), std::string::npos) << m;
  m = run("{mjcf: three.xml}");
  expectAt(m, f, 2, "robot.mjcf");
  EXPECT_NE(m.find("models: analytic cannot run this robot: the robot stands on 3 feet"), std::string::npos) << m;
  EXPECT_NE(m.find("(models: [mujoco])"), std::string::npos) << m;
  m = run("{mjcf: box.xml, feet: [f1, f2, f3, toe]}");
  expectAt(m, f, 2, "robot.feet");
  EXPECT_NE(m.find("no geom or body named 'toe'"), std::string::npos) << m;
  // Commands whose MuJoCo run is the rigid box or changes its settings refuse it (trust, accuracy, mjcf).
  t.write("e.yaml", experiment("{mjcf: box.xml}"));
  try {
    refuseRobotModels(loadExperimentSuite(f), "trust");
    ADD_FAILURE() << "tailsim trust took a robot from its model file";
  } catch (const ConfigError& e) {
    expectAt(e.what(), f, 2, "robot.mjcf");
    EXPECT_NE(std::string(e.what()).find("`tailsim trust` does not take a robot from its model file"), std::string::npos);
  }
  // A tail base in front of the COM.
  m = run("{mjcf: box.xml}", "{mount: {pos_m: [0.25, 0, 0]}, links: 1}");
  expectAt(m, f, 3, "tail.mount.pos_m");
}

// The headline: an experiment on Go1 runs the three models, the MuJoCo one the articulated robot
// with the tail (phi_net equal to `tailsim robot --compare`'s for the same stroke), and the result
// folder keeps the model and the derived values, so it runs again on its own.
TEST(RobotModelExperiment, Go1ExperimentRunsTheThreeModelsArticulated) {
  const fs::path men = menagerieDir();
  if (men.empty()) GTEST_SKIP() << "no shared/robots/menagerie beside the source tree or its parents";
  Scratch t("robot_model_exp");
  const fs::path go1 = men / "go1" / "go1.xml";
  const std::string rel = fs::relative(go1, t.dir).string();
  const std::string f = t.write(
      "go1_tail.yaml", "name: go1_tail\nrobot: {mjcf: " + rel + "}\ntail: {mount: {pos_m: [-0.2, 0, 0]}, links: 1}\n"
                       "trajectory: {rule: eq25, thetadot_max_dps: {sweep: [600, 400]}}\n"
                       "models: [analytic, perfoot, mujoco]\noutput: {settle_s: 1.0, sample_dt_s: 0.01}\n");
  std::vector<Experiment> suite = loadExperimentSuite(f);
  resolveRobotModels(suite);
  ASSERT_EQ(suite.front().cases.size(), 2u);
  // One derivation for the experiment's cases.
  EXPECT_EQ(suite.front().cases[0].robot_derived.get(), suite.front().cases[1].robot_derived.get());
  RunOptions o;
  o.out_dir = (t.dir / "out").string();
  o.threads = 1;
  o.progress = false;
  runSuite(suite, o);

  RobotModelSpec spec;
  spec.file = go1.string();
  spec.mount.pos_m = {-0.2, 0.0, 0.0};
  RobotTailChoice choice;  // 1 link, 10 %, l_F, Eq. 25 at 600 deg/s, 2 s standing, 1 s after
  const RobotComparison cmp = compareRobotModels(spec, choice);

  std::ifstream in(t.dir / "out" / "summary.json");
  const nlohmann::json sum = nlohmann::json::parse(in);
  const nlohmann::json* base = nullptr;
  for (const auto& c : sum.at("cases"))
    if (c.at("sweep").at("trajectory.thetadot_max_dps") == "600") base = &c;
  ASSERT_TRUE(base);
  for (const char* m : {"analytic", "perfoot", "mujoco"}) EXPECT_TRUE(base->at("runs").at(m).at("ok").get<bool>()) << m;
  const double art = base->at("runs").at("mujoco").at("phi_net_deg").get<double>();
  std::printf("go1 articulated phi_net: run %.6f deg, --compare %.6f deg\n", art, cmp.articulated.phi_net_deg);
  EXPECT_EQ(art, cmp.articulated.phi_net_deg);
  EXPECT_EQ(base->at("runs").at("perfoot").at("phi_net_deg").get<double>(), cmp.rows[2].phi_net_deg);
  EXPECT_EQ(base->at("runs").at("analytic").at("phi_net_deg").get<double>(), cmp.rows[3].phi_net_deg);

  // result.json: the derived values and where each came from; the folder keeps the model.
  std::ifstream rj(t.dir / "out" / "cases" / base->at("dir").get<std::string>() / "result.json");
  const nlohmann::json res = nlohmann::json::parse(rj);
  const nlohmann::json& rm = res.at("resolved").at("robot_model");
  ASSERT_TRUE(rm.contains("derived"));
  EXPECT_EQ(rm.at("derived").at(0).at("key"), "quadruped.mass_kg");
  EXPECT_NE(rm.at("derived").at(0).at("source").get<std::string>().find("body_subtreemass"), std::string::npos);
  EXPECT_EQ(res.at("resolved").at("quadruped").at("mass_kg").get<double>(), cmp.robot.quadruped.mass_kg);
  ASSERT_TRUE(fs::is_regular_file(t.dir / "out" / "robot.xml"));
  std::ifstream ey(t.dir / "out" / "experiment.yaml");
  std::stringstream es;
  es << ey.rdbuf();
  EXPECT_NE(es.str().find("robot: {mjcf: robot.xml}"), std::string::npos) << es.str();
  // The folder's copy derives the same robot.
  std::vector<Experiment> again = loadExperimentSuite((t.dir / "out" / "experiment.yaml").string());
  resolveRobotModels(again);
  EXPECT_EQ(again.front().cases.front().robot.quadruped.izz_kgm2, cmp.robot.quadruped.izz_kgm2);
  EXPECT_EQ(again.front().cases.front().robot.quadruped.d_Q2B_m, cmp.robot.quadruped.d_Q2B_m);
}

// Standing 2 s with the tail: the tilt from the settled stance is what the tail
// causes. On their own kp-100 servos Go1 and ANYmal C tilt 1 deg or more (a warning says so);
// with `legs: locked` (joint equalities at the stood angles) both stay below 1 deg.
TEST(RobotModelExperiment, StandingTiltWithTheTailOnServosAndLockedLegs) {
  const fs::path men = menagerieDir();
  if (men.empty()) GTEST_SKIP() << "no shared/robots/menagerie beside the source tree or its parents";
  Scratch t("robot_model_exp");
  const std::string go1 = "{mjcf: " + (men / "go1" / "go1.xml").string() + ", legs: {sweep: [servos, locked]}}";
  const std::string anymal = "{mjcf: " + (men / "anymal_c" / "anymal_c.xml").string() +
                             ", legs: {sweep: [servos, locked]}, stance: {joints_deg: {LF_HFE: 23, LF_KFE: -46, "
                             "RF_HFE: 23, RF_KFE: -46, LH_HFE: -23, LH_KFE: 46, RH_HFE: -23, RH_KFE: 46}}}";
  for (const auto& [robot, x] : {std::pair<std::string, double>{go1, -0.2}, {anymal, -0.35}}) {
    const std::string f = t.write(
        "tilt.yaml", "name: tilt\nrobot: " + robot + "\ntail: {mount: {pos_m: [" + std::to_string(x) +
                         ", 0, 0]}, links: 1}\ntrajectory: {rule: eq25, thetadot_max_dps: 600}\nmodels: [mujoco]\n"
                         "output: {settle_s: 1.0, time_series: none}\n");
    std::vector<Experiment> s = loadExperimentSuite(f);
    resolveRobotModels(s);
    ASSERT_EQ(s.front().cases.size(), 2u);
    for (const ExperimentCase& c : s.front().cases) {
      const RunSummary r = runCase(c, nullptr).front().summary;
      ASSERT_TRUE(r.ok) << r.error;
      const double stand = r.extra.at("stand_max_tilt_from_stance_deg");
      const bool locked = c.robot_model->legs == "locked";
      std::printf("%s legs %s: tilt from the stance while standing with the tail at most %.3f deg, at the stroke's "
                  "start %.3f deg; phi_net %.3f deg\n",
                  c.robot_model->file.c_str(), c.robot_model->legs.c_str(), stand,
                  r.extra.at("stand_end_tilt_from_stance_deg"), r.phi_net_deg);
      bool warned = false;
      for (const std::string& w : r.warnings) warned = warned || w.find("from its stance") != std::string::npos;
      // Both within 1 deg of the stance, no warning. On the model's own servos that needs their
      // set-points trimmed for the tail's weight (untrimmed: 1.06 deg for Go1, 3.58 for ANYmal C);
      // locked legs need no trim.
      EXPECT_LT(stand, 1.0);
      EXPECT_FALSE(warned);
      if (locked) {
        EXPECT_EQ(r.extra.at("stance_trim_rounds"), 0.0);
      } else {
        EXPECT_GT(r.extra.at("stance_trim_rounds"), 1.0);
        EXPECT_GT(r.extra.at("stance_trim_max_offset_deg"), 0.0);
      }
    }
  }
}

// The articulated run estimates its own uncertainty by the rigid-box run's rule
// (run_uncertainty.h): a check run of the same robot at twice the model's timestep gives
// phi_net_check_deg, phi_net_uncertainty_deg = 2 |phi_h - phi_2h| + 0.5 % of max(|phi_h|, 0.5 deg)
// and the uncertain warning beyond mujoco.uncertainty_warn_share; `mujoco: {uncertainty: false}`
// skips it. Go1 at 600 deg/s: +0.165 +- 0.014 deg; at 1200 deg/s: -0.931 +- 0.491 deg (the check
// run -1.174), which warns.
TEST(RobotModelExperiment, ArticulatedRunCarriesItsOwnUncertainty) {
  const fs::path men = menagerieDir();
  if (men.empty()) GTEST_SKIP() << "no shared/robots/menagerie beside the source tree or its parents";
  Scratch t("robot_model_exp");
  for (const bool on : {true, false}) {
    const std::string f = t.write(
        "go1_u.yaml", "name: go1_u\nrobot: {mjcf: " + (men / "go1" / "go1.xml").string() +
                          "}\ntail: {mount: {body: trunk, pos_m: [-0.2, 0, 0]}, links: 1}\n"
                          "trajectory: {rule: eq25, thetadot_max_dps: {sweep: [600, 1200]}}\nmodels: [mujoco]\n"
                          "mujoco: {uncertainty: " + std::string(on ? "true" : "false") +
                          "}\noutput: {time_series: none}\n");
    std::vector<Experiment> s = loadExperimentSuite(f);
    resolveRobotModels(s);
    ASSERT_EQ(s.front().cases.size(), 2u);
    for (const ExperimentCase& c : s.front().cases) {
      const RunSummary r = runCase(c, nullptr).front().summary;
      ASSERT_TRUE(r.ok) << r.error;
      bool warned = false;
      for (const std::string& w : r.warnings) warned = warned || w.rfind(kUncertainWarning, 0) == 0;
      if (!on) {
        EXPECT_FALSE(r.extra.count("phi_net_uncertainty_deg"));
        EXPECT_FALSE(r.extra.count("phi_net_check_deg"));
        EXPECT_FALSE(warned);
        continue;
      }
      ASSERT_TRUE(r.extra.count("phi_net_uncertainty_deg"));
      ASSERT_TRUE(r.extra.count("phi_net_check_deg"));
      const double u = r.extra.at("phi_net_uncertainty_deg"), check = r.extra.at("phi_net_check_deg");
      std::printf("go1 %s: phi_net %+.4f +- %.4f deg, check run %+.4f deg\n",
                  c.name.c_str(), r.phi_net_deg, u, check);
      EXPECT_NE(check, r.phi_net_deg);  // a second run, at another step
      EXPECT_DOUBLE_EQ(u, 2.0 * std::abs(r.phi_net_deg - check) + 0.005 * std::max(std::abs(r.phi_net_deg), 0.5));
      EXPECT_NEAR(r.extra.at("uncertainty_solver_steps"), 0.5 * r.solver_steps, 1.0);  // twice the step
      EXPECT_EQ(warned, c.name.find("1200") != std::string::npos) << c.name << ": U " << u;
    }
  }
}

// A robot on 3 feet runs as the articulated MuJoCo model (`models: [mujoco]`): it stands, the tail
// turns it, and the feet are found one per body even when a foot body has two touching geoms.
TEST(RobotModelExperiment, ThreeFeetRunArticulatedAndFeetAreOnePerBody) {
  Scratch t("robot_model_exp");
  t.write("three.xml", boxRobot(kHome, R"(
      <geom name="f1" type="sphere" size="0.02" pos="0.2 0.12 -0.28"/>
      <geom name="f2" type="sphere" size="0.02" pos="0.2 -0.12 -0.28"/>
      <body name="rear"><geom name="f3" type="sphere" size="0.02" pos="-0.2 0 -0.28"/>
        <geom name="f3b" type="sphere" size="0.02" pos="-0.19 0 -0.28"/></body>)"));
  const std::string f = t.write("e.yaml", "name: tripod\nrobot: {mjcf: three.xml}\ntail: {mount: {pos_m: [-0.25, 0, 0]}, "
                                          "links: 1}\ntrajectory: {rule: eq25, thetadot_max_dps: 600}\nmodels: [mujoco]\n"
                                          "output: {settle_s: 1.0, time_series: none}\n");
  std::vector<Experiment> s = loadExperimentSuite(f);
  resolveRobotModels(s);
  const ExperimentCase& c = s.front().cases.front();
  ASSERT_TRUE(c.robot_derived);
  EXPECT_EQ(c.robot_derived->foot_count, 3);
  EXPECT_EQ(c.robot_derived->feet.size(), 3u);  // f3 and f3b are one foot: the body's lowest geom
  EXPECT_EQ(c.robot_derived->feet.front().rfind("f1", 0) == 0 || c.robot_derived->feet.front().rfind("f2", 0) == 0, true);
  const RunSummary r = runCase(c, nullptr).front().summary;
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.extra.at("feet_in_contact"), 3.0);
  EXPECT_LT(r.extra.at("stand_max_tilt_from_stance_deg"), 1.0);
  EXPECT_GT(std::abs(r.phi_net_deg), 0.0);
  const std::string shown = describeDerivedRobot(*c.robot_derived);
  EXPECT_NE(shown.find("feet (front to back): "), std::string::npos) << shown;
  EXPECT_NE(shown.find("only the articulated MuJoCo model runs on it"), std::string::npos) << shown;
}

// The figures and the result page of an experiment that names a model file call its MuJoCo run
// what it is, the articulated robot ("MuJoCo (contact)" named the rigid-box contact model there too);
// an experiment of tailsim's own robot keeps "MuJoCo (contact)".
TEST(RobotModelExperiment, FiguresNameTheArticulatedRobot) {
  Scratch t("robot_model_exp");
  t.write("box.xml", boxRobot(kHome));
  const std::string f = t.write("e.yaml", "name: box_fig\nrobot: {mjcf: box.xml}\ntail: {mount: {pos_m: [-0.25, 0, 0]}, "
                                          "links: 1}\ntrajectory: {rule: eq25, thetadot_max_dps: 600}\n"
                                          "models: [analytic, mujoco]\noutput: {settle_s: 0.3, sample_dt_s: 0.01}\n");
  std::vector<Experiment> s = loadExperimentSuite(f);
  resolveRobotModels(s);
  RunOptions o;
  o.out_dir = (t.dir / "out").string();
  o.threads = 1;
  o.progress = false;
  runSuite(s, o);
  const ExperimentResults r = loadResults(o.out_dir);
  EXPECT_TRUE(r.articulated);
  EXPECT_EQ(r.modelTitle("mujoco"), "MuJoCo (articulated robot)");
  EXPECT_EQ(r.modelTitle("analytic"), modelTitle("analytic"));
  plotExperiment(r);
  int scripts = 0;
  for (const auto& e : fs::directory_iterator(t.dir / "out" / "plots")) {
    if (e.path().extension() != ".gp") continue;
    std::ifstream in(e.path());
    std::stringstream gp;
    gp << in.rdbuf();
    EXPECT_EQ(gp.str().find("MuJoCo (contact)"), std::string::npos) << e.path();
    scripts += gp.str().find("MuJoCo (articulated robot)") != std::string::npos;
  }
  EXPECT_GT(scripts, 0);
  EXPECT_EQ(modelTitle("mujoco", false), "MuJoCo (contact)");
}

// A robot that falls is a failed run, never a turn: a 10 kg box with a 15 kg, 1 m tail held out to
// its side (the Eq. 25 stroke starts at theta = +90 deg) rolls over while standing. Before, the
// articulated run reported ok and a phi_net with only a tilt warning.
TEST(RobotModelExperiment, ARobotThatFallsIsAFailedRun) {
  Scratch t("robot_model_exp");
  t.write("box.xml", boxRobot(kHome));
  const std::string f =
      t.write("e.yaml", "name: topple\nrobot: {mjcf: box.xml}\ntail: {mount: {pos_m: [-0.25, 0, 0]}, custom: "
                        "[{mass_kg: 15, izz_kgm2: 1.25, length_m: 1.0}]}\ntrajectory: {rule: eq25, thetadot_max_dps: 600}\n"
                        "models: [mujoco]\noutput: {settle_s: 0.5, time_series: none}\n");
  std::vector<Experiment> s = loadExperimentSuite(f);
  resolveRobotModels(s);
  const RunSummary r = runCase(s.front().cases.front(), nullptr).front().summary;
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("the robot fell over"), std::string::npos) << r.error;
  EXPECT_TRUE(std::isnan(r.phi_net_deg));
}

// The articulated robot's rest step schedule (docs/mujoco-model.md "Step schedule"): once the body
// rests after the stroke it steps at rest_step_factor times the model's timestep, with the same
// answer. The box robot on the implicit integrator (the schedule's guard) at a 1 ms step, rows every
// 10 ms (two 5 ms rest steps). Its check run stops once the body rests. (At the default 2 ms step,
// 10 ms rest steps, phi_net moves by 1.3e-5 deg: the box still settles on its soft contacts,
// below the rest thresholds, when the coarse steps begin; docs/mujoco-model.md "Step schedule".)
TEST(RobotModelExperiment, ArticulatedRobotStepsCoarserAtRestWithTheSameAnswer) {
  Scratch t("robot_model_exp");
  std::string xml = boxRobot(kHome);
  xml.replace(xml.find("<worldbody>"), 0, "<option integrator=\"implicit\" timestep=\"0.001\"/>\n  ");
  t.write("box.xml", xml);
  auto run = [&](int factor) {
    const std::string f = t.write(
        "e.yaml", "name: box_rest\nrobot: {mjcf: box.xml}\ntail: {mount: {pos_m: [-0.25, 0, 0]}, links: 1}\n"
                  "trajectory: {rule: eq25, thetadot_max_dps: 600}\nmodels: [mujoco]\n"
                  "mujoco: {rest_step_factor: " + std::to_string(factor) + "}\n"
                  "output: {settle_s: 1.0, sample_dt_s: 0.01}\n");
    std::vector<Experiment> s = loadExperimentSuite(f);
    resolveRobotModels(s);
    return runCase(s.front().cases.front(), nullptr).front();
  };
  const RunResult a = run(1), b = run(5);
  ASSERT_TRUE(a.summary.ok) << a.summary.error;
  ASSERT_TRUE(b.summary.ok) << b.summary.error;
  std::printf("box robot: phi_net %+.9f / %+.9f deg, steps %ld -> %ld, check run steps %g -> %g\n",
              a.summary.phi_net_deg, b.summary.phi_net_deg, a.summary.solver_steps, b.summary.solver_steps,
              a.summary.extra.at("uncertainty_solver_steps"), b.summary.extra.at("uncertainty_solver_steps"));
  EXPECT_NEAR(b.summary.phi_net_deg, a.summary.phi_net_deg, 1e-6);
  // 2 s standing at 1 ms in both; most of the 1 s after the stroke at 5 ms.
  EXPECT_LT(b.summary.solver_steps, a.summary.solver_steps - 600)
      << a.summary.solver_steps << " -> " << b.summary.solver_steps;
  EXPECT_TRUE(b.summary.at_rest);
  expectSameSeries(a.series, b.series, 1e-4);
  // The check run at 2 ms stops once the body rests: fewer than half the run's steps, the same phi_2h.
  EXPECT_LT(a.summary.extra.at("uncertainty_solver_steps"), 0.5 * a.summary.solver_steps - 100);
  EXPECT_NEAR(b.summary.extra.at("phi_net_check_deg"), a.summary.extra.at("phi_net_check_deg"), 1e-6);
}

// In a scene with two free bodies the robot is the tree of the tail mount's body; with no mount body
// to choose by, an error names both.
TEST(RobotModelExperiment, TwoFreeBodiesTheMountBodyChoosesTheRobot) {
  Scratch t("robot_model_exp");
  std::string xml = boxRobot(kHome);
  xml.replace(xml.find("  </worldbody>"), 0,
              "    <body name=\"crate\" pos=\"1 1 0.1\"><freejoint/><geom type=\"box\" size=\"0.1 0.1 0.1\" mass=\"2\"/></body>\n");
  xml.replace(xml.find("qpos=\"0 0 0.3 1 0 0 0\""), 22, "qpos=\"0 0 0.3 1 0 0 0 1 1 0.1 1 0 0 0\"");
  t.write("two.xml", xml);
  const std::string f = (t.dir / "e.yaml").string();
  t.write("e.yaml", experiment("{mjcf: two.xml}"));
  const std::string m = errorOf(f);
  expectAt(m, f, 2, "robot");  // no tail.mount.body in the file: the robot key
  EXPECT_NE(m.find("2 bodies have a free joint ('trunk', 'crate')"), std::string::npos) << m;
  t.write("e.yaml", experiment("{mjcf: two.xml}", "{mount: {body: trunk, pos_m: [-0.25, 0, 0]}, links: 1}"));
  std::vector<Experiment> s = loadExperimentSuite(f);
  resolveRobotModels(s);
  EXPECT_NEAR(s.front().cases.front().robot.quadruped.mass_kg, 10.0, 1e-12);  // the trunk's tree, not the crate
}

// `tailsim run e.yaml --out .` in the folder that holds the user's robot.xml: the run refuses to
// replace it (its own copy of the model is robot.xml) and leaves the folder as it was: before, it
// had already written experiment.yaml and cases/ when it refused.
TEST(RobotModelExperiment, ARefusedRunLeavesTheFolderAsItWas) {
  Scratch t("robot_model_exp");
  t.write("robot.xml", boxRobot(kHome));
  const std::string f = t.write("e.yaml", experiment("{mjcf: robot.xml}"));
  std::vector<Experiment> suite = loadExperimentSuite(f);
  resolveRobotModels(suite);
  std::set<std::string> before;
  for (const auto& p : std::filesystem::directory_iterator(t.dir)) before.insert(p.path().filename().string());
  RunOptions o;
  o.out_dir = t.dir.string();
  o.threads = 1;
  o.progress = false;
  try {
    runSuite(suite, o);
    ADD_FAILURE() << "the user's robot.xml was replaced";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("robot.xml was not written by tailsim"), std::string::npos) << e.what();
  }
  std::set<std::string> after;
  for (const auto& p : std::filesystem::directory_iterator(t.dir)) after.insert(p.path().filename().string());
  after.erase(".tailsim.lock");  // the folder's lock (docs/ARCHITECTURE.md), taken before anything is judged
  EXPECT_EQ(after, before);
  std::ifstream in(t.dir / "robot.xml");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), boxRobot(kHome));
}
