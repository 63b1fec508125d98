#include "controllers/heading_controller.h"

#include <algorithm>
#include <stdexcept>

namespace tailsim {

CycleStrokes cycleStrokes(const ManeuverSettings& s, int n_joints, const StrokeCommand& c, double t_start) {
  if (!(c.scale > 0.0 && c.scale <= 1.0)) throw std::invalid_argument("stroke scale must lie in (0, 1]");
  if (c.direction != 1 && c.direction != -1) throw std::invalid_argument("stroke direction must be +1 or -1");
  const double amp = c.direction * c.scale * s.stroke();
  SplitCycleParams fast;
  fast.theta0_rad = 0.0;
  fast.dtheta_rad = amp;
  fast.dT_s = c.scale * s.stroke_dT_s;  // peak speed 2 A / stroke_dT_s at every scale (Eq. 23)
  fast.w_ss = s.stroke_w_ss;
  fast.t0_s = t_start;
  SplitCycleParams back;
  back.theta0_rad = amp;
  back.dtheta_rad = -amp;
  back.dT_s = s.return_dT_s;
  back.w_ss = s.return_w_ss;
  back.t0_s = fast.t0_s + fast.dT_s + s.rest_s;
  CycleStrokes out;
  for (int i = 0; i < n_joints; ++i) {
    out.fast.joints.emplace_back(fast);
    out.back.joints.emplace_back(back);
  }
  return out;
}

double cycleDuration(const ManeuverSettings& s, double scale) {
  return scale * s.stroke_dT_s + s.rest_s + s.return_dT_s + s.rest_s;
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

std::optional<StrokeCommand> HeadingController::next(double phi_rad) const {
  const double e = s_.heading() - phi_rad;
  if (std::abs(e) <= s_.tolerance()) return std::nullopt;
  StrokeCommand c;
  // A cycle of direction d turns d * full(): pick d so the turn has the error's sign.
  c.direction = (e > 0) == (map_.full() > 0) ? 1 : -1;
  c.scale = std::abs(e) >= std::abs(map_.full()) ? 1.0 : map_.scaleFor(std::abs(e));
  return c;
}

}  // namespace tailsim
