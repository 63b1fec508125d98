// The models in Menagerie form (mjcf/tailsim_n<N>.xml + mjcf/scene_n<N>.xml, mjcf/README.md), tested
// the way MuJoCo Menagerie tests its models: every scene loads, steps 1 s of simulated time with the tail
// driven by the split-cycle profile (ctrl from src/trajectory, as a user would set it) without a MuJoCo
// warning, the robot stays upright, and the `home` keyframe exists and resets. Plus: the files are what
// the generator writes, the feet's friction wins on any floor (geom priority, measured from
// d->contact), the scene simulates the same robot as the single-file model tailsim runs, and MuJoCo 2.2
// has no engine plugins (why mujoco-simulate cannot play the stroke by itself, mjcf/README.md).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"
#include "trajectory/split_cycle_profile.h"
#include "scratch_dir.h"

using namespace tailsim;
using tailsim::testing::ScratchDir;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;
const fs::path kMjcfDir = fs::path(TAILSIM_SOURCE_DIR) / "mjcf";

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<fs::path> scenes() {
  std::vector<fs::path> out;
  for (const fs::directory_entry& e : fs::directory_iterator(kMjcfDir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("scene_", 0) == 0 && e.path().extension() == ".xml") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
  for (size_t i = s.find(from); i != std::string::npos; i = s.find(from, i + to.size())) s.replace(i, from.size(), to);
  return s;
}

// Eq. (25) stroke for an n-link tail at 600 deg/s peak speed, starting at t0.
TailTrajectory eq25(int n, double t0) {
  TailTrajectory tr;
  const SplitCycleParams sc = equalPeakSpeedParams(n, 600.0 * kPi / 180.0, 0.25, t0);
  for (int i = 0; i < n; ++i) tr.joints.emplace_back(sc);
  return tr;
}

struct DriveResult {
  int warnings = 0;           // sum of d->warning[i].number
  double max_tilt_deg = 0.0;  // body z axis against world z
  double max_height_change_m = 0.0;
  double max_track_err_deg = 0.0;  // tail joints, after the servo caught up (t >= 0.05 s)
  double final_theta1_deg = 0.0;
  double yaw_deg = 0.0;  // heading of the body x axis at the end
};

// Resets to `home`, puts the tail at the profile's start angles, and steps `seconds` of simulated time
// with ctrl_i = theta_ref,i + (kv_i / kp_i) theta_dot_ref,i (kp, kv read from the actuators).
DriveResult drive(const mjModel* m, mjData* d, const TailTrajectory& tr, double seconds) {
  const int key = mj_name2id(m, mjOBJ_KEY, "home");
  mj_resetDataKeyframe(m, d, key);
  const int n = m->nu;
  std::vector<int> qadr(n);
  std::vector<double> kv_over_kp(n);
  for (int i = 0; i < n; ++i) {
    const int j = m->actuator_trnid[2 * i];
    qadr[i] = m->jnt_qposadr[j];
    kv_over_kp[i] = -m->actuator_biasprm[mjNBIAS * i + 2] / m->actuator_gainprm[mjNGAIN * i];
  }
  std::vector<JointState> ref;
  tr.evaluate(0.0, ref);
  for (int i = 0; i < n; ++i) d->qpos[qadr[i]] = ref[i].theta;
  mj_forward(m, d);
  const int q = mj_name2id(m, mjOBJ_BODY, mjcf::kQuadrupedBody);
  const double h0 = d->xipos[3 * q + 2];
  DriveResult r;
  const int steps = static_cast<int>(std::lround(seconds / m->opt.timestep));
  for (int k = 0; k < steps; ++k) {
    tr.evaluate(d->time, ref);
    for (int i = 0; i < n; ++i) d->ctrl[i] = ref[i].theta + kv_over_kp[i] * ref[i].theta_dot;
    mj_step(m, d);
    tr.evaluate(d->time, ref);
    r.max_tilt_deg = std::max(r.max_tilt_deg, std::acos(std::min(1.0, d->xmat[9 * q + 8])) * 180.0 / kPi);
    r.max_height_change_m = std::max(r.max_height_change_m, std::abs(d->xipos[3 * q + 2] - h0));
    if (d->time >= 0.05)
      for (int i = 0; i < n; ++i)
        r.max_track_err_deg = std::max(r.max_track_err_deg, std::abs(d->qpos[qadr[i]] - ref[i].theta) * 180.0 / kPi);
  }
  for (int i = 0; i < mjNWARNING; ++i) r.warnings += d->warning[i].number;
  r.final_theta1_deg = d->qpos[qadr[0]] * 180.0 / kPi;
  r.yaw_deg = std::atan2(d->xmat[9 * q + 3], d->xmat[9 * q + 0]) * 180.0 / kPi;
  return r;
}

}  // namespace

