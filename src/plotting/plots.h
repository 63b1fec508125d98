// gnuplot figures of a result folder (`tailsim plot DIR`). Which figures are drawn follows the
// data's structure, not the experiment's name:
//   simulate, no sweep      -> phi(t) of every model overlaid; M_zT, M_zF, I_zz phi_ddot over time
//                              (one panel per model)                                  (Figs. 6, 7)
//   simulate, 1 swept key   -> phi_net over the key, one curve per model (bars side by side when
//                              the key is the number of tail links); phi(t) of every case when
//                              there are at most 12                              (Figs. 11, 13, 14)
//   simulate, 2 swept keys  -> heat map of phi_net with the values in the cells (large grids:
//                              smaller cells, no values; heatMapLayout), one per model
//                              side by side; phi_net over the faster key, one curve per value of
//                              the slower one                                        (Figs. 9, 12)
//                              plus, with two models, the difference of the second from the
//                              first (diverging colours centred on zero)
//   simulate, 3+ swept keys -> small multiples, one figure per model: phi_net over the numeric key
//                              with the most values, one curve per value of the key with the
//                              fewest, one panel per combination of the other keys (facetKeys)
//   pose, 1 swept key       -> M_zT,tan/I_zz and M_zT,cen/I_zz (else the acceleration-/speed-driven
//                              parts) over the key; L_F over the key                      (Fig. 8)
//   pose, 2 swept keys      -> heat map of L_F                                           (Fig. 10)
// Every figure is DIR/plots/<experiment>_<what>.png and .svg, with its .gp script and .dat files.
// Titles are words ("Fig. 6a — body yaw φ(t), 1-link tail: analytic vs MuJoCo", from the
// experiment's description), colours follow plotting/style.h (one colour per model everywhere),
// time axes end shortly after the last motion, and single-case figures shade the phases A-D of
// the analytic run (tail t1; φ̇ = 0; body stuck again).
#pragma once

#include <string>
#include <vector>

#include "plotting/result_folder.h"

namespace tailsim {

struct PlotFile {
  std::string png;      // absolute or DIR-relative path as built from the result folder; .svg beside it
  std::string caption;  // what the figure shows, in words (plain Unicode, no markup)
  std::string title;    // the figure's title as drawn, in plain Unicode ("Fig. 7 — moments ...")
};

// The size of a heat map's cells (px), whether each cell prints its value, and every how many
// values a tic is labelled, for nx x ny cells: 105 x 82 px cells with values up to 19 x 17
// cells, smaller cells without values beyond (the whole grid in about 2000 x 1400 px, cells at
// least 1 px: a 50 x 100 or 100 x 1,000 sweep is one readable picture within cairo's 32767 px).
struct HeatMapLayout {
  int cell_w = 105, cell_h = 82;
  bool values_in_cells = true;
  size_t xtic_every = 1, ytic_every = 1;
  int panel_w = 0, panel_h = 0;  // one panel: the cells, axes, colour box and titles
};
HeatMapLayout heatMapLayout(size_t nx, size_t ny);

// How the figures are drawn for a paper or slides (`tailsim plot --no-titles --size W,H
// --font-scale F`): without the figure's own title (the caption keeps it; panel titles stay),
// every figure at W x H pixels (0: each figure's own size), fonts scaled by F.
struct PlotOptions {
  bool titles = true;
  int width_px = 0, height_px = 0;
  double font_scale = 1.0;
};

// The roles of the swept keys in a figure of 3 or more keys (indices into axes): x is the numeric
// key with the most values (the first key with the most values when none is numeric), series the
// remaining key with the fewest values (one curve each), facets the others in file order (one
// panel per combination of their values).
struct FacetKeys {
  size_t x = 0, series = 1;
  std::vector<size_t> facets;
};
FacetKeys facetKeys(const std::vector<SweepAxis>& axes);

// Draws the figures of one experiment into r.dir/plots/. Throws std::runtime_error if gnuplot
// fails; a model whose CSV is missing is left out of the figures that need it.
std::vector<PlotFile> plotExperiment(const ExperimentResults& r, const PlotOptions& opt = {});

// DIR is one result folder or a suite folder (one result folder per experiment under it).
// Returns every figure written, and writes DIR/figures.html (figure_sheet.h) listing them.
std::vector<PlotFile> plotResults(const std::string& dir, const PlotOptions& opt = {});

}  // namespace tailsim
