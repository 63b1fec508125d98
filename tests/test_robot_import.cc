// A robot from its MuJoCo model file (src/mujoco_model/robot_import.h): missing-file geoms dropped
// or refused, the stance, the feet, and the planar parameters equal to MuJoCo's own figures. The
// Menagerie models are read where the shared folder is (shared/robots/menagerie beside the source
// tree or beside one of its parents); the repository ships none.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <tuple>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/atomic_file.h"
#include "experiments/experiment_loader.h"
#include "experiments/robot_compare.h"
#include "models/mujoco/robot_import.h"
#include "menagerie_models.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = M_PI / 180.0;

using tailsim_test::menagerieDir;

#define REQUIRE_MENAGERIE(dir)                                                                            \
  const fs::path dir = menagerieDir();                                                                    \
  if (dir.empty()) GTEST_SKIP() << "no shared/robots/menagerie beside the source tree or its parents: " \
                                   "the Menagerie checks need go1/ and anymal_c/ there";

// ANYmal C has no keyframe: a standing pose by joint angles (hips and knees bent, knees inward).
RobotModelSpec anymalSpec(const fs::path& dir) {
  RobotModelSpec s;
  s.file = (dir / "anymal_c" / "anymal_c.xml").string();
  for (const char* leg : {"LF", "RF"}) {
    s.joint_angles_rad[std::string(leg) + "_HFE"] = 0.4;
    s.joint_angles_rad[std::string(leg) + "_KFE"] = -0.8;
  }
  for (const char* leg : {"LH", "RH"}) {
    s.joint_angles_rad[std::string(leg) + "_HFE"] = -0.4;
    s.joint_angles_rad[std::string(leg) + "_KFE"] = 0.8;
  }
  return s;
}

void expectMujocoFigures(const DerivedRobot& r, double xml_mass_kg) {
  EXPECT_NEAR(r.quadruped.mass_kg, r.mujoco_subtreemass_kg, 1e-9 * r.mujoco_subtreemass_kg);
  EXPECT_NEAR(r.quadruped.mass_kg, xml_mass_kg, 1e-9 * xml_mass_kg);  // the file's <inertial> masses
  EXPECT_NEAR(r.quadruped.izz_kgm2, r.mujoco_cinert_izz_kgm2, 1e-9 * r.mujoco_cinert_izz_kgm2);
  EXPECT_EQ(r.feet.size(), 4u);
  EXPECT_LT(r.tilt_deg, 1.0);
  EXPECT_GT(r.quadruped.l_F_m, 0.2);
  EXPECT_GT(r.quadruped.w_F_m, 0.1);
  EXPECT_GT(r.quadruped.com_height_m, 0.15);
}

TEST(RobotImport, Go1StandsOnItsHomeKeyAndMatchesMujoco) {
  REQUIRE_MENAGERIE(dir);
  RobotModelSpec s;
  s.file = (dir / "go1" / "go1.xml").string();
  const DerivedRobot r = deriveRobot(s);
  EXPECT_EQ(r.model.dropped_geoms, 13);  // the class="visual" mesh geoms; every collision geom kept
  EXPECT_NE(r.stance.find("keyframe 'home'"), std::string::npos);
  expectMujocoFigures(r, 5.204 + 4 * (0.68 + 1.009 + 0.195862));
  EXPECT_EQ(r.feet, (std::vector<std::string>{"FL", "FR", "RR", "RL"}));
  EXPECT_NEAR(r.mu, 0.8, 1e-12);  // the feet's friction (priority 1) wins over the floor's 1
  std::printf("%s", describeDerivedRobot(r).c_str());
  // The scene file (which includes go1.xml and has a floor) gives the same robot.
  s.file = (dir / "go1" / "scene.xml").string();
  const DerivedRobot sc = deriveRobot(s);
  EXPECT_NEAR(sc.quadruped.izz_kgm2, r.quadruped.izz_kgm2, 1e-3 * r.quadruped.izz_kgm2);  // settled on another floor
}

TEST(RobotImport, AnymalNeedsAStanceAndStandsOnJointAngles) {
  REQUIRE_MENAGERIE(dir);
  RobotModelSpec s = anymalSpec(dir);
  const auto angles = s.joint_angles_rad;
  s.joint_angles_rad.clear();
  try {
    deriveRobot(s);
    ADD_FAILURE() << "no error for a model without a keyframe and no stance";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("no stance: the model has no `home` keyframe"), std::string::npos) << e.what();
  }
  s.joint_angles_rad = angles;
  const DerivedRobot r = deriveRobot(s);
  std::printf("%s", describeDerivedRobot(r).c_str());
  EXPECT_GT(r.model.dropped_geoms, 20);
  EXPECT_EQ(r.model.dropped_textures, 19);
  // The base body is turned 180 deg in the file; its own x axis is the robot's forward.
  EXPECT_NEAR(r.lateral_com_to_feet_m, 0.0, 0.01);
  double xml_mass = 0.0;  // sum of <inertial mass=...> in the file
  {
    std::ifstream in(s.file);
    std::string line, text;
    while (std::getline(in, line)) text += line + "\n";
    for (std::size_t p = text.find("<inertial"); p != std::string::npos; p = text.find("<inertial", p + 1)) {
      const std::size_t q = text.find("mass=\"", p);
      xml_mass += std::stod(text.substr(q + 6));
    }
  }
  expectMujocoFigures(r, xml_mass);
}

// Item 4 of issue 34: a 1-link tail of 10 % of the robot's mass and one body length (l_F), Eq. 25
// stroke at 600 deg/s: the robot stands 2 s with the tail on its 4 feet, turns, and the planar
// models run on the derived parameters. The table is printed (docs/your-robot.md).
void expectFourModelsRun(const RobotModelSpec& spec) {
  RobotTailChoice tail;  // 10 %, l_F, 1 link, 600 deg/s, 2 s standing
  const RobotComparison c = compareRobotModels(spec, tail);
  std::printf("%s\n%s", describeDerivedRobot(c.robot).c_str(), describeComparison(c).c_str());
  ASSERT_EQ(c.rows.size(), 4u);
  for (const ModelRow& r : c.rows) {
    EXPECT_TRUE(r.ok) << r.model;
    EXPECT_TRUE(std::isfinite(r.phi_net_deg)) << r.model;
  }
  EXPECT_EQ(c.articulated.feet_in_contact, 4);
  // Standing 2 s with the tail on the model's own servos: within 1 deg of the stance the whole time,
  // their set-points trimmed for the tail's weight first (untrimmed, Go1 tilts 1.06 deg and ANYmal C
  // 3.58: docs/your-robot.md "Tilt"), and no tilt warning. During the stroke: not over 10 deg.
  const ArticulatedRun& a = c.articulated;
  EXPECT_GT(a.trim.rounds, 1);
  EXPECT_GT(a.trim.max_offset_deg, 0.0);
  EXPECT_LT(a.trim.end_tilt_deg, 0.5);
  EXPECT_LT(a.stand_max_rel_tilt_deg, 1.0);
  EXPECT_LT(a.stand_end_rel_tilt_deg, 1.0);
  for (const std::string& w : a.warnings) EXPECT_EQ(w.find("tilted"), std::string::npos) << w;
  EXPECT_LT(c.articulated.max_tilt_deg, 10.0);
  EXPECT_NEAR(c.tail.front().mass_kg, 0.1 * c.robot.quadruped.mass_kg, 1e-12);
  // Each MuJoCo row's phi_net carries its own +- U (the articulated robot's check run at twice the
  // model's timestep, the rigid box's at twice timestep_s); the planar rows, which estimate none, do not.
  const std::string table = describeComparison(c);
  for (const char* row : {"| mujoco (articulated", "| mujoco (rigid box) |", "| perfoot |", "| analytic |"}) {
    const std::size_t at = table.find(row);
    ASSERT_NE(at, std::string::npos) << row << "\n" << table;
    const std::string line = table.substr(at, table.find('\n', at) - at);
    const std::size_t a = line.find('|', 1), b = line.find('|', a + 1);
    const std::string phi = line.substr(a + 1, b - a - 1);
    EXPECT_EQ(phi.find(" +- ") != std::string::npos, std::string(row).rfind("| mujoco", 0) == 0) << line;
  }
}

