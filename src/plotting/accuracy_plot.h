// The work-precision plot of `tailsim accuracy`: error against wall time, log-log, one curve per
// solver family and model, tailsim's defaults marked.
#pragma once

#include <string>
#include <vector>

#include "experiments/accuracy_study.h"

namespace tailsim {

// DIR/accuracy_<case>.png and .svg (one figure per studied case). Returns the PNG paths.
std::vector<std::string> plotAccuracy(const std::vector<AccuracyStudy>& studies, const std::string& dir);

}  // namespace tailsim
