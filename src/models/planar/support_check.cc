#include "models/planar/support_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "models/planar/foot_loads.h"
#include "models/planar/system_loads.h"

namespace tailsim {
namespace {

// The four edge margins of the support rectangle at t, each >= 0 inside (measured from
// kSupportSlack (l_F + w_F) beyond the edges): l/2 - x_e, l/2 + x_e, w/2 - y_e, w/2 + y_e, each
// as smooth as p_QC(t).
struct EdgeMargins {
  std::array<double, 4> e;
  Vec2 p_CC;
  double min() const { return *std::min_element(e.begin(), e.end()); }
};

class Search {
 public:
  Search(const RobotParams& robot, const TailTrajectory& traj) : robot_(robot), traj_(traj) {
    const QuadrupedParams& q = robot.quadruped;
    slack_ = kSupportSlack * (q.l_F_m + q.w_F_m);
    for (const JointProfile& j : traj.joints) {
      // Peak |speed| (split-cycle: 2 dtheta / dT at t1; spline: its computed peak) and peak
      // |acceleration| (JointProfile::peakAcceleration, a spline's end knots included).
      const double acc = j.peakAcceleration();
      if (!std::isfinite(j.peakSpeed()) || !std::isfinite(acc))
        throw std::runtime_error("a joint's peak speed or acceleration is non-finite: check the trajectory values");
      // A relative margin for round-off in the bounds themselves.
      peak_speed_.push_back(std::abs(j.peakSpeed()) * (1.0 + 1e-9));
      peak_acc_.push_back(acc * (1.0 + 1e-9));
    }
  }

  EdgeMargins at(double t) {
    if (++evaluations_ > kMaxEvaluations)
      throw std::runtime_error("the support check did not converge (" + std::to_string(kMaxEvaluations) +
                               " evaluations): the system COM runs along an edge of the support rectangle, or the joint speeds are too large to bound");
    traj_.evaluate(t, joints_);
    tailKinematics(robot_.tail, joints_, kin_);
    systemMassProperties(robot_, kin_, loads_);
    const QuadrupedParams& q = robot_.quadruped;
    const Vec2 p = comFromFootCentroid(q, loads_.p_QC);
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()))
      throw std::runtime_error("the system COM became non-finite at t=" + std::to_string(t) +
                               " s: check the trajectory values");
    const double hl = 0.5 * q.l_F_m + slack_, hw = 0.5 * q.w_F_m + slack_;
    return {{hl - p.x(), hl + p.x(), hw - p.y(), hw + p.y()}, p};
  }

  // The first time in (a, b] with a margin below zero, given the margins at a (all >= 0) and b.
  std::optional<SupportLoss> first(double a, double b, const EdgeMargins& ga, const EdgeMargins& gb) {
    const auto [L, M] = bounds(a, b);
    const double h = b - a;
    const double dip_lipschitz = 0.5 * L * h, dip_curvature = 0.125 * M * h * h;
    bool certified = true;
    for (int k = 0; k < 4; ++k) {
      // Lowest possible value on [a, b]: from the slope bound, or from the curvature bound
      // (a C2 function lies above its chord minus M (t - a)(b - t) / 2).
      const double low = std::max(0.5 * (ga.e[k] + gb.e[k]) - dip_lipschitz, std::min(ga.e[k], gb.e[k]) - dip_curvature);
      if (low < 0.0) certified = false;
    }
    if (certified) return std::nullopt;
    // Both ends inside and no dip deeper than the slack possible: on an edge, standing (footLoads).
    if (gb.min() >= 0.0 && std::min(dip_lipschitz, dip_curvature) <= slack_) return std::nullopt;
    const double mid = 0.5 * (a + b);
    if (h <= kTimeResolution || !(mid > a && mid < b)) {
      if (gb.min() < 0.0) return SupportLoss{b, gb.p_CC};
      return std::nullopt;
    }
    const EdgeMargins gm = at(mid);
    if (auto r = first(a, mid, ga, gm)) return r;
    if (gm.min() < 0.0) return SupportLoss{mid, gm.p_CC};
    return first(mid, b, gm, gb);
  }

 private:
  static constexpr long kMaxEvaluations = 2'000'000;
  static constexpr double kTimeResolution = 1e-12;  // of the exit time  [s]

  // Bounds on |d p_QC/dt| (L) and |d^2 p_QC/dt^2| (M) over [a, b], from the joints that move in it.
  // p_L,i = sum_{k<i} l_k e(psi_k) + c_i e(psi_i): |v_L,i| <= sum_{k<i} l_k |psi_dot_k| + |c_i| |psi_dot_i|,
  // |a_L,i| <= the same with |psi_ddot_k| + psi_dot_k^2, and p_QC = -(1/m) sum m_i p_L,i + const.
  std::pair<double, double> bounds(double a, double b) const {
    double P = 0, Q = 0, L = 0, M = 0, reach_v = 0, reach_a = 0;
    for (size_t i = 0; i < robot_.tail.size(); ++i) {
      const JointProfile& j = traj_.joints[i];
      const bool moves = a < j.t2() && b > j.params().t0_s;
      if (moves) {
        P += peak_speed_[i];
        Q += peak_acc_[i];
      }
      const TailLink& l = robot_.tail[i];
      const double c = std::abs(l.com_offset_m);
      L += l.mass_kg * (reach_v + c * P);
      M += l.mass_kg * (reach_a + c * (Q + P * P));
      reach_v += std::abs(l.length_m) * P;
      reach_a += std::abs(l.length_m) * (Q + P * P);
    }
    const double m = robot_.systemMass();
    if (!std::isfinite(L / m) || !std::isfinite(M / m))
      throw std::runtime_error("the tail's speeds or accelerations are non-finite (their squares overflow): check the trajectory values");
    return {L / m * (1.0 + 1e-9), M / m * (1.0 + 1e-9)};
  }

  const RobotParams& robot_;
  const TailTrajectory& traj_;
  double slack_ = 0;
  std::vector<double> peak_speed_, peak_acc_;
  std::vector<JointState> joints_;
  TailKinematics kin_;
  SystemLoads loads_;
  long evaluations_ = 0;
};

}  // namespace

std::optional<SupportLoss> firstSupportLoss(const RobotParams& robot, const TailTrajectory& traj, double t_end) {
  requireOneJointPerLink(traj.joints.size(), robot.tail.size());
  Search s(robot, traj);
  const EdgeMargins g0 = s.at(0.0);
  if (g0.min() < 0.0) return SupportLoss{0.0, g0.p_CC};
  // After the tail's motion the COM stays where it ended.
  const double b = std::min(t_end, traj.endTime());
  if (!(b > 0.0)) return std::nullopt;
  return s.first(0.0, b, g0, s.at(b));
}

void requireSupport(const RobotParams& robot, const TailTrajectory& traj, double t_end) {
  if (const auto loss = firstSupportLoss(robot, traj, t_end)) throw TippingError(supportLossMessage(robot.quadruped, *loss));
}

std::string supportLossMessage(const QuadrupedParams& q, const SupportLoss& loss, const char* what) {
  std::ostringstream os;
  os.precision(9);
  os << tippingMessage(q, loss.p_CC.x(), loss.p_CC.y(), what) << " at t = " << loss.t_s << " s";
  return os.str();
}

}  // namespace tailsim
