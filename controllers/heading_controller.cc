#include "controllers/heading_controller.h"

#include <algorithm>
#include <stdexcept>

#include "common/work_limits.h"

namespace tailsim {

TailTrajectory fastStrokeShape(const ManeuverSettings& s, int n_joints) {
  TailTrajectory out;
  if (s.stroke_shape.joints.empty()) {
    SplitCycleParams p;
    p.theta0_rad = 0.0;
    p.dtheta_rad = s.stroke();
    p.dT_s = s.stroke_dT_s;
    p.w_ss = s.stroke_w_ss;
    p.t0_s = 0.0;
    for (int i = 0; i < n_joints; ++i) out.joints.emplace_back(p);
    return out;
  }
  if (static_cast<int>(s.stroke_shape.joints.size()) != n_joints)
    throw std::invalid_argument("the maneuver's stroke has " + std::to_string(s.stroke_shape.joints.size()) +
                                " joints, the tail " + std::to_string(n_joints));
  return shiftedToZero(s.stroke_shape);
}

TailTrajectory shiftedToZero(const TailTrajectory& t) {
  TailTrajectory out;
  const double t_a = t.startTime();
  for (const auto& j : t.joints) {
    if (j.isSpline()) {
      SplineParams p = j.spline();
      p.t0_s -= t_a;
      out.joints.emplace_back(p);
    } else {
      SplitCycleParams p = j.params();
      p.t0_s -= t_a;
      out.joints.emplace_back(p);
    }
  }
  return out;
}

double minScaleFloor(const ManeuverSettings& s, int n_joints) {
  double shortest = 1e300;
  for (const auto& j : fastStrokeShape(s, n_joints).joints) shortest = std::min(shortest, j.params().dT_s);
  return std::min(1.0, std::max(1e-3, limits::kMinDT_s / shortest));
}

namespace {

// The shape scaled by `scale` about each joint's start angle (amplitude and time), mirrored for
// direction -1, starting at t_start.
TailTrajectory scaledStroke(const TailTrajectory& shape, double scale, int dir, double t_start) {
  TailTrajectory out;
  for (const JointProfile& j : shape.joints) {
    if (j.isSpline()) {
      SplineParams p = j.spline();
      const double p0 = p.knots_rad.front();
      for (double& k : p.knots_rad) k = dir * (p0 + scale * (k - p0));
      p.dT_s *= scale;
      p.t0_s = t_start + scale * p.t0_s;
      out.joints.emplace_back(p);
    } else {
      SplitCycleParams p = j.params();
      p.theta0_rad = dir * p.theta0_rad;
      p.dtheta_rad = dir * (scale * p.dtheta_rad);
      p.dT_s = scale * p.dT_s;
      p.t0_s = t_start + scale * p.t0_s;
      out.joints.emplace_back(p);
    }
  }
  return out;
}

// A slow split-cycle move of every joint from `a` to `b` in dT, starting at t0.
TailTrajectory slowMove(const std::vector<double>& a, const std::vector<double>& b, double dT, double w_ss, double t0) {
  TailTrajectory out;
  for (std::size_t i = 0; i < a.size(); ++i) {
    SplitCycleParams p;
    p.theta0_rad = a[i];
    p.dtheta_rad = b[i] - a[i];
    p.dT_s = dT;
    p.w_ss = w_ss;
    p.t0_s = t0;
    out.joints.emplace_back(p);
  }
  return out;
}

std::vector<double> poseAt(const TailTrajectory& t, double time) {
  std::vector<JointState> js;
  t.evaluate(time, js);
  std::vector<double> out;
  for (const JointState& j : js) out.push_back(j.theta);
  return out;
}

}  // namespace

std::vector<double> cycleStartPose(const ManeuverSettings& s, int n_joints, int direction) {
  return poseAt(scaledStroke(fastStrokeShape(s, n_joints), 1.0, direction, 0.0), -1.0);
}

CycleStrokes cycleStrokes(const ManeuverSettings& s, int n_joints, const StrokeCommand& c, double t_start,
                          const std::vector<double>* from) {
  if (!(c.scale > 0.0 && c.scale <= 1.0)) throw std::invalid_argument("stroke scale must lie in (0, 1]");
  if (c.direction != 1 && c.direction != -1) throw std::invalid_argument("stroke direction must be +1 or -1");
  const TailTrajectory shape = fastStrokeShape(s, n_joints);
  CycleStrokes out;
  out.rest_s = s.rest_s;
  const std::vector<double> start = poseAt(scaledStroke(shape, c.scale, c.direction, 0.0), -1.0);
  double t = t_start;
  if (from) {
    bool differs = from->size() != start.size();
    for (std::size_t i = 0; !differs && i < start.size(); ++i) differs = std::abs((*from)[i] - start[i]) > 1e-12;
    if (differs) {
      out.pre = slowMove(*from, start, s.return_dT_s, s.return_w_ss, t_start);
      t = out.pre.endTime() + s.rest_s;
    }
  }
  out.fast = scaledStroke(shape, c.scale, c.direction, t);
  out.back = slowMove(poseAt(out.fast, out.fast.endTime() + 1.0), start, s.return_dT_s, s.return_w_ss,
                      out.fast.endTime() + s.rest_s);
  return out;
}

double cycleDuration(const ManeuverSettings& s, double scale) {
  const double fast = s.stroke_shape.joints.empty() ? s.stroke_dT_s : s.stroke_shape.endTime() - s.stroke_shape.startTime();
  return scale * fast + s.rest_s + s.return_dT_s + s.rest_s;
}

double YawMap::scaleFor(double want) const {
  if (scale.empty()) throw std::logic_error("empty yaw map");
  want = std::abs(want);
  if (want <= std::abs(yaw_rad.front())) return scale.front();
  for (std::size_t i = 1; i < scale.size(); ++i) {
    const double a = std::abs(yaw_rad[i - 1]), b = std::abs(yaw_rad[i]);
    if (want <= b) return b > a ? scale[i - 1] + (want - a) / (b - a) * (scale[i] - scale[i - 1]) : scale[i];
  }
  return scale.back();
}

HeadingController::HeadingController(ManeuverSettings settings, YawMap map) : s_(settings), map_(std::move(map)) {
  if (map_.scale.size() < 2 || map_.scale.size() != map_.yaw_rad.size())
    throw std::invalid_argument("HeadingController: the yaw map needs at least 2 points");
  if (map_.full() == 0.0) throw std::invalid_argument("HeadingController: a full cycle does not turn the body");
}

double YawMap::yawAt(double sc) const {
  if (scale.empty()) throw std::logic_error("empty yaw map");
  if (sc <= scale.front()) return std::abs(yaw_rad.front());
  for (std::size_t i = 1; i < scale.size(); ++i)
    if (sc <= scale[i])
      return std::abs(yaw_rad[i - 1]) +
             (sc - scale[i - 1]) / (scale[i] - scale[i - 1]) * (std::abs(yaw_rad[i]) - std::abs(yaw_rad[i - 1]));
  return std::abs(yaw_rad.back());
}

std::optional<StrokeCommand> HeadingController::next(double phi_rad, double yaw_factor) const {
  const double e = s_.heading() - phi_rad;
  if (std::abs(e) <= s_.tolerance()) return std::nullopt;
  StrokeCommand c;
  // A cycle of direction d turns d * full(): pick d so the turn has the error's sign.
  c.direction = (e > 0) == (map_.full() > 0) ? 1 : -1;
  const double want = std::abs(e) / yaw_factor;
  c.scale = want >= std::abs(map_.full()) ? 1.0 : map_.scaleFor(want);
  return c;
}

}  // namespace tailsim
