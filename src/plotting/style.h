// The look of every tailsim figure, declared once: the colour-blind-safe Okabe-Ito palette with a
// fixed colour per model, the diverging / sequential colour maps of the heat maps, and the words
// (gnuplot enhanced text: subscripts, Greek) for swept keys, their values and figure titles.
//
// Enhanced text: `_` subscripts one character or a {group}, `^` superscripts; gpText() escapes
// free text (case names, descriptions) so an underscore prints as an underscore.
#pragma once

#include <string>

#include "results/palette.h"

namespace tailsim {

// ---- colours: the Okabe-Ito palette, results/palette.h (shared with the videos) -------------

// Fixed colour per model in every plot: analytic blue, MuJoCo vermillion, others bluish green.
std::string modelColor(const std::string& model);
// Legend / panel name of a model: "analytic (stiction)", "MuJoCo (contact)".
std::string modelTitle(const std::string& model);
// Curves that are not models (one per case or per value of a key): Okabe-Ito colours in an order
// that keeps neighbours apart, then again with dashes (seriesDash) after the 7th.
std::string seriesColor(size_t i);
int seriesDash(size_t i);  // gnuplot dashtype: 1 solid for the first 7, then 2, 3, ...
// Every Okabe-Ito line colour (yellow left out), for plots whose series are neither models nor
// cases (the accuracy study's integrator families): 7 distinct colours.
std::string categoricalColor(size_t i);
// The three moments of Figs. 6-7 (tail, friction, inertial), never a model's colour.
std::string quantityColor(size_t i);

// gnuplot `set palette defined (...)` for a signed quantity on a range centred on zero
// (blue - white - vermillion) and for a one-signed quantity (white - orange - dark orange).
std::string divergingPalette();
std::string sequentialPalette();

// ---- words -----------------------------------------------------------------------------------
// Escapes gnuplot enhanced-text control characters (_ ^ @ & ~ { } \) in free text.
std::string gpText(const std::string& s);
// Plain text with tailsim's identifiers turned into enhanced-text symbols:
// "phi_net over theta0 and d_Q2B" -> "φ_{net} over θ_0 and d_{Q2B}"; everything else escaped.
std::string gpSymbols(const std::string& s);
// Same in plain Unicode for HTML/Markdown captions ("φ_net over θ0 and d_Q2B").
std::string plainSymbols(const std::string& s);

// A swept key as shown on an axis or in a legend, and how to show its values.
struct KeyDisplay {
  std::string symbol;  // enhanced text, "d_{Q2B}", "Δθ", "tail links n", "friction law"
  std::string plain;   // Unicode for captions, "d_Q2B", "Δθ"
  std::string unit;    // shown unit, "mm", "deg", "s", "" (none)
  double scale = 1.0;  // shown value = stored value * scale (d_Q2B_m -> mm)
};
KeyDisplay keyDisplay(const std::string& key);
// "d_{Q2B} [mm]"; "tail links n"; "friction law".
std::string gpAxisLabel(const std::string& key);
// A value of a key in words for legends and tic labels: "d_{Q2B} = 25 mm", "Δθ = -90°",
// "w_{ss} = 0.25", "n = 3 links", "stiction", "paper coupling". with_symbol=false: "25", "-90°".
std::string gpValueLabel(const std::string& key, const std::string& value, bool with_symbol = true);
std::string plainValueLabel(const std::string& key, const std::string& value);

// The figure's name from the experiment's description: "Fig. 6(a): phi(t), ..." -> "Fig. 6a";
// a description without a colon is the name itself ("Fig. 7 case with mu_s and mu_d swapped ...").
// Plain Unicode (no markup). Falls back to the experiment name with spaces for underscores when
// there is no description.
std::string figureName(const std::string& description, const std::string& experiment);
// Sort key for paper order: the figure number (6.0 for "Fig. 6(a)", 6.1 for "Fig. 6(b)"), or a
// large number when the description names no figure.
double figureOrder(const std::string& description);

}  // namespace tailsim