TEST(Menagerie, FilesInMjcfAreWhatTheGeneratorWrites) {
  // Regenerate with scripts/mjcf_menagerie.sh (= tailsim mjcf --links N --menagerie mjcf, N = 1..6).
  for (int n = 1; n <= 6; ++n) {
    const MenagerieFiles f = generateMenagerie(paperRobot(n), MujocoSettings{}, Effects{}, "n" + std::to_string(n));
    EXPECT_EQ(f.robot_file, "tailsim_n" + std::to_string(n) + ".xml");
    EXPECT_EQ(f.scene_file, "scene_n" + std::to_string(n) + ".xml");
    EXPECT_EQ(readFile(kMjcfDir / f.robot_file), f.robot_xml) << f.robot_file << " is stale: run scripts/mjcf_menagerie.sh";
    EXPECT_EQ(readFile(kMjcfDir / f.scene_file), f.scene_xml) << f.scene_file << " is stale: run scripts/mjcf_menagerie.sh";
  }
}

TEST(Menagerie, EverySceneStepsOneSecondWithTheTailDrivenUprightAndWithoutWarnings) {
  const std::vector<fs::path> all = scenes();
  ASSERT_GE(all.size(), 6u) << "expected scene_n1..6.xml in " << kMjcfDir;
  for (const fs::path& scene : all) {
    SCOPED_TRACE(scene.filename().string());
    ModelPtr model = loadModelFromFile(scene.string());
    const mjModel* m = model.get();
    DataPtr data = makeData(m);
    const int n = m->nu;
    ASSERT_GE(n, 1);
    const TailTrajectory tr = eq25(n, 0.2);
    const DriveResult r = drive(m, data.get(), tr, 1.0);
    EXPECT_NEAR(data->time, 1.0, 0.5 * m->opt.timestep);
    EXPECT_EQ(r.warnings, 0);
    EXPECT_LT(r.max_tilt_deg, 1.0);            // paper cases: <= 0.32 deg (docs/mujoco-model.md)
    EXPECT_LT(r.max_height_change_m, 0.003);   // paper cases: <= 1.4 mm
    EXPECT_LT(r.max_track_err_deg, 1.0);       // the servo follows the profile ...
    const double end_deg = (tr.joints[0].params().theta0_rad + tr.joints[0].params().dtheta_rad) * 180.0 / kPi;
    EXPECT_NEAR(r.final_theta1_deg, end_deg, 0.5);  // ... to the stroke's end (-90 deg for n = 1)
    EXPECT_GT(std::abs(r.yaw_deg), 1.0);  // and the tail turned the body
    std::printf("%s: nu %d, warnings %d, max tilt %.3f deg, max height change %.2f mm, max tracking error %.3f deg, "
                "theta1 at 1 s %.2f deg (stroke end %.2f), body yaw at 1 s %.2f deg\n",
                scene.filename().c_str(), n, r.warnings, r.max_tilt_deg, 1e3 * r.max_height_change_m,
                r.max_track_err_deg, r.final_theta1_deg, end_deg, r.yaw_deg);
  }
}

TEST(Menagerie, HomeKeyframeExistsAndResets) {
  for (const fs::path& scene : scenes()) {
    SCOPED_TRACE(scene.filename().string());
    ModelPtr model = loadModelFromFile(scene.string());
    const mjModel* m = model.get();
    DataPtr data = makeData(m);
    mjData* d = data.get();
    const int key = mj_name2id(m, mjOBJ_KEY, "home");
    ASSERT_GE(key, 0) << "no keyframe 'home'";
    drive(m, d, eq25(m->nu, 0.0), 0.3);  // move away from home
    mj_resetDataKeyframe(m, d, key);
    for (int i = 0; i < m->nq; ++i) EXPECT_EQ(d->qpos[i], m->key_qpos[m->nq * key + i]) << "qpos " << i;
    for (int i = 0; i < m->nv; ++i) EXPECT_EQ(d->qvel[i], 0.0) << "qvel " << i;
    EXPECT_EQ(d->time, 0.0);
    mj_forward(m, d);
    const int q = mj_name2id(m, mjOBJ_BODY, mjcf::kQuadrupedBody);
    EXPECT_NEAR(d->xipos[3 * q + 2], MujocoSettings{}.body_height_m, 1e-12);  // Q at h, upright
    EXPECT_NEAR(d->xmat[9 * q + 8], 1.0, 1e-12);
    for (int k = 1; k <= 4; ++k) {  // the feet touch the floor (sphere bottoms at z = 0)
      const int g = mj_name2id(m, mjOBJ_GEOM, mjcf::footGeomName(k).c_str());
      EXPECT_NEAR(d->geom_xpos[3 * g + 2] - m->geom_size[3 * g], 0.0, 1e-12);
    }
    for (int i = 1; i <= m->nu; ++i) {  // tail straight
      const int j = mj_name2id(m, mjOBJ_JOINT, mjcf::tailJointName(i).c_str());
      EXPECT_EQ(d->qpos[m->jnt_qposadr[j]], 0.0);
    }
  }
}

