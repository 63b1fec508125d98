// The output time grid that both models sample on, so their CSVs line up row for row.
#pragma once

namespace tailsim {

struct OutputSettings {
  double sample_dt_s = 1e-3;  // CSV row spacing  [s]
  double duration_s = 0.0;    // simulated time; 0 = tail end time + settle_s  [s]
  double settle_s = 0.5;      // time simulated after the tail stops, when duration_s = 0  [s]
};

}  // namespace tailsim