TEST(RobotImport, Go1WithATailStandsTurnsAndAllModelsRun) {
  REQUIRE_MENAGERIE(dir);
  RobotModelSpec s;
  s.file = (dir / "go1" / "go1.xml").string();
  s.mount.pos_m = {-0.2, 0.0, 0.0};  // behind the trunk's collision box (half-length 0.125 m + the rear)
  expectFourModelsRun(s);
}

TEST(RobotImport, AnymalWithATailStandsTurnsAndAllModelsRun) {
  REQUIRE_MENAGERIE(dir);
  RobotModelSpec s = anymalSpec(dir);
  s.mount.pos_m = {-0.35, 0.0, 0.0};
  expectFourModelsRun(s);
}

using tailsim_test::Scratch;

const char* kBoxRobot = R"(<mujoco model="box">
  <default><default class="vis"><geom contype="0" conaffinity="0" group="2"/></default></default>
  <asset><mesh name="shell" file="shell.stl"/><mesh file="leg.stl"/></asset>
  <worldbody>
    <body name="trunk" pos="0 0 0.3">
      <freejoint/>
      <inertial pos="0 0 0" mass="10" diaginertia="0.1 0.2 0.25"/>
      <geom class="vis" type="mesh" mesh="shell"/>
      <geom name="body_box" type="box" size="0.25 0.15 0.05"/>
      %LEG%
      <geom name="f1" type="sphere" size="0.02" pos="0.2 0.12 -0.28"/>
      <geom name="f2" type="sphere" size="0.02" pos="0.2 -0.12 -0.28"/>
      <geom name="f3" type="sphere" size="0.02" pos="-0.2 -0.12 -0.28"/>
      <geom name="f4" type="sphere" size="0.02" pos="-0.2 0.12 -0.28"/>
    </body>
  </worldbody>
</mujoco>
)";

std::string boxRobot(const std::string& leg) {
  std::string s = kBoxRobot;
  s.replace(s.find("%LEG%"), 5, leg);
  return s;
}

TEST(RobotImport, MissingMeshDroppedWhenItCannotCollideElseAnError) {
  Scratch t("robot_import");
  RobotModelSpec s;
  s.file = t.write("ok.xml", boxRobot(""));
  s.joint_angles_rad = {};
  s.keyframe = "";
  // No keyframe and no joints: a rigid robot still needs a stance named; give none -> error.
  EXPECT_THROW(deriveRobot(s), RobotImportError);
  // A standing keyframe under another name (Menagerie's Barkour v0: 'standing'): the error lists it.
  std::string keyed = boxRobot("");
  keyed.replace(keyed.find("</worldbody>"), 12,
                "</worldbody>\n<keyframe><key name=\"standing\" qpos=\"0 0 0.3 1 0 0 0\"/></keyframe>");
  s.file = t.write("keyed.xml", keyed);
  try {
    deriveRobot(s);
    ADD_FAILURE() << "no error without a home keyframe or joint angles";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("no `home` keyframe (keyframes: standing)"), std::string::npos) << e.what();
  }
  s.file = t.write("ok.xml", boxRobot(""));
  const PreparedModel p = prepareRobotModel(s.file);
  EXPECT_EQ(p.dropped_geoms, 1);
  EXPECT_EQ(p.xml.find("shell.stl"), std::string::npos);

  s.file = t.write("bad.xml", boxRobot(R"(<geom name="leg_shell" type="mesh" mesh="leg"/>)"));
  try {
    prepareRobotModel(s.file);
    ADD_FAILURE() << "no error for a colliding geom whose mesh is missing";
  } catch (const RobotImportError& e) {
    const std::string msg = e.what();
    std::printf("error text: %s\n", msg.c_str());
    EXPECT_NE(msg.find("geom 'leg_shell' in body 'trunk' collides but its mesh file " +
                           (t.dir / "leg.stl").lexically_normal().string() +
                       " is missing"),
              std::string::npos)
        << msg;
  }
}

// A scene that includes the robot and then has its own <worldbody> with the floor (Menagerie's
// A1 and Go2 scene.xml): MuJoCo merges the worldbodies, so the scene's floor is the floor; no
// second plane is added under the feet.
TEST(RobotImport, SceneFloorInALaterWorldbodyIsTheFloor) {
  Scratch t("robot_import");
  t.write("robot.xml", boxRobot(""));
  const std::string scene = R"(<mujoco model="scene">
  <include file="robot.xml"/>
  <worldbody><geom name="floor" type="plane" size="0 0 0.05"/></worldbody>
</mujoco>
)";
  const PreparedModel p = prepareRobotModel(t.write("scene.xml", scene));
  EXPECT_EQ(p.floor_geom, "floor");
  for (const std::string& n : p.notes) EXPECT_EQ(n.find("added a floor"), std::string::npos) << n;
  EXPECT_EQ(p.xml.find("tailsim_floor"), std::string::npos);
}

