#include "results/time_series.h"

#include <limits>
#include <stdexcept>

namespace tailsim {

int TimeSeries::addColumn(const std::string& name) {
  if (column(name) >= 0) throw std::logic_error("duplicate time-series column " + name);
  const size_t rows = data_.empty() ? 0 : data_[0].size();
  names_.push_back(name);
  data_.emplace_back(rows, std::numeric_limits<double>::quiet_NaN());
  return static_cast<int>(names_.size()) - 1;
}

int TimeSeries::column(const std::string& name) const {
  for (size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name) return static_cast<int>(i);
  return -1;
}

void TimeSeries::appendRow(const std::vector<double>& row) {
  if (row.size() != names_.size()) throw std::logic_error("time-series row has the wrong width");
  const double* v = row.data();
  for (std::vector<double>& col : data_) col.push_back(*v++);
}

void TimeSeries::appendRepeated(const std::vector<double>& row, size_t count, int grid_col, long first, double step) {
  if (row.size() != names_.size() || grid_col < 0 || static_cast<size_t>(grid_col) >= names_.size())
    throw std::logic_error("time-series row has the wrong width");
  for (size_t c = 0; c < row.size(); ++c) {
    std::vector<double>& col = data_[c];
    if (static_cast<int>(c) != grid_col) {
      col.insert(col.end(), count, row[c]);
      continue;
    }
    for (size_t i = 0; i < count; ++i) col.push_back(static_cast<double>(first + static_cast<long>(i)) * step);
  }
}

void TimeSeries::appendRowMajor(const double* data, size_t rows) {
  const size_t width = names_.size();
  for (size_t c = 0; c < width; ++c) {
    std::vector<double>& col = data_[c];
    const size_t old = col.size();
    col.resize(old + rows);
    double* out = col.data() + old;
    const double* in = data + c;
    for (size_t i = 0; i < rows; ++i, in += width) out[i] = *in;
  }
}

void TimeSeries::reserveRows(size_t rows) {
  for (auto& col : data_) col.reserve(rows);
}

const std::vector<double>& TimeSeries::values(const std::string& name) const {
  const int c = column(name);
  if (c < 0) throw std::out_of_range("no time-series column " + name);
  return data_[c];
}

}  // namespace tailsim
