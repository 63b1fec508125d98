// The output columns of the planar models (analytic, per-foot) as a table: each column's name
// (its unit as a suffix, results/columns.h) beside the function that reads its value from what the
// recorder evaluated at one sample (`Row`, each model's own). The column list a model declares
// (its registry entry) and the values of every row it writes come from the same table, so no
// list of names is matched against a list of values by position.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "results/columns.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

template <class Row>
struct RowColumn {
  std::string name;
  double (*get)(const Row&, int index);
  int index = 0;  // the joint or foot (0-based) a per-joint or per-foot column reads
};

// The columns every planar model starts with: t_s, then theta<i>_deg, thetadot<i>_dps and
// thetaddot<i>_dps2 of each joint i = 1..links. Row has `t` and `joints` (the joint states at t).
template <class Row>
void addTimeAndJointColumns(std::vector<RowColumn<Row>>& table, int links) {
  table.push_back({col::kT, [](const Row& r, int) { return r.t; }});
  for (int i = 1; i <= links; ++i)
    table.push_back({col::theta(i), [](const Row& r, int j) { return r.joints[j].theta * (180.0 / M_PI); }, i - 1});
  for (int i = 1; i <= links; ++i)
    table.push_back(
        {col::thetadot(i), [](const Row& r, int j) { return r.joints[j].theta_dot * (180.0 / M_PI); }, i - 1});
  for (int i = 1; i <= links; ++i)
    table.push_back(
        {col::thetaddot(i), [](const Row& r, int j) { return r.joints[j].theta_ddot * (180.0 / M_PI); }, i - 1});
}

template <class Row>
std::vector<std::string> columnNames(const std::vector<RowColumn<Row>>& table) {
  std::vector<std::string> names;
  names.reserve(table.size());
  for (const RowColumn<Row>& c : table) names.push_back(c.name);
  return names;
}

// Writes row r's values into out[0 .. table.size()).
template <class Row>
void fillColumns(const std::vector<RowColumn<Row>>& table, const Row& r, double* out) {
  for (const RowColumn<Row>& c : table) *out++ = c.get(r, c.index);
}

}  // namespace tailsim
