#include "results/csv.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "common/number_text.h"

namespace tailsim {

std::string toCsv(const TimeSeries& ts) {
  std::string head;
  for (size_t c = 0; c < ts.numColumns(); ++c) {
    if (c) head += ',';
    head += ts.names()[c];
  }
  head += '\n';
  // Formatting is most of the cost of a run's output, and a column often repeats its last value
  // (a body at rest, a state flag, rows copied to the end): each column remembers where its last
  // value's text is in the output and copies it when the bits are the same (so -0 and 0 stay
  // apart). The text itself is formatG12's ("%.12g", the same bytes as std::to_chars with
  // precision 12, ~4x faster). Rows are written through a pointer into a buffer that grows by
  // doubling, with room for a whole row (32 characters a number) before each row.
  const size_t n_cols = ts.numColumns(), row_max = n_cols * 33 + 1;
  std::string out(head.size() + ts.numRows() * n_cols * 12 + row_max, '\0');
  std::memcpy(out.data(), head.data(), head.size());
  size_t pos = head.size();
  struct Last {
    uint64_t bits = 0;
    size_t at = 0, len = 0;  // where the text of that value is in `out`
    bool have = false;
  };
  std::vector<Last> last(n_cols);
  for (size_t r = 0; r < ts.numRows(); ++r) {
    if (out.size() - pos < row_max) out.resize(std::max(2 * out.size(), pos + row_max));
    char* p = out.data() + pos;
    for (size_t c = 0; c < n_cols; ++c) {
      if (c) *p++ = ',';
      const double v = ts.at(r, static_cast<int>(c));
      if (std::isnan(v)) {
        std::memcpy(p, "nan", 3);
        p += 3;
        continue;
      }
      uint64_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      Last& l = last[c];
      if (l.have && bits == l.bits) {
        std::memcpy(p, out.data() + l.at, l.len);
        p += l.len;
      } else {
        char* e = formatG12(p, v);
        l = Last{bits, static_cast<size_t>(p - out.data()), static_cast<size_t>(e - p), true};
        p = e;
      }
    }
    *p++ = '\n';
    pos = static_cast<size_t>(p - out.data());
  }
  out.resize(pos);
  return out;
}

void writeCsvAtomic(const std::string& path, const TimeSeries& ts) { writeFileAtomic(path, toCsv(ts)); }

TimeSeries readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  TimeSeries ts;
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(path + " is empty");
  std::stringstream hs(line);
  std::string name;
  while (std::getline(hs, name, ',')) ts.addColumn(name);
  std::vector<double> row(ts.numColumns());
  size_t lineNo = 1;
  while (std::getline(in, line)) {
    ++lineNo;
    if (line.empty()) continue;
    const char* p = line.c_str();
    for (size_t c = 0; c < row.size(); ++c) {
      char* end = nullptr;
      row[c] = std::strtod(p, &end);
      if (end == p) throw std::runtime_error(path + ":" + std::to_string(lineNo) + ": bad number");
      p = (*end == ',') ? end + 1 : end;
    }
    ts.appendRow(row);
  }
  return ts;
}

}  // namespace tailsim