// A Menagerie file written for MuJoCo 3.x (Spot's joint actuatorfrcrange, position inheritrange):
// MuJoCo 2.2's schema refuses it; the error names the user's file (an included one too), the line
// and the attribute, and says it is from a newer MuJoCo.
TEST(RobotImport, AttributeFromANewerMujocoNamedAtItsLineInTheUsersFile) {
  Scratch t("robot_import");
  std::string robot = boxRobot("");
  robot.replace(robot.find("<default>"), 9, "<default>\n  <joint actuatorfrcrange=\"-10 10\"/>");
  RobotModelSpec s;
  s.file = t.write("robot.xml", robot);
  s.keyframe = "";
  s.joint_angles_rad = {};
  const std::string scene = R"(<mujoco model="scene">
  <include file="robot.xml"/>
  <worldbody><geom name="floor" type="plane" size="0 0 0.05"/></worldbody>
</mujoco>
)";
  const std::string robotFile = (t.dir / "robot.xml").lexically_normal().string();
  for (const std::string& f : {s.file, t.write("scene.xml", scene)}) {
    s.file = f;
    try {
      deriveRobot(s);
      ADD_FAILURE() << "no error for an attribute MuJoCo 2.2 does not know";
    } catch (const RobotImportError& e) {
      const std::string msg = e.what();
      std::printf("error text: %s\n", msg.c_str());
      EXPECT_EQ(msg.rfind(robotFile + ":3: attribute 'actuatorfrcrange' of <joint> is not known to MuJoCo 2.2", 0),
                0u)
          << msg;
      EXPECT_NE(msg.find("newer MuJoCo, 3.x"), std::string::npos) << msg;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a RobotImportError: " << e.what();
    }
  }
}

TEST(RobotImport, FeetAndPlanarNumbersOfARigidBox) {
  Scratch t("robot_import");
  std::string xml = boxRobot("");
  xml.replace(xml.find("</worldbody>"), 12,
              "</worldbody>\n<keyframe><key name=\"home\" qpos=\"0 0 0.3 1 0 0 0\"/></keyframe>");
  RobotModelSpec s;
  s.file = t.write("box.xml", xml);
  s.mount.pos_m = {-0.25, 0.0, 0.0};
  s.settle_s = 0.3;
  const DerivedRobot r = deriveRobot(s);
  EXPECT_EQ(r.feet, (std::vector<std::string>{"f1", "f2", "f3", "f4"}));
  EXPECT_NEAR(r.quadruped.mass_kg, 10.0, 1e-12);
  EXPECT_NEAR(r.quadruped.izz_kgm2, 0.25, 1e-6);  // one body, upright
  EXPECT_NEAR(r.quadruped.l_F_m, 0.4, 1e-4);
  EXPECT_NEAR(r.quadruped.w_F_m, 0.24, 1e-4);
  EXPECT_NEAR(r.quadruped.d_Q2C_m, 0.0, 1e-4);
  EXPECT_NEAR(r.quadruped.d_Q2B_m, 0.25, 1e-4);
  EXPECT_NEAR(r.quadruped.com_height_m, 0.30, 2e-3);  // sphere feet: contact 0.3 below the COM
  EXPECT_NEAR(r.mu, 1.0, 1e-12);                        // MuJoCo's default friction on both sides
  // Feet named by the user win; a wrong count is an error.
  s.feet = {"f1", "f2"};
  EXPECT_THROW(deriveRobot(s), RobotImportError);
}

// `tailsim robot FILE.yaml`: a robot given by its size prints the values derived from its box.
TEST(RobotImport, YamlRobotPrintsItsValues) {
  Scratch t("robot_import");
  const std::string f = t.write("box.yaml",
                                "quadruped: {mass_kg: 12, size_m: [0.5, 0.3, 0.2], foot_inset_m: 0.03}\n"
                                "friction: {mu_s: 0.5, mu_d: 0.4}\ngravity_mps2: 9.81\n"
                                "tails:\n  1: {mass_kg: 1.2, izz_kgm2: 0.025, length_m: 0.5}\n");
  const std::string out = describeYamlRobot(f);
  std::printf("%s", out.c_str());
  EXPECT_NE(out.find("quadruped.izz_kgm2       0.34 "), std::string::npos) << out;
  EXPECT_NE(out.find("quadruped.l_F_m          0.44 "), std::string::npos) << out;
  EXPECT_NE(out.find("quadruped.com_height_m   0.1 "), std::string::npos) << out;
  t.write("exp.yaml", "name: e\nrobot: box.yaml\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nquadruped: {mass_kg: 24}\n");
  EXPECT_NE(describeYamlRobot((t.dir / "exp.yaml").string()).find("quadruped.mass_kg        24 "), std::string::npos);
}

// --write-robot: the derived values as a tailsim robot file, read back exactly by the loader (so
// an experiment on it runs the planar models on them and records them in each result.json).
TEST(RobotImport, DerivedRobotFileLoadsBackExactly) {
  Scratch t("robot_import");
  std::string xml = boxRobot("");
  xml.replace(xml.find("</worldbody>"), 12,
              "</worldbody>\n<keyframe><key name=\"home\" qpos=\"0 0 0.3 1 0 0 0\"/></keyframe>");
  RobotModelSpec s;
  s.file = t.write("box.xml", xml);
  s.mount.pos_m = {-0.25, 0.0, 0.0};
  s.settle_s = 0.3;
  const DerivedRobot r = deriveRobot(s);
  RobotTailChoice c;
  const std::string path = t.write("box_robot.yaml", derivedRobotFile(r, c));
  const RobotFileData f = loadRobotFile(path);
  const QuadrupedParams& q = f.base.quadruped;
  EXPECT_EQ(q.mass_kg, r.quadruped.mass_kg);
  EXPECT_EQ(q.izz_kgm2, r.quadruped.izz_kgm2);
  EXPECT_EQ(q.d_Q2C_m, r.quadruped.d_Q2C_m);
  EXPECT_EQ(q.d_Q2B_m, r.quadruped.d_Q2B_m);
  EXPECT_EQ(q.l_F_m, r.quadruped.l_F_m);
  EXPECT_EQ(q.w_F_m, r.quadruped.w_F_m);
  EXPECT_EQ(q.com_height_m, r.quadruped.com_height_m);
  EXPECT_EQ(f.base.friction.mu_s, r.mu);
  ASSERT_EQ(f.tails.size(), 6u);
  EXPECT_NEAR(f.tails.at(1).mass_kg, 0.1 * r.quadruped.mass_kg, 1e-12);
  EXPECT_NEAR(f.tails.at(3).length_m * 3, r.quadruped.l_F_m, 1e-12);

  // `--write-robot FILE` (writeUserFile with the robot file's marker) replaces a robot file it
  // wrote, never the user's model: `tailsim robot box.xml --write-robot box.xml` once turned the
  // model into YAML.
  const std::string text = derivedRobotFile(r, c);
  EXPECT_FALSE(writeUserFile(path, text, kDerivedRobotFileMarker));
  std::string before;
  {
    std::ifstream in(s.file);
    before.assign(std::istreambuf_iterator<char>(in), {});
  }
  try {
    writeUserFile(s.file, text, kDerivedRobotFileMarker);
    ADD_FAILURE() << "the model file was replaced";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("box.xml exists and was not written by tailsim: not replaced"), std::string::npos)
        << e.what();
  }
  std::ifstream in(s.file);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), before);
}

}  // namespace

