// The generated MJCF compiles to a MuJoCo model whose masses, inertias, COMs, foot and tail
// geometry equal the robot parameters (read back from mjModel / mjData, not from the XML).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"

using namespace tailsim;

namespace {

// A robot with non-default numbers everywhere, so a swapped or hard-coded value shows.
RobotParams oddRobot() {
  RobotParams p;
  p.quadruped = {7.3, 0.17, 0.021, 0.1405, 0.33, 0.24};
  p.tail = {{1.1, 4e-3, 0.14, 0.06}, {0.7, 2e-3, 0.11, 0.05}, {0.45, 7e-4, 0.09, 0.03}};
  p.gravity_mps2 = 9.5;
  return p;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

class MujocoModelParams : public ::testing::TestWithParam<int> {};

TEST_P(MujocoModelParams, CompiledModelEqualsParameters) {
  const int which = GetParam();  // 1..6: paper robot with n links; 0: oddRobot
  const RobotParams p = which > 0 ? paperRobot(which) : oddRobot();
  const MujocoSettings s;
  ModelPtr model = loadModelFromXml(generateMjcf(p, s, Effects{}));
  const mjModel* m = model.get();
  DataPtr data = makeData(m);
  mjData* d = data.get();
  mj_resetDataKeyframe(m, d, mj_name2id(m, mjOBJ_KEY, "home"));
  mj_forward(m, d);
  const double tol = 1e-12;
  const int n = p.numLinks();
  EXPECT_EQ(m->nu, n);
  EXPECT_EQ(m->nv, 6 + n);

  // Quadruped: mass, Izz exact, COM at the body origin, body at the nominal height.
  const int q = bodyId(m, "quadruped");
  EXPECT_NEAR(m->body_mass[q], p.quadruped.mass_kg, tol);
  EXPECT_NEAR(m->body_inertia[3 * q + 2], p.quadruped.izz_kgm2, tol);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(m->body_ipos[3 * q + a], 0.0, tol);
  EXPECT_NEAR(m->body_iquat[4 * q], 1.0, tol);  // principal axes = body axes
  EXPECT_NEAR(m->body_subtreemass[q], p.systemMass(), 1e-12);  // Eq. (10)
  const double h = s.body_height_m;
  EXPECT_NEAR(d->xpos[3 * q + 2], h, tol);

  // Feet: Eq. (17) positions relative to the quadruped COM; sphere bottoms touch z = 0.
  for (int k = 1; k <= 4; ++k) {
    const int g = geomId(m, mjcf::footGeomName(k));
    const double sx = (k == 1 || k == 2) ? 1 : -1, sy = (k == 1 || k == 4) ? 1 : -1;
    EXPECT_NEAR(d->geom_xpos[3 * g] - d->xpos[3 * q], p.quadruped.d_Q2C_m + sx * 0.5 * p.quadruped.l_F_m, tol);
    EXPECT_NEAR(d->geom_xpos[3 * g + 1] - d->xpos[3 * q + 1], sy * 0.5 * p.quadruped.w_F_m, tol);
    EXPECT_NEAR(d->geom_xpos[3 * g + 2] - m->geom_size[3 * g], 0.0, tol);
    EXPECT_EQ(m->geom_type[g], mjGEOM_SPHERE);
    EXPECT_EQ(m->geom_contype[g], 1);
    EXPECT_NEAR(m->geom_friction[3 * g], std::max(p.friction.mu_s, p.friction.mu_d), tol);
    EXPECT_EQ(m->geom_condim[g], s.condim);
  }

  // Tail: base at -d_Q2B x at the COM height, R_B = R_Z(180 deg) (Eq. 1-2), joint i at the end of
  // link i-1 (Eq. 3), COM at com_offset along the link, exact mass and Izz, z hinges, no contacts.
  double jx = -p.quadruped.d_Q2B_m;  // world x of joint i with the tail straight (theta = 0)
  for (int i = 1; i <= n; ++i) {
    const TailLink& l = p.tail[i - 1];
    const int b = bodyId(m, mjcf::tailBodyName(i));
    const int j = jointId(m, mjcf::tailJointName(i));
    EXPECT_NEAR(m->body_mass[b], l.mass_kg, tol);
    EXPECT_NEAR(m->body_inertia[3 * b + 2], l.izz_kgm2, tol);
    EXPECT_NEAR(d->xpos[3 * b], jx, tol);
    EXPECT_NEAR(d->xpos[3 * b + 1], 0.0, tol);
    EXPECT_NEAR(d->xpos[3 * b + 2], h, tol);
    EXPECT_NEAR(d->xmat[9 * b], -1.0, tol);  // link x axis points along -x of the body
    EXPECT_NEAR(d->xipos[3 * b], jx - l.com_offset_m, tol);
    EXPECT_EQ(m->jnt_type[j], mjJNT_HINGE);
    EXPECT_NEAR(d->xaxis[3 * j + 2], 1.0, tol);
    jx -= l.length_m;
    for (int g = 0; g < m->ngeom; ++g)
      if (m->geom_bodyid[g] == b) {
        EXPECT_EQ(m->geom_contype[g] | m->geom_conaffinity[g], 0);
      }
    // Servo: gain kp, bias (0, -kp, -kv) with the documented gain rule.
    const int a = actuatorId(m, mjcf::tailActuatorName(i));
    const ServoGains gains = tailServoGains(p, s);
    EXPECT_NEAR(m->actuator_gainprm[a * mjNGAIN], gains.kp[i - 1], 1e-9 * gains.kp[i - 1]);
    EXPECT_NEAR(m->actuator_biasprm[a * mjNBIAS + 1], -gains.kp[i - 1], 1e-9 * gains.kp[i - 1]);
    EXPECT_NEAR(m->actuator_biasprm[a * mjNBIAS + 2], -gains.kv[i - 1], 1e-9 * gains.kv[i - 1]);
  }

  // System COM and Izz about it (Eqs. 10-12) computed by hand for the straight tail.
  double mx = p.quadruped.mass_kg * 0.0, msum = p.quadruped.mass_kg;
  std::vector<double> xl;
  double x = -p.quadruped.d_Q2B_m;
  for (const TailLink& l : p.tail) {
    xl.push_back(x - l.com_offset_m);
    mx += l.mass_kg * xl.back();
    msum += l.mass_kg;
    x -= l.length_m;
  }
  const double xc = mx / msum;
  EXPECT_NEAR(d->subtree_com[3 * q], xc, 1e-12);
  double izz = p.quadruped.izz_kgm2 + p.quadruped.mass_kg * xc * xc;
  for (size_t i = 0; i < p.tail.size(); ++i)
    izz += p.tail[i].izz_kgm2 + p.tail[i].mass_kg * (xl[i] - xc) * (xl[i] - xc);
  double izz_mj = 0.0;  // from MuJoCo's composite inertia about the world origin, shifted to the COM
  for (int b = 1; b < m->nbody; ++b) {
    const double dx = d->xipos[3 * b] - xc, dy = d->xipos[3 * b + 1];
    izz_mj += m->body_inertia[3 * b + 2] + m->body_mass[b] * (dx * dx + dy * dy);
  }
  EXPECT_NEAR(izz_mj, izz, 1e-12);
  // Gravity as configured.
  EXPECT_NEAR(m->opt.gravity[2], -p.gravity_mps2, tol);
}

INSTANTIATE_TEST_SUITE_P(Robots, MujocoModelParams, ::testing::Values(0, 1, 2, 3, 4, 5, 6));

TEST(MujocoModel, EffectsAndSettingsReachTheModel) {
  const RobotParams p = paperRobot(2);
  MujocoSettings s;
  s.timestep_s = 5e-4;
  s.integrator = MujocoIntegrator::kEuler;
  s.solver = MujocoSolver::kCG;
  s.iterations = 37;
  s.cone = MujocoCone::kPyramidal;
  s.noslip_iterations = 3;
  s.impratio = 2.5;
  s.mu = 0.42;
  s.torsional_friction_m = 0.003;
  s.condim = 4;
  s.foot_shape = MujocoFootShape::kCapsule;
  s.foot_half_length_m = 0.013;
  s.solref = {0.004, 0.9};
  Effects e;
  ModelPtr m = loadModelFromXml(generateMjcf(p, s, e));
  EXPECT_DOUBLE_EQ(m->opt.timestep, 5e-4);
  EXPECT_EQ(m->opt.integrator, mjINT_EULER);
  EXPECT_EQ(m->opt.solver, mjSOL_CG);
  EXPECT_EQ(m->opt.iterations, 37);
  EXPECT_EQ(m->opt.cone, mjCONE_PYRAMIDAL);
  EXPECT_EQ(m->opt.noslip_iterations, 3);
  EXPECT_DOUBLE_EQ(m->opt.impratio, 2.5);
  const int g = geomId(m.get(), mjcf::footGeomName(3));
  EXPECT_DOUBLE_EQ(m->geom_friction[3 * g], 0.42);
  EXPECT_DOUBLE_EQ(m->geom_friction[3 * g + 1], 0.003);
  EXPECT_DOUBLE_EQ(m->geom_friction[3 * g + 2], 0.0);
  EXPECT_EQ(m->geom_condim[g], 4);
  EXPECT_EQ(m->geom_type[g], mjGEOM_CAPSULE);
  EXPECT_DOUBLE_EQ(m->geom_size[3 * g], s.foot_radius_m);
  EXPECT_DOUBLE_EQ(m->geom_size[3 * g + 1], 0.013);
  EXPECT_DOUBLE_EQ(m->geom_solref[mjNREF * g], 0.004);
  EXPECT_DOUBLE_EQ(m->geom_solref[mjNREF * g + 1], 0.9);

  e.friction = FrictionLaw::kNone;
  e.gravity = false;
  m = loadModelFromXml(generateMjcf(p, s, e));
  EXPECT_EQ(m->geom_condim[geomId(m.get(), mjcf::footGeomName(1))], 1);
  EXPECT_EQ(m->opt.gravity[2], 0.0);
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_GRAVITY);

  e = Effects{};
  e.ground_contact = false;
  e.translation = false;
  m = loadModelFromXml(generateMjcf(p, s, e));
  EXPECT_LT(mj_name2id(m.get(), mjOBJ_GEOM, mjcf::kFloorGeom), 0);
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_CONTACT);
  EXPECT_EQ(m->jnt_type[jointId(m.get(), mjcf::kRootJoint)], mjJNT_BALL);
  EXPECT_EQ(m->jnt_type[jointId(m.get(), mjcf::kHeightJoint)], mjJNT_SLIDE);
  EXPECT_EQ(m->nv, 4 + 2);

