#include "numerics/sin_cos.h"

namespace tailsim::sin_cos_detail {
namespace {
std::array<Entry, 2 * kHalf + 1> makeTable() {
  std::array<Entry, 2 * kHalf + 1> t{};
  for (int k = -kHalf; k <= kHalf; ++k) {
    const double a = static_cast<double>(k) / kPerRad;  // exact
    t[k + kHalf] = {std::sin(a), std::cos(a)};
  }
  return t;
}
}  // namespace

const std::array<Entry, 2 * kHalf + 1> kTable = makeTable();

}  // namespace tailsim::sin_cos_detail
