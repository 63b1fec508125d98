#include "rendering/replay.h"

#include "models/mujoco/mjcf_generator.h"
#include "results/columns.h"
#include "common/units.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tailsim {

// ---------------------------------------------------------------- sampling

PlanarStateSampler::PlanarStateSampler(const TimeSeries& ts, int n_links, const std::string& what) {
  auto col = [&](const std::string& name) {
    if (!ts.has(name)) throw std::invalid_argument(what + " time series has no column " + name);
    return &ts.values(name);
  };
  t_ = col(col::kT);
  x_ = col(col::kX);
  y_ = col(col::kY);
  phi_ = col(col::kPhi);
  for (int i = 1; i <= n_links; ++i) theta_.push_back(col(col::theta(i)));
  if (t_->empty()) throw std::invalid_argument(what + " time series has no rows");
  for (size_t r = 1; r < t_->size(); ++r)
    if (!((*t_)[r] > (*t_)[r - 1]))
      throw std::invalid_argument(what + " time series: t_s must increase (row " + std::to_string(r + 1) + ")");
}

PlanarState PlanarStateSampler::at(double t) const {
  const std::vector<double>& tv = *t_;
  size_t i0 = 0, i1 = 0;
  double w = 0.0;
  if (t <= tv.front()) {
    i0 = i1 = 0;
  } else if (t >= tv.back()) {
    i0 = i1 = tv.size() - 1;
  } else {
    i1 = static_cast<size_t>(std::upper_bound(tv.begin(), tv.end(), t) - tv.begin());
    i0 = i1 - 1;
    w = (t - tv[i0]) / (tv[i1] - tv[i0]);
  }
  auto lerp = [&](const std::vector<double>& v) { return (1.0 - w) * v[i0] + w * v[i1]; };
  PlanarState s;
  s.x = lerp(*x_);
  s.y = lerp(*y_);
  s.phi = lerp(*phi_) * units::kRadPerDeg;
  for (const auto* th : theta_) s.theta.push_back(lerp(*th) * units::kRadPerDeg);
  return s;
}

// ---------------------------------------------------------------- paper kinematics

PlanarTailPose planarTailPose(const RobotParams& robot, const PlanarState& s) {
  const int n = robot.numLinks();
  if (static_cast<int>(s.theta.size()) != n)
    throw std::invalid_argument("planarTailPose: state has " + std::to_string(s.theta.size()) +
                                " joint angles for a " + std::to_string(n) + "-link tail");
  PlanarTailPose pose;
  // Eq. (2): p_B = p_Q - d_Q2B R_Q x.
  const double c = std::cos(s.phi), sn = std::sin(s.phi);
  std::array<double, 2> p = {s.x - robot.quadruped.d_Q2B_m * c, s.y - robot.quadruped.d_Q2B_m * sn};
  pose.joints.push_back(p);
  // Eq. (1): R_B = R_Q R_Z(180 deg); R_T,i = R_T,i-1 R_Z(theta_i) -> planar yaw sums.
  double yaw = s.phi + M_PI;
  for (int i = 0; i < n; ++i) {
    yaw += s.theta[i];
    pose.link_yaw.push_back(yaw);
    // Eq. (3) (index fixed): p_J,i+1 = p_J,i + L_L R_T,i x.
    p = {p[0] + robot.tail[i].length_m * std::cos(yaw), p[1] + robot.tail[i].length_m * std::sin(yaw)};
    pose.joints.push_back(p);
  }
  return pose;
}

TailPhase tailPhase(const TailTrajectory& traj, double t) {
  bool decel = false;
  for (const SplitCycleProfile& j : traj.joints) {
    if (t >= j.params().t0_s && t <= j.t1()) return TailPhase::kAccelerating;
    if (t > j.t1() && t <= j.t2()) decel = true;
  }
  return decel ? TailPhase::kDecelerating : TailPhase::kAtRest;
}

bool splitCycleStrokes(const TailTrajectory& traj) {
  if (traj.joints.empty()) return false;
  for (const SplitCycleProfile& j : traj.joints)
    if (j.isSpline()) return false;
  return true;
}

const char* tailPhaseName(TailPhase p) {
  switch (p) {
    case TailPhase::kAccelerating: return "accelerating";
    case TailPhase::kDecelerating: return "decelerating";
    default: return "at rest";
  }
}

// ---------------------------------------------------------------- MuJoCo layout