// The articulated run's sign conventions (tail mount, joint axis, stroke direction, heading): ANYmal C
// with its legs locked at the stance by joint equality constraints is a rigid robot on its own feet,
// so it must turn the way the rigid box of its derived parameters turns, and by about as much (mu 0.3,
// where both slip). The same file with the base turned 180 deg about z (facing +x instead of -x)
// must give the same phi_net: the heading is measured from where the robot stood.
TEST(RobotImport, AnymalWithLockedLegsTurnsLikeTheRigidBoxWhicheverWayItFaces) {
  REQUIRE_MENAGERIE(dir);
  Scratch t("robot_import");
  RobotModelSpec s = anymalSpec(dir);
  std::string xml;
  {
    std::ifstream in(s.file);
    std::string line;
    while (std::getline(in, line)) xml += line + "\n";
  }
  std::string eq = "<equality>\n";
  for (const char* leg : {"LF", "RF", "LH", "RH"})
    for (const char* j : {"_HAA", "_HFE", "_KFE"}) {
      const std::string name = std::string(leg) + j;
      const auto a = s.joint_angles_rad.find(name);
      char line[160];
      std::snprintf(line, sizeof line, "<joint joint1=\"%s\" polycoef=\"%.17g 0 0 0 0\" solref=\"0.002 1\"/>\n",
                    name.c_str(), a == s.joint_angles_rad.end() ? 0.0 : a->second);
      eq += line;
    }
  xml.replace(xml.find("<actuator>"), 0, eq + "</equality>\n");
  const std::string facingMinusX = "<body name=\"base\" pos=\"0 0 0.62\" quat=\"0 0 0 1\"";
  ASSERT_NE(xml.find(facingMinusX), std::string::npos);
  s.file = t.write("anymal_locked.xml", xml);
  s.mount.pos_m = {-0.35, 0.0, 0.0};
  s.mu = 0.3;
  RobotTailChoice tail;  // 10 %, l_F, 1 link, Eq. 25 at 600 deg/s
  const RobotComparison c = compareRobotModels(s, tail);
  std::printf("%s", describeComparison(c).c_str());
  ASSERT_TRUE(c.articulated.ok) << c.articulated.error;
  const ModelRow& box = c.rows.at(1);
  ASSERT_EQ(box.model, "mujoco (rigid box)");
  ASSERT_TRUE(box.ok);
  EXPECT_GT(box.phi_net_deg, 1.0);  // it slips at mu 0.3
  EXPECT_NEAR(c.articulated.phi_net_deg, box.phi_net_deg, 0.25 * box.phi_net_deg);
  EXPECT_LT(c.articulated.max_tilt_deg, 1.0);  // the legs are locked

  xml.replace(xml.find(facingMinusX), facingMinusX.size(), "<body name=\"base\" pos=\"0 0 0.62\" quat=\"1 0 0 0\"");
  s.file = t.write("anymal_locked_facing_x.xml", xml);
  const ArticulatedRun turned = runArticulated(deriveRobot(s), s.mount, c.tail, c.planar.trajectory(),
                                               c.planar.mujoco, tail.stand_s, tail.settle_after_s);
  ASSERT_TRUE(turned.ok) << turned.error;
  EXPECT_NEAR(turned.phi_net_deg, c.articulated.phi_net_deg, 0.02);
}

// A URDF robot: MuJoCo 2.2's URDF reader would fuse the root link into the world (no free joint);
// tailsim keeps it a body (fusestatic off) and gives it the free joint. A 10 kg box base and four
// 0.5 kg legs, two on revolute joints (held by tailsim's PD), two on fixed joints (their own bodies).
// Models in styles nobody here wrote (an outside review's findings, each a wrong number or a
// misleading error before): the helpers below build small robots in those styles.
namespace {

// A URDF quadruped: `base` (given by `base_link`), four legs on hinges `<leg>_j` at 0 (the stance),
// each a 0.5 kg link with a collision sphere 0.2 m below the hip.
struct UrdfLeg {
  const char* name;
  double x, y;
};
// A 10 kg base link with its collision box.
const char* kUrdfBoxBase = R"(<link name="base"><inertial><mass value="10"/>
  <inertia ixx="0.1" iyy="0.2" izz="0.25" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><geometry><box size="0.5 0.3 0.1"/></geometry></collision></link>
)";
constexpr UrdfLeg kUrdfLegs[] = {{"FL", 0.2, 0.12}, {"FR", 0.2, -0.12}, {"RR", -0.2, -0.12}, {"RL", -0.2, 0.12}};

// rear_joint: the rear legs' joint type ("fixed": welded, not held).
std::string urdfQuadruped(const std::string& base_link, double effort_Nm = 50.0, const char* rear_joint = "revolute") {
  std::string legs;
  for (const UrdfLeg& l : kUrdfLegs) {
    char b[1200];
    std::snprintf(b, sizeof b,
                  "<link name=\"%s\"><inertial><origin xyz=\"0 0 -0.1\"/><mass value=\"0.5\"/>"
                  "<inertia ixx=\"0.002\" iyy=\"0.002\" izz=\"0.0003\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>"
                  "<collision><origin xyz=\"0 0 -0.2\"/><geometry><sphere radius=\"0.02\"/></geometry></collision></link>\n"
                  "<joint name=\"%s_j\" type=\"%s\"><parent link=\"base\"/><child link=\"%s\"/>"
                  "<origin xyz=\"%g %g -0.05\"/><axis xyz=\"0 1 0\"/>"
                  "<limit lower=\"-1\" upper=\"1\" effort=\"%g\" velocity=\"10\"/></joint>\n",
                  l.name, l.name, l.x < 0 ? rear_joint : "revolute", l.name, l.x, l.y, effort_Nm);
    legs += b;
  }
  return "<robot name=\"bot\">\n" + base_link + legs + "</robot>\n";
}

RobotModelSpec urdfSpec(const std::string& file) {
  RobotModelSpec s;
  s.file = file;
  for (const char* j : {"FL_j", "FR_j", "RR_j", "RL_j"}) s.joint_angles_rad[j] = 0.0;
  s.settle_s = 0.3;
  return s;
}

const char* kAutolimits = "<compiler autolimits=\"true\"/>";

// An MJCF box robot whose four legs hang on hinges j1..j4 held by `actuators` (%J% = the joint).
std::string mjcfLegRobot(const std::string& compiler, const std::string& actuator, double stance_rad) {
  std::string legs, acts;
  const double xy[4][2] = {{0.2, 0.12}, {0.2, -0.12}, {-0.2, -0.12}, {-0.2, 0.12}};
  for (int i = 0; i < 4; ++i) {
    char b[700];
    std::snprintf(b, sizeof b,
                  "<body name=\"leg%d\" pos=\"%g %g -0.05\"><joint name=\"j%d\" axis=\"0 1 0\" range=\"-1 1\"/>"
                  "<inertial pos=\"0 0 -0.1\" mass=\"0.5\" diaginertia=\"0.002 0.002 0.0003\"/>"
                  "<geom name=\"f%d\" type=\"sphere\" size=\"0.02\" pos=\"0 0 -0.22\"/></body>\n",
                  i + 1, xy[i][0], xy[i][1], i + 1, i + 1);
    legs += b;
    std::string a = actuator;
    for (std::size_t p = a.find("%J%"); p != std::string::npos; p = a.find("%J%")) a.replace(p, 3, "j" + std::to_string(i + 1));
    acts += a;
  }
  char key[200];
  std::snprintf(key, sizeof key, "<keyframe><key name=\"home\" qpos=\"0 0 0.3 1 0 0 0 %g %g %g %g\"/></keyframe>",
                stance_rad, stance_rad, stance_rad, stance_rad);
  return "<mujoco model=\"legbot\">\n" + compiler + R"(
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1"/>
    <body name="trunk" pos="0 0 0.3">
      <freejoint/>
      <inertial pos="0 0 0" mass="10" diaginertia="0.1 0.2 0.25"/>
      <geom name="body_box" type="box" size="0.25 0.15 0.05"/>
)" + legs + "    </body>\n  </worldbody>\n  <actuator>" + acts + "</actuator>\n" + key + "\n</mujoco>\n";
}

}  // namespace