  e = Effects{};
  e.friction = FrictionLaw::kContinuous;  // mu(0) = 0 until the first step updates it
  m = loadModelFromXml(generateMjcf(p, MujocoSettings{}, e));
  EXPECT_EQ(m->geom_friction[3 * geomId(m.get(), mjcf::footGeomName(1))], 0.0);
}

// mujoco.foot_shape reaches mjModel (geom type, size, capsule axis along body x), and the robot
// stands on each shape: after 0.3 s with the tail held, the feet's contact normal forces carry
// m g, the body sits at body_height_m (the lowest point / bottom face of every shape at z = 0,
// less the soft contact's penetration) and each foot touches at 1 (sphere), 2 (capsule: the end
// caps) or 4 (box: the bottom corners) points.
TEST(MujocoModel, FootShapeReachesTheModelAndTheRobotStandsOnIt) {
  const RobotParams p = paperRobot(1);
  const double mg = p.systemMass() * p.gravity_mps2;
  struct Shape {
    MujocoFootShape shape;
    int type, contacts_per_foot;
  };
  double z_sphere = NAN;
  for (const Shape& sh : {Shape{MujocoFootShape::kSphere, mjGEOM_SPHERE, 1}, Shape{MujocoFootShape::kCapsule, mjGEOM_CAPSULE, 2},
                          Shape{MujocoFootShape::kBox, mjGEOM_BOX, 4}}) {
    SCOPED_TRACE(name(sh.shape));
    MujocoSettings s;
    s.foot_shape = sh.shape;
    s.foot_radius_m = 0.012;
    s.foot_half_length_m = 0.017;
    ModelPtr model = loadModelFromXml(generateMjcf(p, s, Effects{}));
    mjModel* m = model.get();
    for (int k = 1; k <= 4; ++k) {
      const int g = geomId(m, mjcf::footGeomName(k));
      EXPECT_EQ(m->geom_type[g], sh.type);
      EXPECT_DOUBLE_EQ(m->geom_size[3 * g], 0.012);
      if (sh.shape == MujocoFootShape::kCapsule) {
        EXPECT_DOUBLE_EQ(m->geom_size[3 * g + 1], 0.017);
        // geom z axis (the capsule's) along body x: R(q) e_z = e_x.
        const mjtNum* q = m->geom_quat + 4 * g;
        const double zx = 2 * (q[1] * q[3] + q[0] * q[2]), zy = 2 * (q[2] * q[3] - q[0] * q[1]);
        EXPECT_NEAR(zx, 1.0, 1e-9);
        EXPECT_NEAR(zy, 0.0, 1e-9);
      }
      if (sh.shape == MujocoFootShape::kBox) {
        EXPECT_DOUBLE_EQ(m->geom_size[3 * g + 1], 0.012);
        EXPECT_DOUBLE_EQ(m->geom_size[3 * g + 2], 0.012);
      }
      // Centre foot_radius_m above the floor with the body at body_height_m.
      EXPECT_NEAR(m->geom_pos[3 * g + 2], -(s.body_height_m - 0.012), 1e-12);
    }
    DataPtr data = makeData(m);
    mjData* d = data.get();
    for (int i = 0; i < static_cast<int>(0.3 / s.timestep_s); ++i) mj_step(m, d);
    double fn = 0.0;
    std::array<int, 4> touches{};
    for (int i = 0; i < d->ncon; ++i) {
      mjtNum f6[6];
      mj_contactForce(m, d, i, f6);
      fn += f6[0];
      for (int k = 1; k <= 4; ++k)
        if (d->contact[i].geom1 == geomId(m, mjcf::footGeomName(k)) || d->contact[i].geom2 == geomId(m, mjcf::footGeomName(k)))
          ++touches[k - 1];
    }
    EXPECT_NEAR(fn, mg, 0.02 * mg);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(touches[k], sh.contacts_per_foot) << "foot " << k + 1;
    const double z = d->xpos[3 * mj_name2id(m, mjOBJ_BODY, mjcf::kQuadrupedBody) + 2];
    EXPECT_LT(z, s.body_height_m);
    EXPECT_GT(z, s.body_height_m - 2e-3);
    if (sh.shape == MujocoFootShape::kSphere) z_sphere = z;
    else EXPECT_NEAR(z, z_sphere, 1e-3);
  }
}

