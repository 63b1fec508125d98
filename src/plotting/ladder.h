// The gap ladder (docs/per-foot-model.md "The gap ladder"): from a result folder
// of configs/ladder/ experiments (each figure's cases run with analytic.coupling swept over
// paper/exact and effects.friction over stiction/continuous, models analytic, perfoot, mujoco),
// every case's phi_net on six rungs
//   paper model -> exact coupling -> per-foot Coulomb -> per-foot ADAMS law -> MuJoCo (ADAMS law)
//   -> MuJoCo (constant mu)
// and each step's share of the total gap (MuJoCo constant mu - paper model), plus the per-foot vs
// MuJoCo agreement with the same friction law and the Fig. 6 verdict (paper Sec. 4.2).
#pragma once

#include <string>
#include <vector>

namespace tailsim {

// One figure case on the ladder (phi_net in deg; NaN where a run is missing or failed).
struct LadderCase {
  std::string experiment;  // the ladder experiment (one per paper figure)
  std::string name;        // the case without the two ladder keys ("base" if nothing else is swept)
  double paper = 0, exact = 0, perfoot_coulomb = 0, perfoot_adams = 0, mujoco_adams = 0, mujoco_const = 0;
  double paper_adams = 0;  // the paper model with the ADAMS law (the paper's own explanation, alone)
};

// The ladder of every ladder experiment under `dir` (a suite folder or one experiment folder).
// Throws std::runtime_error when a folder lacks the two ladder axes or a model.
std::vector<LadderCase> loadLadder(const std::string& dir);

// Writes DIR/ladder.md (the tables, the agreement and the verdict), DIR/ladder.csv (one row a
// case) and DIR/plots/ladder_<experiment>.png/.svg (one a figure); returns the paths written.
std::vector<std::string> writeLadder(const std::string& dir);

}  // namespace tailsim
