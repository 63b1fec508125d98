#include "results/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tailsim {

void writeFileAtomic(const std::string& path, const std::string& contents) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  // No fsync: rename makes the file appear whole or not at all if the process dies (the
  // guarantee we give); fsync per file would only add power-loss durability, at ~10 ms a file.
  const bool ok = std::fwrite(contents.data(), 1, contents.size(), f) == contents.size() && std::fflush(f) == 0;
  const bool closed = std::fclose(f) == 0;
  if (!ok || !closed) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot move " + tmp + " to " + path + ": " + std::strerror(errno));
  }
}

std::string toCsv(const TimeSeries& ts) {
  std::string out;
  out.reserve(ts.numRows() * ts.numColumns() * 12 + 256);
  for (size_t c = 0; c < ts.numColumns(); ++c) {
    if (c) out += ',';
    out += ts.names()[c];
  }
  out += '\n';
  char buf[40];
  for (size_t r = 0; r < ts.numRows(); ++r) {
    for (size_t c = 0; c < ts.numColumns(); ++c) {
      if (c) out += ',';
      const double v = ts.at(r, static_cast<int>(c));
      if (std::isnan(v)) {
        out += "nan";
        continue;
      }
      const auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 12);
      out.append(buf, res.ptr);
    }
    out += '\n';
  }
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
