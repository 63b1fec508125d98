// Work-precision study (`tailsim accuracy EXPERIMENT.yaml --out DIR`): what each solver
// setting of each model buys in accuracy and costs in time, against a converged reference of
// the same model.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "experiments/experiment_loader.h"

namespace tailsim {

struct AccuracyRow {
  std::string model;    // analytic | mujoco
  std::string family;   // curve of the work-precision plot, e.g. "adaptive", "timestep/implicit", "solver"
  std::string setting;  // what differs from the case's settings, e.g. "rel_tol=1e-8", "solver=CG"
  double value = 0;     // the swept number (tolerance, step) or 0 for categorical settings
  bool is_default = false;  // tailsim's shipped setting
  bool ok = true;
  std::string failure;  // why not ok (MuJoCo warning, NaN, ...)
  double phi_net_deg = 0;      // MuJoCo: mean over `runs`
  double err_phi_net_deg = 0;  // |phi_net - reference|
  double rms_err_phi_deg = 0;  // RMS over the output grid of phi(t) - phi_ref(t)
  double wall_s = 0;           // median over repeats
  long steps = 0;
  int runs = 1;               // runs averaged into phi_net_deg (MuJoCo: a dT_s ensemble)
};

struct AccuracyStudy {
  std::string case_name;
  struct Reference {
    bool present = false;
    std::string setting;
    double phi_net_deg = 0;      // MuJoCo: mean over the perturbed ensemble
    double uncertainty_deg = 0;  // estimated error of the reference itself
    // MuJoCo only: spread (standard deviation) of phi_net when dT_s is perturbed by 1..K us at
    // fixed settings; contact chatter makes phi_net this sensitive. Errors below it are noise.
    double noise_deg = 0;
    double noise_default_deg = 0;  // the same at tailsim's default settings
    std::vector<std::string> evidence;  // Markdown bullet lines: how convergence was established
  };
  Reference analytic, mujoco;
  double analytic_exact_deg = NAN;  // analytic reference with the exact coupling (perspective)
  std::vector<AccuracyRow> rows;
};

struct AccuracyOptions {
  int repeats = 3;          // wall time = median of this many runs (1 for runs above 0.5 s)
  bool mujoco = true;       // include the MuJoCo families
  bool quick = false;       // a reduced grid (tests)
};

// Every case of `e` (kind: simulate), both models unless options.mujoco is false.
std::vector<AccuracyStudy> runAccuracyStudy(const Experiment& e, const AccuracyOptions& options);

// Throws std::runtime_error naming the file when DIR/accuracy.csv or DIR/accuracy.md is there but not
// tailsim's (its .tailsim-manifest does not name it as it is): checked before the study runs.
void checkAccuracyTables(const std::string& dir);
// DIR/accuracy.csv and DIR/accuracy.md (tables, defaults marked, references and their error), each
// only over a file of tailsim's (writeOwnedFile).
void writeAccuracyTables(const std::vector<AccuracyStudy>& studies, const std::string& dir);

}  // namespace tailsim
