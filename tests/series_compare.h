// Test helper: two runs' time series hold the same columns, rows and times, every column within
// `rel` of its largest value (the step schedule's "same answer" checks).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "results/time_series.h"

namespace tailsim {

inline void expectSameSeries(const TimeSeries& a, const TimeSeries& b, double rel) {
  ASSERT_EQ(a.names(), b.names());
  for (const std::string& name : a.names()) {
    const std::vector<double>& x = a.values(name);
    const std::vector<double>& y = b.values(name);
    ASSERT_EQ(x.size(), y.size()) << name;
    double scale = 1e-9, diff = 0.0;
    for (size_t k = 0; k < x.size(); ++k) {
      scale = std::max(scale, std::abs(x[k]));
      diff = std::max(diff, std::abs(x[k] - y[k]));
    }
    if (name == "t_s") {  // braces: EXPECT_EQ is an if-else macro
      EXPECT_EQ(diff, 0.0);
    }
    EXPECT_LE(diff, rel * scale) << name;
  }
}

}  // namespace tailsim