TEST(MujocoModel, BadSettingsAreRejectedByName) {
  MujocoSettings s;
  s.integrator = static_cast<MujocoIntegrator>(9);  // not a declared integrator
  try {
    generateMjcf(paperRobot(1), s, Effects{});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("integrator"), std::string::npos) << e.what();
  }
}

TEST(MujocoModel, CompileErrorsBecomeExceptionsWithMujocoText) {
  try {
    loadModelFromXml("<mujoco><worldbody><geom type='sphere' size='-1' nonsense='3'/></worldbody></mujoco>");
    FAIL() << "expected MujocoError";
  } catch (const MujocoError& e) {
    EXPECT_NE(std::string(e.what()).find("nonsense"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loadModelFromFile("/nonexistent/tail.xml"), MujocoError);
}

TEST(MujocoModel, MjcfFilesAreUpToDate) {
  // mjcf/tail_n<N>.xml = writeMjcfFile(N, ...): regenerate with `tailsim mjcf --links N --out FILE`.
  for (int n = 1; n <= 6; ++n) {
    const std::string path = std::string(TAILSIM_SOURCE_DIR) + "/mjcf/tail_n" + std::to_string(n) + ".xml";
    const std::string expected = generateMjcf(paperRobot(n), MujocoSettings{}, Effects{});
    EXPECT_EQ(readFile(path), expected) << path << " is stale: regenerate it with writeMjcfFile(" << n << ", ...)";
    EXPECT_NO_THROW(loadModelFromFile(path));
  }
}
