// The Markdown reproduction report (`tailsim report DIR`): for a suite folder (one result folder
// per experiment, as `tailsim run configs/paper/all.yaml --out DIR` writes) or a single
// experiment's folder. It lists every paper claim with a YES / NO / n/a verdict per model and
// the numbers behind it (findings.h), the Fig. 6 phi_net table, the mu_s/mu_d swap, and every
// experiment's figures.
#pragma once

#include <string>
#include <vector>

#include "plotting/findings.h"
#include "plotting/plots.h"

namespace tailsim {

// The report text. `base_dir` is the folder the report is written to (image links are relative
// to it); `plots` are the figures to embed (from plotResults, or the PNGs found in each
// experiment's plots/ folder when empty).
std::string reportMarkdown(const std::vector<ExperimentResults>& results, const std::vector<Finding>& findings,
                           const std::vector<PlotFile>& plots, const std::string& base_dir);

// Writes DIR/report.md (drawing the figures first when draw_plots) and returns its path.
// Throws std::runtime_error if DIR holds no result folder or gnuplot fails.
std::string writeReport(const std::string& dir, bool draw_plots = true);

}  // namespace tailsim
