// `tailsim trust EXPERIMENT --out DIR`: the convergence and sensitivity study of an experiment's
// MuJoCo results (docs/accuracy.md "tailsim trust"). Every simulate case is run at its own
// settings and once per variant (timestep, contact compliance, stroke jitter) against a converged
// reference (the case's settings at timestep / 8 with the servo's w_n kept, impratio >= 100,
// noslip >= 3: tests/bench_trust.cc's reference), each with its wall time, so a user sees what
// phi_net depends on and what pinning it down costs. The planar models of the case and the
// verdict across the models (experiments/verdict.h) are part of each case's table.
#pragma once

#include <string>
#include <vector>

#include "experiments/experiment_loader.h"

namespace tailsim {

struct TrustRow {
  std::string group;    // "default", "timestep", "contact", "jitter", "reference", "planar"
  std::string setting;  // what differs from the case's settings, e.g. "timestep_s = 5e-05 s"
  std::string model = "mujoco";
  bool ok = true;
  std::string failure;       // why not ok
  double phi_net_deg = 0;
  double uncertainty_deg = 0;  // the default run's own estimate (phi_net_uncertainty_deg); NaN elsewhere
  double wall_s = 0;           // the run's wall time (the default: its check run included)
  long steps = 0;              // mj_step calls of the run proper (pre-roll and check run excluded)
  long check_steps = 0;        // mj_step calls of its uncertainty check run (the default's; 0 without one)
};

struct TrustStudy {
  std::string case_name;
  std::vector<TrustRow> rows;  // rows[0]: the default MuJoCo run; one "reference" row
  std::string verdict;         // across the case's models (empty: fewer than two)
  const TrustRow* row(const std::string& group) const;  // the first row of the group, or nullptr
};

struct TrustOptions {
  std::string only_case;  // study this case only (empty: every simulate case)
};

// Every simulate case of `e` (MuJoCo is run whether or not the case lists it). Throws ConfigError
// when options.only_case names no case, or when no case is a simulate case.
std::vector<TrustStudy> runTrustStudy(const Experiment& e, const TrustOptions& options);

}  // namespace tailsim
