// The output columns of the planar models (analytic, per-foot) as a table: each column's name
// (its unit as a suffix, results/columns.h) beside the function that reads its value from what the
// recorder evaluated at one sample (`Row`, each model's own). The column list a model declares
// (its registry entry) and the values of every row it writes come from the same table, so no
// list of names is matched against a list of values by position.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <limits>

#include "models/planar/system_loads.h"
#include "results/columns.h"
#include "trajectory/split_cycle_profile.h"
#include "common/units.h"

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
    table.push_back({col::theta(i), [](const Row& r, int j) { return r.joints[j].theta * units::kDegPerRad; }, i - 1});
  for (int i = 1; i <= links; ++i)
    table.push_back(
        {col::thetadot(i), [](const Row& r, int j) { return r.joints[j].theta_dot * units::kDegPerRad; }, i - 1});
  for (int i = 1; i <= links; ++i)
    table.push_back(
        {col::thetaddot(i), [](const Row& r, int j) { return r.joints[j].theta_ddot * units::kDegPerRad; }, i - 1});
}

// What every planar model's row holds (the model's own row type derives from it).
struct PlanarRow {
  double t;                               // [s]
  const std::vector<JointState>& joints;  // at t
  double x, y;                            // the quadruped COM, world  [m]
  double phi, phi_dot, phi_ddot;          // yaw  [rad, rad/s, rad/s^2]
  const SystemLoads& loads;               // the tail's loads at t
  bool decomp;                            // effects.load_decomposition: the M_zT parts were evaluated
  double MzF;                             // friction moment about the system COM  [N m]
  double L_F;                             // the paper's friction arm  [m]
  Vec2 FT_W, FF_W;                        // tail force and friction force, world  [N]
  double rot_state, trans_state;          // 0 stuck, 1 sliding, NaN: no stick/slip state
};

// The stick/slip state column's value: 0 stuck, 1 sliding, NaN where the state does not exist.
inline double stickSlipState(bool exists, bool stuck) {
  return exists ? (stuck ? 0.0 : 1.0) : std::numeric_limits<double>::quiet_NaN();
}

// The columns every planar model has after the joints': the body's pose and rates, the tail's
// moment (and its parts with load decomposition), friction, inertia, the arm L_F, the tail and
// friction forces and the stick/slip states. Row derives from PlanarRow.
template <class Row>
void addBodyColumns(std::vector<RowColumn<Row>>& table) {
  using R = const Row&;
  constexpr double kDeg = units::kDegPerRad;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const std::vector<RowColumn<Row>> body = {
      {col::kX, [](R r, int) { return r.x; }},
      {col::kY, [](R r, int) { return r.y; }},
      {col::kPhi, [](R r, int) { return r.phi * kDeg; }},
      {col::kPhidot, [](R r, int) { return r.phi_dot * kDeg; }},
      {col::kPhiddot, [](R r, int) { return r.phi_ddot * kDeg; }},
      {col::kMzT, [](R r, int) { return r.loads.MzT; }},
      {col::kMzTAcc, [](R r, int) { return r.decomp ? r.loads.MzT_acc : kNaN; }},
      {col::kMzTSpeed, [](R r, int) { return r.decomp ? r.loads.MzT_speed : kNaN; }},
      {col::kMzTTan, [](R r, int) { return r.decomp ? r.loads.MzT_tan : kNaN; }},
      {col::kMzTCen, [](R r, int) { return r.decomp ? r.loads.MzT_cen : kNaN; }},
      {col::kMzF, [](R r, int) { return r.MzF; }},
      {col::kIzzPhiddot, [](R r, int) { return r.loads.Izz_kgm2 * r.phi_ddot; }},
      {col::kIzz, [](R r, int) { return r.loads.Izz_kgm2; }},
      {col::kLF, [](R r, int) { return r.L_F; }},
      {col::kFTx, [](R r, int) { return r.FT_W.x(); }},
      {col::kFTy, [](R r, int) { return r.FT_W.y(); }},
      {col::kFFx, [](R r, int) { return r.FF_W.x(); }},
      {col::kFFy, [](R r, int) { return r.FF_W.y(); }},
      {col::kRotState, [](R r, int) { return r.rot_state; }},
      {col::kTransState, [](R r, int) { return r.trans_state; }},
  };
  table.insert(table.end(), body.begin(), body.end());
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
