#include "results/thin_series.h"

#include <algorithm>
#include <cmath>

#include "results/columns.h"

namespace tailsim {

std::vector<size_t> thinRowIndices(const TimeSeries& ts, const std::vector<double>& marks, size_t grid) {
  const size_t n = ts.numRows();
  std::vector<char> keep(n, 0);
  if (n == 0) return {};
  if (grid == 0) grid = 1;
  for (size_t k = 0; k < n; k += grid) keep[k] = 1;  // 1. the coarse grid
  keep[n - 1] = 1;
  // 2. stick/slip switches (NaN = no stuck state: equal to NaN)
  for (const char* name : {col::kRotState, col::kTransState}) {
    const int c = ts.column(name);
    if (c < 0) continue;
    const std::vector<double>& s = ts.values(c);
    for (size_t k = 1; k < n; ++k) {
      const bool same = s[k] == s[k - 1] || (std::isnan(s[k]) && std::isnan(s[k - 1]));
      if (!same) keep[k - 1] = keep[k] = 1;
    }
  }
  // 3. the tail's phase boundaries
  const int tc = ts.column(col::kT);
  if (tc >= 0) {
    const std::vector<double>& t = ts.values(tc);
    for (double m : marks) {
      const size_t after = static_cast<size_t>(std::lower_bound(t.begin(), t.end(), m) - t.begin());
      if (after < n) keep[after] = 1;
      if (after > 0) keep[after - 1] = 1;  // t[after - 1] < m
      if (after < n && t[after] == m && after > 0) keep[after - 1] = 1;
    }
  }
  // 4. phi's turning points, plateaus' ends, and its extremes
  const int pc = ts.column(col::kPhi);
  if (pc >= 0) {
    const std::vector<double>& phi = ts.values(pc);
    auto sign = [](double d) { return d > 0 ? 1 : d < 0 ? -1 : 0; };
    for (size_t k = 1; k + 1 < n; ++k)
      if (sign(phi[k] - phi[k - 1]) != sign(phi[k + 1] - phi[k])) keep[k] = 1;
    size_t lo = 0, hi = 0;
    for (size_t k = 1; k < n; ++k) {
      if (phi[k] < phi[lo]) lo = k;
      if (phi[k] > phi[hi]) hi = k;
    }
    keep[lo] = keep[hi] = 1;
  }
  std::vector<size_t> out;
  for (size_t k = 0; k < n; ++k)
    if (keep[k]) out.push_back(k);
  return out;
}

TimeSeries thinRows(const TimeSeries& ts, const std::vector<double>& marks, size_t grid) {
  TimeSeries out;
  for (const std::string& name : ts.names()) out.addColumn(name);
  const std::vector<size_t> rows = thinRowIndices(ts, marks, grid);
  out.reserveRows(rows.size());
  std::vector<double> row(ts.numColumns());
  for (size_t k : rows) {
    for (size_t c = 0; c < row.size(); ++c) row[c] = ts.at(k, static_cast<int>(c));
    out.appendRow(row);
  }
  return out;
}

}  // namespace tailsim
