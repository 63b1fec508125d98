// What one experiment's results say, in sentences, for any experiment (not only the paper's):
// figures.html and report.md show it under each experiment. From summary.json alone (phi_net of
// every run, its warnings), so it needs no time series.
//   best      the case with the largest phi_net, per model, with its swept values
//   trends    per swept key and model: phi_net averaged over the other keys at each value of the
//             key, and how it goes (rises, falls, peaks at, dips at, flat; largest at a value for
//             a categorical key)
//   disagree  with two or more models: each model against the first (analytic), the largest
//             difference and where, the mean absolute difference, the cases of opposite sign.
//             Results carry no uncertainty yet, so no difference is called significant.
//   warnings  every run's warnings gathered once: one line per warning text (numbers masked,
//             warningShape) with the model, how many runs and the first case
// Pose studies (no motion, phi_net is zero) have no phi_net summary; their warnings are listed.
#pragma once

#include <string>
#include <vector>

#include "plotting/result_folder.h"

namespace tailsim {

struct SweepSummary {
  std::vector<std::string> best, trends, disagree, warnings;  // plain Unicode sentences
};
SweepSummary summarizeSweep(const ExperimentResults& r);

// Whether the experiment reproduces a paper figure: its description names one ("Fig. 9: ...",
// "Fig. 7 case with ...", style.h figureOrder), or its name is one of configs/paper/'s, which the
// findings look experiments up by (fig06a..., fig14..., model_bridge..., mu_swapped). The
// paper-claims parts of figures.html and report.md are shown only when some experiment is one.
bool isPaperFigure(const ExperimentResults& r);

}  // namespace tailsim