TEST(RobotImport, UrdfRobotKeepsItsRootLinkAndStands) {
  Scratch t("robot_import");
  const std::string urdf = urdfQuadruped(R"(<link name="base">
    <inertial><origin xyz="0.01 0 0"/><mass value="10"/>
      <inertia ixx="0.1" iyy="0.2" izz="0.25" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://boxbot/meshes/shell.stl"/></geometry></visual>
    <collision><geometry><box size="0.5 0.3 0.1"/></geometry></collision>
  </link>
)", 50.0, "fixed");
  RobotModelSpec s;
  s.file = t.write("boxbot.urdf", urdf);
  s.joint_angles_rad = {{"FL_j", 0.0}, {"FR_j", 0.0}};
  const DerivedRobot r = deriveRobot(s);
  std::printf("%s", describeDerivedRobot(r).c_str());
  EXPECT_TRUE(r.model.from_urdf);
  EXPECT_EQ(r.root_body, "base");
  EXPECT_EQ(r.pd_joints.size(), 2u);
  expectMujocoFigures(r, 10.0 + 4 * 0.5);
  // By hand: I_zz of the base and legs about the COM (x_c = 0.1 / 12), legs upright.
  const double xc = (10 * 0.01 + 0.5 * (0.2 + 0.2 - 0.2 - 0.2)) / 12.0;
  double izz = 0.25 + 10 * (0.01 - xc) * (0.01 - xc) + 4 * 0.0003;
  for (const UrdfLeg& l : kUrdfLegs) izz += 0.5 * ((l.x - xc) * (l.x - xc) + l.y * l.y);
  EXPECT_NEAR(r.quadruped.izz_kgm2, izz, 1e-4 * izz);
  EXPECT_NEAR(r.quadruped.l_F_m, 0.4, 1e-3);
  EXPECT_NEAR(r.quadruped.w_F_m, 0.24, 1e-9);
}

// Standing with the tail: the tilt that counts is the one from the robot's own settled stance. A
// rigid box robot whose front feet are 40 mm shorter stands pitched by atan(0.04 / 0.4) = 5.7 deg
// with or without a tail; holding the tail must not tilt it further, and no tilt warning is given.
// Legs driven by torque motors (Menagerie's Go2: <motor> actuators, a home keyframe whose ctrl
// are joint angles): tailsim's PD holds the joints and the motors' ctrl stays 0 while the robot
// stands with the tail. A motor given the stance angle as its ctrl would push each leg with
// gear x angle (here 50 x 0.3 = 15 N m) away from the stance.
TEST(RobotImport, MotorLegsAreHeldByThePdAndTheirCtrlStaysZero) {
  Scratch t("robot_import");
  // The motors' keyframe ctrl are the stance angles (Go2's are).
  std::string xml = mjcfLegRobot(kAutolimits, "<motor joint=\"%J%\" gear=\"50\"/>", 0.3);
  xml.replace(xml.find("0.3 0.3 0.3 0.3\"/>"), 18, "0.3 0.3 0.3 0.3\" ctrl=\"0.3 0.3 0.3 0.3\"/>");
  RobotModelSpec s;
  s.file = t.write("motorbot.xml", xml);
  s.mount.pos_m = {-0.25, 0.0, 0.0};
  s.settle_s = 0.3;
  RobotTailChoice tail;
  tail.stand_s = 0.5;
  const RobotComparison c = compareRobotModels(s, tail);
  EXPECT_EQ(c.robot.pd_joints.size(), 4u);
  EXPECT_NE(c.robot.stance.find("the model's 4 other joint actuators are not position servos"), std::string::npos)
      << c.robot.stance;
  const ArticulatedRun& a = c.articulated;
  ASSERT_TRUE(a.ok) << a.error;
  std::printf("stance: %s\ntrim: %d rounds, largest joint error %.3f deg; tilt from the stance %.3f deg\n",
              c.robot.stance.c_str(), a.trim.rounds, a.trim.residual_deg, a.stand_end_rel_tilt_deg);
  EXPECT_LT(a.trim.residual_deg, 1.0);
  EXPECT_LT(a.stand_max_rel_tilt_deg, 1.0);
}

TEST(RobotImport, TiltWithTheTailIsMeasuredFromTheStance) {
  Scratch t("robot_import");
  std::string xml = boxRobot("");
  for (const char* front : {"pos=\"0.2 0.12 -0.28\"", "pos=\"0.2 -0.12 -0.28\""}) {
    std::string shorter = front;
    shorter.replace(shorter.find("-0.28"), 5, "-0.24");
    xml.replace(xml.find(front), std::string(front).size(), shorter);
  }
  xml.replace(xml.find("</worldbody>"), 12,
              "</worldbody>\n<keyframe><key name=\"home\" qpos=\"0 0 0.3 1 0 0 0\"/></keyframe>");
  RobotModelSpec s;
  s.file = t.write("pitched_box.xml", xml);
  s.mount.pos_m = {-0.25, 0.0, 0.0};
  s.settle_s = 0.3;
  RobotTailChoice tail;
  tail.stand_s = 0.5;
  const RobotComparison c = compareRobotModels(s, tail);
  const ArticulatedRun& a = c.articulated;
  ASSERT_TRUE(a.ok) << a.error;
  const double pitch = std::atan(0.04 / 0.4) / kDeg;
  EXPECT_NEAR(a.stance_tilt_deg, pitch, 0.1);
  EXPECT_NEAR(a.stand_end_tilt_deg, pitch, 0.3);
  EXPECT_LT(a.stand_end_rel_tilt_deg, 0.3);
  EXPECT_LT(a.stand_max_rel_tilt_deg, 0.3);
  for (const std::string& w : a.warnings) EXPECT_EQ(w.find("tilted"), std::string::npos) << w;
  std::printf("stance %.3f, after standing %.3f abs / %.3f from the stance, stroke max %.3f / %.3f deg\n",
              a.stance_tilt_deg, a.stand_end_tilt_deg, a.stand_end_rel_tilt_deg, a.max_tilt_deg, a.max_rel_tilt_deg);
}