// Measured from MuJoCo's own contacts: a foot on a floor of friction 1 (the scene's default) or 1.5
// (condim 6, soft solref) gets the foot's mu, condim and solref, because the feet have priority 1. The
// same robot without the priority gets the floor's larger friction: the test can fail.
TEST(Menagerie, FeetGiveThePaperMuOnAnyFloor) {
  struct Case {
    const char* what;
    double mu_setting;     // mujoco.mu (< 0: max(mu_s, mu_d) = 0.3)
    std::string floor;     // extra floor attributes in the scene
    bool strip_priority;   // remove priority="1" from the feet
    double expect_mu;
    int expect_dim;
  };
  const std::vector<Case> cases = {
      {"paper robot, scene floor (friction 1)", -1.0, "", false, 0.3, 3},
      {"mu 0.42, floor friction 1.5 condim 6 solref 0.02", 0.42, R"( friction="1.5 0.1 0.01" condim="6" solref="0.02 1")",
       false, 0.42, 3},
      {"paper robot without priority (control)", -1.0, "", true, 1.0, 3},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    MujocoSettings s;
    s.mu = c.mu_setting;
    MenagerieFiles f = generateMenagerie(paperRobot(1), s, Effects{}, "probe");
    if (c.strip_priority) {
      ASSERT_NE(f.robot_xml.find(R"( priority="1")"), std::string::npos);
      f.robot_xml = replaceAll(f.robot_xml, R"( priority="1")", "");
    }
    if (!c.floor.empty()) f.scene_xml = replaceAll(f.scene_xml, R"(material="groundplane"/>)", R"(material="groundplane")" + c.floor + "/>");
    const ScratchDir dir("menagerie_friction");
    const std::vector<std::string> paths = writeMenagerie(f, dir.string());
    ModelPtr model = loadModelFromFile(paths[1]);
    const mjModel* m = model.get();
    const int floor = mj_name2id(m, mjOBJ_GEOM, mjcf::kFloorGeom);
    ASSERT_GE(floor, 0);
    EXPECT_GE(m->geom_friction[3 * floor], 1.0);  // a floor that would win the max() rule
    DataPtr data = makeData(m);
    mjData* d = data.get();
    mj_resetDataKeyframe(m, d, mj_name2id(m, mjOBJ_KEY, "home"));
    for (int k = 0; k < 500; ++k) mj_step(m, d);  // 0.1 s: the robot settles on its feet
    ASSERT_EQ(d->ncon, 4);
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& con = d->contact[i];
      EXPECT_TRUE(con.geom1 == floor || con.geom2 == floor);
      EXPECT_DOUBLE_EQ(con.friction[0], c.expect_mu) << "contact " << i;
      if (i == 0)
        std::printf("%s: floor friction %g, contact friction %g, dim %d, solref %g\n", c.what,
                    m->geom_friction[3 * floor], con.friction[0], con.dim, con.solref[0]);
      EXPECT_EQ(con.dim, c.expect_dim) << "contact " << i;
      if (!c.strip_priority) {
        EXPECT_DOUBLE_EQ(con.solref[0], s.solref[0]) << "contact " << i;
      }
    }
  }
}

