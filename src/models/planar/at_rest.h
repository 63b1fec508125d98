// The warning of a planar run whose body still moves when it ends (both planar models).
#pragma once

#include <sstream>
#include <string>

#include "common/work_limits.h"

namespace tailsim {

inline std::string notAtRestWarning(double t_end, double phidot_dps, double speed_mps) {
  std::ostringstream os;
  os.precision(4);
  os << "the body is still moving when the run ends at t = " << t_end << " s (|phi_dot| " << phidot_dps
     << " deg/s, speed " << speed_mps << " m/s; at rest means below " << limits::kAtRestPhidotDps << " deg/s and "
     << limits::kAtRestSpeedMps << " m/s): phi_net is not final, raise output.settle_s or duration_s";
  return os.str();
}

}  // namespace tailsim