// A URDF robot has no actuators: tailsim's PD holds its joints. Its damper is the joints' own
// damping, which MuJoCo's Euler step treats implicitly; applied explicitly, kv = 5 N m s/rad on a
// 0.3 kg shank at the default 2 ms diverged during the stroke ("Nan, Inf or huge value in QACC").
TEST(RobotImport, UrdfLegsOnTailsimsPdStayStableThroughTheStroke) {
  Scratch t("robot_import");
  std::string legs;
  for (const auto& [name, x, y] : {std::tuple<const char*, double, double>{"FL", 0.2, 0.12}, {"FR", 0.2, -0.12},
                                   {"RR", -0.2, -0.12}, {"RL", -0.2, 0.12}}) {
    char b[1600];
    std::snprintf(b, sizeof b,
                  "<link name=\"%s_th\"><inertial><origin xyz=\"0 0 -0.1\"/><mass value=\"0.5\"/><inertia ixx=\"0.002\" "
                  "iyy=\"0.002\" izz=\"0.0003\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial><collision><origin xyz=\"0 0 -0.1\"/>"
                  "<geometry><cylinder radius=\"0.015\" length=\"0.2\"/></geometry></collision></link>\n"
                  "<joint name=\"%s_hip\" type=\"revolute\"><parent link=\"base\"/><child link=\"%s_th\"/><origin "
                  "xyz=\"%g %g -0.05\"/><axis xyz=\"0 1 0\"/><limit lower=\"-2\" upper=\"2\" effort=\"50\" velocity=\"10\"/></joint>\n"
                  "<link name=\"%s_sh\"><inertial><origin xyz=\"0 0 -0.1\"/><mass value=\"0.3\"/><inertia ixx=\"0.001\" "
                  "iyy=\"0.001\" izz=\"0.0002\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial><collision><origin xyz=\"0 0 -0.2\"/>"
                  "<geometry><sphere radius=\"0.02\"/></geometry></collision></link>\n"
                  "<joint name=\"%s_knee\" type=\"revolute\"><parent link=\"%s_th\"/><child link=\"%s_sh\"/><origin "
                  "xyz=\"0 0 -0.2\"/><axis xyz=\"0 1 0\"/><limit lower=\"-2.5\" upper=\"2.5\" effort=\"50\" velocity=\"10\"/></joint>\n",
                  name, name, name, x, y, name, name, name, name);
    legs += b;
  }
  RobotModelSpec s;
  s.file = t.write("bot.urdf", "<robot name=\"bot\"><link name=\"base\"><inertial><mass value=\"10\"/><inertia ixx=\"0.1\" "
                               "iyy=\"0.2\" izz=\"0.25\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial><collision><geometry>"
                               "<box size=\"0.5 0.3 0.1\"/></geometry></collision></link>\n" + legs + "</robot>\n");
  for (const char* leg : {"FL", "FR", "RR", "RL"}) {
    s.joint_angles_rad[std::string(leg) + "_hip"] = 20.0 * M_PI / 180.0;
    s.joint_angles_rad[std::string(leg) + "_knee"] = -40.0 * M_PI / 180.0;
  }
  s.mount.pos_m = {-0.3, 0.0, 0.0};
  RobotTailChoice tail;  // 10 %, l_F, 1 link, 600 deg/s, 2 s standing
  const RobotComparison c = compareRobotModels(s, tail);
  EXPECT_EQ(c.robot.pd_joints.size(), 8u);
  ASSERT_FALSE(c.rows.empty());
  EXPECT_TRUE(c.rows.front().ok) << (c.rows.front().warnings.empty() ? "" : c.rows.front().warnings.front());
  EXPECT_LT(c.articulated.stand_max_rel_tilt_deg, 1.0);
  EXPECT_LT(c.articulated.max_tilt_deg, 5.0);
  EXPECT_EQ(c.articulated.feet_in_contact, 4);
}

// A stance angle outside the joint's range is an error naming the joint and its range (before, the
// actuator's ctrlrange clamped it silently); a tail on a leg body is noted.
TEST(RobotImport, StanceOutsideAJointsRangeIsAnErrorAndALegMountIsNoted) {
  REQUIRE_MENAGERIE(dir);
  RobotModelSpec s;
  s.file = (dir / "go1" / "go1.xml").string();
  s.joint_angles_rad = {{"FR_hip_joint", 300.0 * M_PI / 180.0}};
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a stance at 300 deg was taken";
  } catch (const RobotImportError& e) {
    EXPECT_EQ(e.key(), "robot.stance");
    EXPECT_NE(std::string(e.what()).find("joint 'FR_hip_joint' at 300 deg is outside its range [-49.4463, 49.4463] deg"),
              std::string::npos)
        << e.what();
  }
  s.joint_angles_rad.clear();
  s.mount.body = "FR_calf";
  const DerivedRobot r = deriveRobot(s);
  bool noted = false;
  for (const std::string& n : r.notes) noted = noted || n.find("the tail is mounted on 'FR_calf'") != std::string::npos;
  EXPECT_TRUE(noted);
}

// A model path that is there but not a regular file is named as such, not "not found".
TEST(RobotImport, ADeviceAsTheModelFileIsNotARegularFile) {
  RobotModelSpec s;
  s.file = "/dev/zero";
  try {
    deriveRobot(s);
    ADD_FAILURE() << "/dev/zero was taken as a model file";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: the model file is not a regular file"), std::string::npos) << e.what();
  }
}

// A URDF whose collision mesh is missing: tailsim's error naming the link and the file (before,
// MuJoCo's own "could not open STL file" from inside its URDF reader).
TEST(RobotImport, UrdfCollisionMeshMissingNamesTheLinkAndFile) {
  Scratch t("robot_import");
  RobotModelSpec s;
  s.file = t.write("bot.urdf", R"(<robot name="bot"><link name="base"><inertial><mass value="10"/>
<inertia ixx="0.1" iyy="0.2" izz="0.25" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><mesh filename="package://bot/meshes/shell.stl"/></geometry></collision></link></robot>
)");
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a URDF with a missing collision mesh was read";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("1 colliding geom has a missing mesh file: a collision of link 'base': its mesh "
                                         "package://bot/meshes/shell.stl is missing (looked for " +
                                         (t.dir / "shell.stl").string() + ")"),
              std::string::npos)
        << e.what();
  }
}