namespace {

std::string jointList(const mjModel* m) {
  static const char* kType[] = {"free", "ball", "slide", "hinge"};
  std::ostringstream os;
  for (int j = 0; j < m->njnt; ++j) {
    const char* name = mj_id2name(m, mjOBJ_JOINT, j);
    os << (j ? ", " : "") << (name ? name : "(unnamed)") << " [" << kType[m->jnt_type[j]] << "]";
  }
  return m->njnt ? os.str() : "(none)";
}

}  // namespace

std::string MujocoReplayLayout::describe(const mjModel* m) const {
  std::ostringstream os;
  const char* body = root_body >= 0 ? mj_id2name(m, mjOBJ_BODY, root_body) : nullptr;
  os << "root body " << (body ? body : "?") << ", " << (free_root ? "free" : "ball") << " joint at qpos " << root_qpos
     << ", tail qpos";
  for (int a : tail_qpos) os << " " << a;
  return os.str();
}

MujocoReplayLayout findReplayLayout(const mjModel* m, int n_links) {
  MujocoReplayLayout L;
  auto fail = [&](const std::string& why) {
    throw std::runtime_error("rendering: cannot map the time series onto the MuJoCo model: " + why +
                             ". Joints in the model: " + jointList(m));
  };
  const int root = mj_name2id(m, mjOBJ_JOINT, mjcf::kRootJoint);
  if (root < 0) fail(std::string("no joint named '") + mjcf::kRootJoint + "'");
  if (m->jnt_type[root] != mjJNT_FREE && m->jnt_type[root] != mjJNT_BALL)
    fail(std::string("joint '") + mjcf::kRootJoint + "' is neither a free nor a ball joint");
  L.free_root = m->jnt_type[root] == mjJNT_FREE;
  L.root_qpos = m->jnt_qposadr[root];
  L.root_body = m->jnt_bodyid[root];
  const int quat_adr = L.root_qpos + (L.free_root ? 3 : 0);
  if (L.free_root)
    for (int k = 0; k < 3; ++k) L.root_pos0[k] = m->qpos0[L.root_qpos + k];
  else
    for (int k = 0; k < 3; ++k) L.root_pos0[k] = m->body_pos[3 * L.root_body + k];
  for (int k = 0; k < 4; ++k) L.root_quat0[k] = m->qpos0[quat_adr + k];
  // The time series' x, y are the quadruped COM p_Q: the COM in the root body frame.
  L.com_offset = {m->body_ipos[3 * L.root_body], m->body_ipos[3 * L.root_body + 1]};
  for (int i = 1; i <= n_links; ++i) {
    const std::string name = mjcf::tailJointName(i);
    const int j = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    if (j < 0) fail("no joint named '" + name + "' for tail link " + std::to_string(i));
    const mjtNum* a = m->jnt_axis + 3 * j;
    if (m->jnt_type[j] != mjJNT_HINGE || std::abs(a[2] - 1.0) > 1e-9)
      fail("tail joint '" + name + "' is not a hinge about +z");
    L.tail_qpos.push_back(m->jnt_qposadr[j]);
  }
  return L;
}

void setReplayQpos(const mjModel* m, const MujocoReplayLayout& L, const PlanarState& s, double* qpos) {
  // quat = R_Z(phi) * quat0: yaw about world z on top of the initial orientation.
  const mjtNum qz[4] = {std::cos(0.5 * s.phi), 0, 0, std::sin(0.5 * s.phi)};
  const mjtNum q0[4] = {L.root_quat0[0], L.root_quat0[1], L.root_quat0[2], L.root_quat0[3]};
  if (L.free_root) {
    const double c = std::cos(s.phi), sn = std::sin(s.phi);
    double* q = qpos + L.root_qpos;
    // Body frame origin such that the COM (ipos, body frame) lands on (x, y); z as in qpos0.
    q[0] = s.x - (c * L.com_offset[0] - sn * L.com_offset[1]);
    q[1] = s.y - (sn * L.com_offset[0] + c * L.com_offset[1]);
    q[2] = L.root_pos0[2];
    mju_mulQuat(q + 3, qz, q0);
    mju_normalize4(q + 3);
  } else {
    // Ball root (translation off): the body stays where the MJCF put it; yaw only.
    mju_mulQuat(qpos + L.root_qpos, qz, q0);
    mju_normalize4(qpos + L.root_qpos);
  }
  for (size_t i = 0; i < L.tail_qpos.size(); ++i) qpos[L.tail_qpos[i]] = s.theta[i];
}

}  // namespace tailsim
