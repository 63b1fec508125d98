// The time-series column names, in one place for every writer and reader (both models' recorders,
// plots, the renderer's replay, the accuracy study), and the one column order both models' CSVs
// are written in (docs/ARCHITECTURE.md "Time-series columns"): the columns every model writes
// first, then each model's own in registry order (modelColumnOrder, experiments/model_registry.h),
// then any other in the order it was added.
// A name carries its unit as a suffix; degrees only here, at the CSV edge.
#pragma once

#include <string>
#include <vector>

#include "results/time_series.h"

namespace tailsim::col {

inline constexpr const char* kT = "t_s";
inline constexpr const char* kX = "x_m";
inline constexpr const char* kY = "y_m";
inline constexpr const char* kPhi = "phi_deg";
inline constexpr const char* kPhidot = "phidot_dps";
inline constexpr const char* kPhiddot = "phiddot_dps2";
inline constexpr const char* kMzT = "MzT_Nm";            // tail moment about the system COM (Eq. 13)
inline constexpr const char* kMzTAcc = "MzT_acc_Nm";     // part driven by joint accelerations
inline constexpr const char* kMzTSpeed = "MzT_speed_Nm"; // part driven by joint speeds
inline constexpr const char* kMzTTan = "MzT_tan_Nm";     // Eq. (24)'s tangential term
inline constexpr const char* kMzTCen = "MzT_cen_Nm";     // Eq. (24)'s centripetal term
inline constexpr const char* kMzF = "MzF_Nm";            // friction moment
inline constexpr const char* kIzzPhiddot = "Izz_phiddot_Nm";
inline constexpr const char* kIzz = "Izz_kgm2";
inline constexpr const char* kLF = "LF_m";               // friction moment arm
inline constexpr const char* kFTx = "FTx_N";
inline constexpr const char* kFTy = "FTy_N";
inline constexpr const char* kFFx = "FFx_N";
inline constexpr const char* kFFy = "FFy_N";
inline constexpr const char* kRotState = "rot_state";    // 0 stuck, 1 slipping
inline constexpr const char* kTransState = "trans_state";

// Per joint i = 1..n and per foot k = 1..4.
inline std::string theta(int i) { return "theta" + std::to_string(i) + "_deg"; }
inline std::string thetadot(int i) { return "thetadot" + std::to_string(i) + "_dps"; }
inline std::string thetaddot(int i) { return "thetaddot" + std::to_string(i) + "_dps2"; }
inline std::string footFn(int k) { return "foot" + std::to_string(k) + "_Fn_N"; }
inline std::string footFt(int k) { return "foot" + std::to_string(k) + "_Ft_N"; }
inline std::string trackErr(int i) { return "track_err" + std::to_string(i) + "_deg"; }

// Columns every model writes (a pose evaluation: those that exist at one instant), in order.
std::vector<std::string> shared(int links);

// MuJoCo's own columns, in order (the planar models' come from their column tables,
// models/planar/row_columns.h).
inline std::vector<std::string> mujocoOnly(int links) {
  std::vector<std::string> c;
  for (int k = 1; k <= 4; ++k) {
    c.push_back(footFn(k));
    c.push_back(footFt(k));
  }
  for (int i = 1; i <= links; ++i) c.push_back(trackErr(i));
  return c;
}

// The per-foot model's own (models/perfoot/per_foot_model.h): foot k's friction force (world)
// and normal load, k = 1 front-left .. 4 rear-left, and the load factor of the held wrench.
inline std::string footFx(int k) { return "F" + std::to_string(k) + "x_N"; }
inline std::string footFy(int k) { return "F" + std::to_string(k) + "y_N"; }
inline std::string footN(int k) { return "N" + std::to_string(k) + "_N"; }
inline constexpr const char* kLoadFactor = "load_factor";
inline std::vector<std::string> perfootOnly() {
  std::vector<std::string> c;
  for (int k = 1; k <= 4; ++k) {
    c.push_back(footFx(k));
    c.push_back(footFy(k));
  }
  for (int k = 1; k <= 4; ++k) c.push_back(footN(k));
  c.push_back(kLoadFactor);
  return c;
}

// The joints a series has (its theta<i>_deg columns).
int links(const TimeSeries& ts);

// The series with its columns in `order` (names it lacks skipped), then any other column in the
// order it has. Returns the series itself when it is in that order already.
TimeSeries inColumnOrder(const TimeSeries& ts, const std::vector<std::string>& order);

}  // namespace tailsim::col