namespace {

// A URDF link without <inertial> weighs nothing (URDF's rule), not its collision geoms' mass at
// density 1000 (MuJoCo's default): the ANYmal pattern, a `base` link holding only a collision box,
// its 10 kg on a link fixed to it. Before: 15 kg more (the 0.5 x 0.3 x 0.1 m box).
TEST(RobotImport, UrdfLinkWithoutInertialWeighsNothing) {
  Scratch t("robot_import");
  const std::string base = R"(<link name="base"><collision><geometry><box size="0.5 0.3 0.1"/></geometry></collision></link>
<link name="base_inertia"><inertial><origin xyz="0.01 0 0"/><mass value="10"/>
  <inertia ixx="0.1" iyy="0.2" izz="0.25" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="base_to_inertia" type="fixed"><parent link="base"/><child link="base_inertia"/></joint>
)";
  const DerivedRobot r = deriveRobot(urdfSpec(t.write("bot.urdf", urdfQuadruped(base))));
  EXPECT_EQ(r.root_body, "base");
  expectMujocoFigures(r, 10.0 + 4 * 0.5);
  // The URDF's own setting wins: mass from the collision geoms when it asks for it.
  std::string asked = urdfQuadruped(base);
  asked.replace(asked.find('\n') + 1, 0, "<mujoco><compiler inertiafromgeom=\"auto\"/></mujoco>\n");
  const DerivedRobot a = deriveRobot(urdfSpec(t.write("asked.urdf", asked)));
  EXPECT_NEAR(a.quadruped.mass_kg, 10.0 + 4 * 0.5 + 1000 * 0.5 * 0.3 * 0.1, 1e-6);
}

// A URDF's collision geoms have no names: its feet are named by their links (bodies).
TEST(RobotImport, FeetNamedByTheirBodies) {
  Scratch t("robot_import");
  const std::string base = kUrdfBoxBase;
  RobotModelSpec s = urdfSpec(t.write("bot.urdf", urdfQuadruped(base)));
  s.feet = {"RL", "FL", "FR", "RR"};
  const DerivedRobot r = deriveRobot(s);
  ASSERT_EQ(r.feet.size(), 4u);
  EXPECT_NE(r.feet[0].find("of body 'FL'"), std::string::npos) << r.feet[0];  // ordered FL, FR, RR, RL
  EXPECT_NEAR(r.quadruped.l_F_m, 0.4, 1e-3);
  s.feet = {"RL", "FL", "FR", "nobody"};
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a foot named after nothing was taken";
  } catch (const RobotImportError& e) {
    EXPECT_EQ(e.key(), "robot.feet");
    EXPECT_NE(std::string(e.what()).find("feet: no geom or body named 'nobody'"), std::string::npos) << e.what();
  }
}

// A <position> servo with gear 2 holds its joint where ctrl = 2 q: given ctrl = q it held the legs
// at half the stance angle (a robot that stood at gear 1 fell over at gear 2). A stance whose ctrl
// is outside the ctrlrange is an error naming the actuator (MuJoCo would clamp it silently).
TEST(RobotImport, PositionServosHoldTheStanceThroughTheirGearAndRange) {
  Scratch t("robot_import");
  RobotModelSpec s;
  s.settle_s = 0.3;
  // gear 2 at kp 400 is the joint stiffness of gear 1 at kp 1600: the same stance, the same settling.
  s.file = t.write("gear1.xml", mjcfLegRobot(kAutolimits, "<position joint=\"%J%\" kp=\"1600\"/>", 0.3));
  const DerivedRobot r1 = deriveRobot(s);
  s.file = t.write("gear2.xml", mjcfLegRobot(kAutolimits, "<position joint=\"%J%\" kp=\"400\" gear=\"2\"/>", 0.3));
  const DerivedRobot r = deriveRobot(s);
  EXPECT_LT(r.tilt_deg, 1.0);
  for (const char* j : {"j1", "j2", "j3", "j4"}) {
    EXPECT_NEAR(r.settled_qpos.at(j).at(0), r1.settled_qpos.at(j).at(0), 1e-9) << j;
    EXPECT_NEAR(r.settled_qpos.at(j).at(0), 0.3, 0.06) << j;  // ctrl = q held it near 0.15
  }
  s.file = t.write("clamp.xml", mjcfLegRobot(kAutolimits, "<position name=\"a_%J%\" joint=\"%J%\" kp=\"400\" ctrlrange=\"-0.2 0.2\"/>", 0.3));
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a stance outside the ctrlrange was taken";
  } catch (const RobotImportError& e) {
    EXPECT_EQ(e.key(), "robot.stance");
    EXPECT_NE(std::string(e.what()).find("actuator 'a_j1' cannot hold joint 'j1' at its stance angle 17.1887 deg: that "
                                         "needs ctrl 0.3, outside its ctrlrange [-0.2, 0.2]"),
              std::string::npos)
        << e.what();
  }
}

// The compiler's settings as MuJoCo applies them: global coordinates are refused (the tail is
// attached in local ones: before, it hung at the world origin); a joint MuJoCo 2.2 refuses is named
// at its line in the user's file, with the hint for files written for MuJoCo >= 2.3.
TEST(RobotImport, CompilerSettingsAsMujocoAppliesThem) {
  Scratch t("robot_import");
  RobotModelSpec s;
  s.file = t.write("global.xml", mjcfLegRobot("<compiler coordinate=\"global\" autolimits=\"true\"/>",
                                              "<position joint=\"%J%\" kp=\"400\"/>", 0.0));
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a model in global coordinates was taken";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("global.xml: the model is written in global coordinates"), std::string::npos)
        << e.what();
  }
  const std::string text = mjcfLegRobot("", "<position joint=\"%J%\" kp=\"400\"/>", 0.0);
  s.file = t.write("nolimits.xml", text);
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + text.find("name=\"j1\""), '\n'));
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a range without limited was taken by MuJoCo 2.2";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("nolimits.xml:" + std::to_string(line) + ": MuJoCo 2.2 refuses the model"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("add <compiler autolimits=\"true\"/>"), std::string::npos) << e.what();
  }
}

// A binary STL tetrahedron (MuJoCo 2.2 reads binary STL).
void writeTetrahedronStl(const fs::path& file) {
  const float v[4][3] = {{0, 0, 0}, {0.05f, 0, 0}, {0, 0.05f, 0}, {0, 0, 0.05f}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::ofstream out(file, std::ios::binary);
  const std::string header(80, ' ');
  out.write(header.data(), 80);
  const uint32_t n = 4;
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& tri : f) {
    const float normal[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), 12);
    for (int k : tri) out.write(reinterpret_cast<const char*>(v[k]), 12);
    const uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

// A scene with its own <compiler> before it includes the robot, whose <compiler meshdir> names the
// mesh folder: the last setting wins, as in MuJoCo (before, the scene's compiler was the only one
// read, and the robot's colliding mesh was looked for beside the scene).
TEST(RobotImport, TheLastCompilerSettingWins) {
  Scratch t("robot_import");
  fs::create_directories(t.dir / "assets");
  writeTetrahedronStl(t.dir / "assets" / "shell.stl");
  std::string robot = mjcfLegRobot("<compiler meshdir=\"assets\" autolimits=\"true\"/>\n  <asset><mesh name=\"shell\" file=\"shell.stl\"/></asset>",
                                   "<position joint=\"%J%\" kp=\"400\"/>", 0.0);
  robot.replace(robot.find("<geom name=\"body_box\""), 0, "<geom name=\"shell\" type=\"mesh\" mesh=\"shell\" pos=\"0 0 0.05\"/>\n      ");
  robot.replace(robot.find("<geom name=\"floor\" type=\"plane\" size=\"0 0 1\"/>"), 45, "");
  t.write("bot.xml", robot);
  RobotModelSpec s;
  s.settle_s = 0.3;
  s.file = t.write("scene.xml", R"(<mujoco model="scene">
  <compiler autolimits="true"/>
  <include file="bot.xml"/>
  <worldbody><geom name="floor" type="plane" size="0 0 1"/></worldbody>
</mujoco>
)");
  const DerivedRobot r = deriveRobot(s);
  EXPECT_EQ(r.model.dropped_geoms, 0);
  EXPECT_EQ(r.feet.size(), 4u);
}

}  // namespace

