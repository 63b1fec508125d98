// The output time grid that both models sample on, so their CSVs line up row for row.
#pragma once

#include "settings/fields.h"

namespace tailsim {

struct OutputSettings {
  double sample_dt_s = 1e-3;  // CSV row spacing  [s]
  double duration_s = 0.0;    // simulated time; 0 = tail end time + settle_s  [s]
  double settle_s = 0.5;      // time simulated after the tail stops, when duration_s = 0  [s]
};

// The YAML/JSON keys of OutputSettings (settings/fields.h), declared once.
template <class V, class S>
settings::For<S, OutputSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"sample_dt_s", "CSV row spacing [s]"}, s.sample_dt_s, Limits::positive());
  v.number(Field{"duration_s", "simulated time; 0 = tail end time + settle_s [s]"}, s.duration_s, Limits::nonNegative());
  v.number(Field{"settle_s", "time simulated after the tail stops, when duration_s = 0 [s]"}, s.settle_s,
           Limits::nonNegative());
}

}  // namespace tailsim
