// The paper's claims (paper-notes "Checks that follow from the text", Sec. 4.4's Fig. 8
// statements and Fig. 13's "larger |dtheta| wins at a fixed peak speed"), each checked against
// a result folder, model by model, with the numbers that decide it.
//
// Experiments are found by name prefix (fig06a, fig06b, fig07, ..., fig14, mu_swapped: the
// names of configs/paper/*.yaml) and sweep axes by leaf key (d_Q2B_m, theta0_deg, ...).
// phi_net is compared signed: positive = counter-clockwise, against the tail's clockwise swing
// (dtheta < 0), the direction the paper's figures show as positive.
#pragma once

#include <string>
#include <vector>

#include "plotting/result_folder.h"

namespace tailsim {

enum class Verdict { kYes, kNo, kNotAvailable };
const char* verdictText(Verdict v);  // "YES", "NO", "n/a"

struct ModelVerdict {
  std::string model;   // "analytic", "mujoco", or "mujoco vs analytic" for comparisons
  Verdict verdict = Verdict::kNotAvailable;
  std::string detail;  // the numbers behind the verdict, or why there is none
};

struct Finding {
  std::string id;     // short stable id, e.g. "fig09_dQ2B_rises"
  std::string where;  // "Sec. 4.4, Fig. 9"
  std::string claim;  // what the paper says
  std::vector<ModelVerdict> verdicts;
  std::string brief{};  // the claim in a few words (report table); set by computeFindings
  const ModelVerdict* verdictFor(const std::string& model) const;  // nullptr if absent
};

// Whether y (ordered by increasing x) strictly rises (direction +1) or falls (-1) at every step.
struct Trend {
  bool complete = false;   // every value finite
  bool holds = false;      // complete and every step has the wanted sign (|step| > tol)
  double min_step = 0.0;   // smallest step in the wanted direction (direction * (y[i+1]-y[i]))
  size_t worst = 0;        // index i of that step (y[i] -> y[i+1])
  int zero_plateaus = 0;   // steps skipped because both ends are 0 (zero_plateaus_ok)
};
// With zero_plateaus_ok, a flat step between two values with |y| <= tol (the body never broke
// static friction in either case) is neither a rise nor a reversal: it is skipped and counted.
Trend checkTrend(const std::vector<double>& y, int direction, double tol = 1e-9, bool zero_plateaus_ok = false);

// Every finding the given experiments allow (a finding whose experiment is missing is listed
// with n/a verdicts, so the report always has the full list).
std::vector<Finding> computeFindings(const std::vector<ExperimentResults>& results);

// The first experiment whose name starts with `prefix`, or nullptr.
const ExperimentResults* findExperiment(const std::vector<ExperimentResults>& results, const std::string& prefix);
// The axis whose leaf key is `leaf` ("d_Q2B_m"), or nullptr.
const SweepAxis* findAxis(const ExperimentResults& r, const std::string& leaf);

}  // namespace tailsim