namespace {

// A ground that is a box, not a plane: an error saying so (before, tailsim added its plane at z = 0
// as well, and the robot stood on either, or inside the box).
TEST(RobotImport, AGroundThatIsNotAPlaneIsNamed) {
  Scratch t("robot_import");
  std::string xml = mjcfLegRobot(kAutolimits, "<position joint=\"%J%\" kp=\"400\"/>", 0.0);
  xml.replace(xml.find("<geom name=\"floor\" type=\"plane\" size=\"0 0 1\"/>"), 45,
              "<geom name=\"ground\" type=\"box\" size=\"3 3 0.05\" pos=\"0 0 -0.05\"/>");
  RobotModelSpec s;
  s.file = t.write("boxground.xml", xml);
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a box ground was taken";
  } catch (const RobotImportError& e) {
    EXPECT_NE(std::string(e.what()).find("the model has no plane to stand on, but a static colliding geom 'ground' (box, line 4)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace

namespace {

// Legs held by tailsim's PD stay within the joint's own torque limit (the URDF's effort, a motor's
// ctrlrange x gear): a robot too weak to hold its stance sags and says so; before, the PD's 200 N
// m/rad held any robot up.
TEST(RobotImport, ThePdKeepsWithinTheJointsTorqueLimit) {
  Scratch t("robot_import");
  const std::string base = kUrdfBoxBase;
  RobotModelSpec s = urdfSpec(t.write("strong.urdf", urdfQuadruped(base, 50.0)));
  for (auto& [j, q] : s.joint_angles_rad) q = 0.4;
  const DerivedRobot r = deriveRobot(s);
  EXPECT_EQ(r.pd_torque_limit_Nm.at("FL_j"), 50.0);
  EXPECT_NE(r.stance.find("its torque kept within the joint's own limit on 4 of them: 50 N m"), std::string::npos) << r.stance;
  EXPECT_EQ(r.stance.find("at their torque limit"), std::string::npos) << r.stance;
  s.file = t.write("weak.urdf", urdfQuadruped(base, 0.2));  // 2.6 kg a leg at ~0.08 m needs ~2 N m
  std::string what;
  try {
    const DerivedRobot w = deriveRobot(s);
    what = w.stance;
  } catch (const RobotImportError& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("4 of them at their torque limit (FL_j, FR_j, RR_j, RL_j): the legs cannot hold the stance"),
            std::string::npos)
      << what;
}

}  // namespace

namespace {

// A fall of the articulated robot whose leg servos are too stiff for the model's step (w_n h > 1)
// says the step may be the cause: the same file at a quarter of the step stands and turns.
TEST(RobotImport, AFallAtATooCoarseStepSaysSo) {
  Scratch t("robot_import");
  std::ifstream in(fs::path(TAILSIM_SOURCE_DIR) / "tests" / "data" / "light_quadruped.xml");
  const std::string xml(std::istreambuf_iterator<char>(in), {});
  RobotModelSpec s;
  s.file = t.write("light.xml", xml);
  s.mount.pos_m = {-0.3, 0.0, 0.0};
  RobotTailChoice tail;
  const RobotComparison coarse = compareRobotModels(s, tail);
  EXPECT_FALSE(coarse.articulated.ok);
  EXPECT_NE(coarse.articulated.error.find("its stiffest leg servo has w_n h = 1.32 > 1 at the model's timestep (0.002 s)"),
            std::string::npos)
      << coarse.articulated.error;
  std::string fine = xml;
  fine.replace(fine.find("<worldbody>"), 0, "<option timestep=\"0.0005\"/>\n  ");
  s.file = t.write("light_fine.xml", fine);
  const RobotComparison ok = compareRobotModels(s, tail);
  EXPECT_TRUE(ok.articulated.ok) << ok.articulated.error;
}

}  // namespace

namespace {

// A robot whose legs give way is not measured lying on its body (an outside review's 200 kg robot
// on kp 100 servos had its trunk and thighs taken as feet); one that still rocks after settle_s
// stands on until it rests, or says that it has not.
TEST(RobotImport, ARobotMustStandAndRestBeforeItIsMeasured) {
  Scratch t("robot_import");
  RobotModelSpec s;
  s.settle_s = 0.3;
  // tests/data/light_quadruped.xml at 200 kg: its kp 100 servos cannot carry it.
  std::ifstream in(fs::path(TAILSIM_SOURCE_DIR) / "tests" / "data" / "light_quadruped.xml");
  std::string heavy(std::istreambuf_iterator<char>(in), {});
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"mass=\"0.3\" diaginertia=\"0.003 0.006 0.0075\"", "mass=\"176\" diaginertia=\"1.76 3.52 4.4\""},
           {"mass=\"0.033\" diaginertia=\"0.000132 0.000132 3.3e-05\"", "mass=\"4\" diaginertia=\"0.016 0.016 0.004\""},
           {"mass=\"0.0165\" diaginertia=\"6.6e-05 6.6e-05 1.65e-05\"", "mass=\"2\" diaginertia=\"0.008 0.008 0.002\""}})
    for (std::size_t p = heavy.find(from); p != std::string::npos; p = heavy.find(from)) heavy.replace(p, from.size(), to);
  s.file = t.write("heavy.xml", heavy);
  try {
    deriveRobot(s);
    ADD_FAILURE() << "a robot whose legs gave way was measured";
  } catch (const RobotImportError& e) {
    EXPECT_EQ(e.key(), "robot.stance");
    EXPECT_NE(std::string(e.what()).find("its legs do not hold the stance"), std::string::npos) << e.what();
  }
  s.file = t.write("firm.xml", mjcfLegRobot(kAutolimits, "<position joint=\"%J%\" kp=\"400\"/>", 0.3));
  const DerivedRobot r = deriveRobot(s);
  const auto noted = [&](const DerivedRobot& d, const std::string& text) {
    return std::any_of(d.notes.begin(), d.notes.end(), [&](const std::string& n) { return n.find(text) != std::string::npos; });
  };
  EXPECT_FALSE(noted(r, "the body still moves")) << describeDerivedRobot(r);
  EXPECT_TRUE(noted(r, "then stood ")) << describeDerivedRobot(r);
}

}  // namespace
