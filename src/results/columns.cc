#include "results/columns.h"

#include <algorithm>

namespace tailsim::col {

std::vector<std::string> shared(int links) {
  std::vector<std::string> c{kT};
  for (int i = 1; i <= links; ++i) c.push_back(theta(i));
  for (int i = 1; i <= links; ++i) c.push_back(thetadot(i));
  for (int i = 1; i <= links; ++i) c.push_back(thetaddot(i));
  for (const char* n : {kX, kY, kPhi, kPhidot, kPhiddot, kMzT, kMzF, kIzzPhiddot, kIzz, kFTx, kFTy, kFFx, kFFy})
    c.push_back(n);
  return c;
}

int links(const TimeSeries& ts) {
  int n = 0;
  while (ts.has(theta(n + 1))) ++n;
  return n;
}

TimeSeries inColumnOrder(const TimeSeries& ts, const std::vector<std::string>& order) {
  std::vector<int> cols;
  for (const std::string& n : order)
    if (const int c = ts.column(n); c >= 0) cols.push_back(c);
  for (int c = 0; c < static_cast<int>(ts.numColumns()); ++c)
    if (std::find(cols.begin(), cols.end(), c) == cols.end()) cols.push_back(c);
  bool same = true;
  for (size_t i = 0; i < cols.size(); ++i) same = same && cols[i] == static_cast<int>(i);
  if (same) return ts;
  TimeSeries out;
  for (int c : cols) out.addColumn(ts.names()[c]);
  std::vector<double> row(cols.size());
  for (size_t r = 0; r < ts.numRows(); ++r) {
    for (size_t i = 0; i < cols.size(); ++i) row[i] = ts.at(r, cols[i]);
    out.appendRow(row);
  }
  return out;
}

}  // namespace tailsim::col