// The Menagerie scene is the robot tailsim simulates (generateMjcf): the same masses, inertias, frames
// and servo gains, and the same motion under the same drive.
TEST(Menagerie, SceneSimulatesTheSameRobotAsTheSingleFileModel) {
  for (int n : {1, 6}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    ModelPtr single = loadModelFromXml(generateMjcf(paperRobot(n), MujocoSettings{}, Effects{}));
    ModelPtr scene = loadModelFromFile((kMjcfDir / ("scene_n" + std::to_string(n) + ".xml")).string());
    const mjModel* a = single.get();
    const mjModel* b = scene.get();
    ASSERT_EQ(a->nq, b->nq);
    ASSERT_EQ(a->nv, b->nv);
    ASSERT_EQ(a->nu, b->nu);
    ASSERT_EQ(a->nbody, b->nbody);
    EXPECT_EQ(a->opt.timestep, b->opt.timestep);
    EXPECT_EQ(a->opt.integrator, b->opt.integrator);
    for (int i = 0; i < a->nbody; ++i) {
      EXPECT_EQ(a->body_mass[i], b->body_mass[i]);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(a->body_inertia[3 * i + k], b->body_inertia[3 * i + k]);
        EXPECT_EQ(a->body_pos[3 * i + k], b->body_pos[3 * i + k]);
        EXPECT_EQ(a->body_ipos[3 * i + k], b->body_ipos[3 * i + k]);
      }
    }
    for (int i = 0; i < a->nu; ++i) {
      EXPECT_EQ(a->actuator_gainprm[mjNGAIN * i], b->actuator_gainprm[mjNGAIN * i]);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(a->actuator_biasprm[mjNBIAS * i + k], b->actuator_biasprm[mjNBIAS * i + k]);
    }
    DataPtr da = makeData(a), db = makeData(b);
    const TailTrajectory tr = eq25(n, 0.2);
    const DriveResult ra = drive(a, da.get(), tr, 1.0), rb = drive(b, db.get(), tr, 1.0);
    EXPECT_NEAR(ra.yaw_deg, rb.yaw_deg, 1e-6) << "single-file " << ra.yaw_deg << " deg";
    EXPECT_NEAR(ra.final_theta1_deg, rb.final_theta1_deg, 1e-6);
    std::printf("n = %d: body yaw at 1 s: single-file %.9f deg, Menagerie scene %.9f deg\n", n, ra.yaw_deg, rb.yaw_deg);
  }
}

// Any experiment's robot, including custom tails and switched-off effects, in Menagerie form.
TEST(Menagerie, CustomRobotsAndEffectsCompile) {
  RobotParams p;
  p.quadruped = {7.3, 0.17, 0.021, 0.1405, 0.33, 0.24};
  p.tail = {{1.1, 4e-3, 0.14, 0.06}, {0.7, 2e-3, 0.11, 0.05}, {0.45, 7e-4, 0.09, 0.03}};
  Effects e;
  e.friction = FrictionLaw::kContinuous;  // simulated from mu(0) = 0; the file carries the stiction value
  const MenagerieFiles f = generateMenagerie(p, MujocoSettings{}, e, "custom");
  const ScratchDir dir("menagerie_custom"), dir2("menagerie_noeffects");
  ModelPtr model = loadModelFromFile(writeMenagerie(f, dir.string())[1]);
  const mjModel* m = model.get();
  EXPECT_EQ(m->nu, 3);
  EXPECT_EQ(m->body_mass[mj_name2id(m, mjOBJ_BODY, mjcf::tailBodyName(2).c_str())], 0.7);
  EXPECT_EQ(m->geom_friction[3 * mj_name2id(m, mjOBJ_GEOM, mjcf::footGeomName(1).c_str())],
            std::max(p.friction.mu_s, p.friction.mu_d));
  EXPECT_NE(f.robot_xml.find("m_Q = 7.3 kg"), std::string::npos);  // the comments carry the parameters
  EXPECT_NE(f.robot_xml.find("m_L,i = [1.1, 0.7, 0.45] kg"), std::string::npos);

  e = Effects{};
  e.translation = false;
  e.ground_contact = false;
  e.gravity = false;
  ModelPtr m2 = loadModelFromFile(writeMenagerie(generateMenagerie(p, MujocoSettings{}, e, "noeffects"),
                                                 dir2.string())[1]);
  EXPECT_TRUE(m2->opt.disableflags & mjDSBL_CONTACT);
  EXPECT_TRUE(m2->opt.disableflags & mjDSBL_GRAVITY);
  EXPECT_EQ(m2->nv, 4 + 3);

  EXPECT_THROW(generateMenagerie(p, MujocoSettings{}, Effects{}, "../x"), std::invalid_argument);
  EXPECT_THROW(generateMenagerie(p, MujocoSettings{}, Effects{}, ""), std::invalid_argument);
}

// No model element of MuJoCo 2.2 can run a time profile inside mujoco-simulate; the
// engine-plugin mechanism that could (<extension><plugin>) arrived in MuJoCo 2.3.0. Measured here so
// the note in mjcf/README.md is revisited when MuJoCo is upgraded.
TEST(Menagerie, MuJoCo22HasNoEnginePlugins) {
  EXPECT_EQ(mj_version(), 222);
  try {
    loadModelFromXml("<mujoco><extension><plugin plugin=\"mujoco.pid\"/></extension><worldbody/></mujoco>");
    FAIL() << "MuJoCo accepted <extension>: engine plugins exist, revisit mjcf/README.md 'Watching the tail move'";
  } catch (const MujocoError& e) {
    EXPECT_NE(std::string(e.what()).find("unrecognized element"), std::string::npos) << e.what();
  }
}
