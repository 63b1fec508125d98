// Cross-check of the two models' tail dynamics: MuJoCo's inverse dynamics of the generated model
// (base held still, gravity and contacts off) equals the analytic recursive Newton-Euler tail
// base load of Eqs. (5)-(8) (models/planar/tail_dynamics.h) at random tail states.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "models/planar/tail_dynamics.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"

using namespace tailsim;

namespace {

void crossCheck(const RobotParams& p, int samples, unsigned seed) {
  Effects e;
  e.gravity = false;
  e.ground_contact = false;
  ModelPtr model = loadModelFromXml(generateMjcf(p, MujocoSettings{}, e));
  const mjModel* m = model.get();
  DataPtr data = makeData(m);
  mjData* d = data.get();
  const int n = p.numLinks();
  const int q = bodyId(m, mjcf::kQuadrupedBody);
  const int l1 = bodyId(m, mjcf::tailBodyName(1));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ang(-M_PI, M_PI), vel(-15.0, 15.0), acc(-400.0, 400.0);
  for (int s = 0; s < samples; ++s) {
    mj_resetDataKeyframe(m, d, mj_name2id(m, mjOBJ_KEY, mjcf::kHomeKey));
    std::vector<JointState> js(n);
    for (int i = 0; i < n; ++i) {
      js[i] = {ang(rng), vel(rng), acc(rng)};
      const int j = jointId(m, mjcf::tailJointName(i + 1));
      d->qpos[m->jnt_qposadr[j]] = js[i].theta;
      d->qvel[m->jnt_dofadr[j]] = js[i].theta_dot;
    }
    mj_forward(m, d);
    // Base still: zero velocity and acceleration of the quadruped's dofs; tail at the sample.
    for (int v = 0; v < m->nv; ++v) d->qacc[v] = 0.0;
    for (int i = 0; i < n; ++i) d->qacc[m->jnt_dofadr[jointId(m, mjcf::tailJointName(i + 1))]] = js[i].theta_ddot;
    mj_inverse(m, d);
    mj_rnePostConstraint(m, d);

    const TailLoad ref = tailBaseLoad(p.tail, js);
    // cfrc_int of link 1: (torque, force) the base applies to the tail, at the system COM, world
    // axes. B = body rotated by 180 deg about z (Eq. 1), body at yaw 0: world = -B in x and y.
    const mjtNum* f = d->cfrc_int + 6 * l1;
    const double Fx = -ref.F_J1_B.x(), Fy = -ref.F_J1_B.y();
    const double scale_f = std::max(1.0, std::hypot(Fx, Fy));
    EXPECT_NEAR(f[3], Fx, 1e-9 * scale_f);
    EXPECT_NEAR(f[4], Fy, 1e-9 * scale_f);
    EXPECT_NEAR(f[5], 0.0, 1e-9 * scale_f);
    // z moment about joint 1: move the torque from the system COM to the joint.
    const mjtNum* c = d->subtree_com + 3 * q;
    const mjtNum* pj = d->xanchor + 3 * jointId(m, mjcf::tailJointName(1));
    const double mz_joint = f[2] + ((c[0] - pj[0]) * f[4] - (c[1] - pj[1]) * f[3]);
    const double scale_m = std::max(1.0, std::abs(ref.M_J1));
    EXPECT_NEAR(mz_joint, ref.M_J1, 1e-9 * scale_m);
    // The joint-1 torque of MuJoCo's inverse dynamics is the same z moment (hinge through joint 1).
    EXPECT_NEAR(d->qfrc_inverse[m->jnt_dofadr[jointId(m, mjcf::tailJointName(1))]], ref.M_J1, 1e-9 * scale_m);
  }
}

}  // namespace

TEST(MujocoInverseDynamics, MatchesAnalyticTailBaseLoadForPaperTails) {
  for (int n = 1; n <= 6; ++n) crossCheck(paperRobot(n), 40, 100 + n);
}

TEST(MujocoInverseDynamics, MatchesAnalyticTailBaseLoadForUnevenLinks) {
  RobotParams p;
  p.tail = {{1.1, 4e-3, 0.14, 0.06}, {0.7, 2e-3, 0.11, 0.05}, {0.45, 7e-4, 0.09, 0.03}};
  p.quadruped.d_Q2B_m = 0.1405;
  crossCheck(p, 60, 7);
}
