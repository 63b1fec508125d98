// The look of every tailsim figure, declared once: the colour-blind-safe Okabe-Ito palette with a
// fixed colour per model, the diverging / sequential colour maps of the heat maps, and the words
// (gnuplot enhanced text: subscripts, Greek) for swept keys, their values and figure titles.
//
// Enhanced text: `_` subscripts one character or a {group}, `^` superscripts; gpText() escapes
// free text (case names, descriptions) so an underscore prints as an underscore.
#pragma once

#include <string>
#include <vector>

#include "plotting/result_folder.h"
#include "common/palette.h"

namespace tailsim {

// ---- colours: the Okabe-Ito palette, common/palette.h (shared with the videos) -------------

// Fixed colour per model in every plot: analytic blue, MuJoCo vermillion, others bluish green.
std::string modelColor(const std::string& model);
// Legend / panel name of a model: "analytic (stiction)", "MuJoCo (contact)".
std::string modelTitle(const std::string& model);
// The same in an experiment whose cases name a model file (articulated: its MuJoCo run is the user's
// articulated robot, ModelEntry::articulated_title).
std::string modelTitle(const std::string& model, bool articulated);
// Its title without the parenthesis ("MuJoCo", "analytic"): for panels that compare models over a
// swept key the parenthesis may name ("analytic (stiction)" when the friction law is swept), and
// for the keys of a model's own section ("MuJoCo foot shape").
std::string modelShortTitle(const std::string& model);
// One sentence naming what each of `models` is, in the order analytic, per-foot, MuJoCo, only the
// models given: "Analytic = the paper's model (stiction friction); per-foot = ...; MuJoCo = ...".
std::string modelGlossary(const std::vector<std::string>& models);
// The title of one model's panel in a figure over swept keys (enhanced text): what the panel
// compares. The model's title, without its parenthesis when that names a value of a swept key
// ("analytic", not "analytic (stiction)", when the friction law is swept); then the values of each
// non-numeric key ("stiction vs continuous × paper vs exact coupling"; numeric keys are on the
// axes); then each swept key the model does not read ("analytic.coupling" for MuJoCo): "coupling
// not used". Only numeric keys, all read: the model's title.
std::string gpPanelTitle(const std::string& model, const std::vector<SweepAxis>& axes);
// Curves that are not models (one per case or per value of a key), in every figure the same way:
// the five Okabe-Ito line colours that are not a model's (orange, sky blue, bluish green, reddish
// purple, black) in that order, then five darker or greyer ones (brown, grey, dark purple, olive,
// dark teal): no colour twice among the first ten curves (Fig. 9: seven values of d_Q2B; Fig. 14:
// six tails). All solid for the first ten, then the same colours dashed, then dotted, ...; the
// points differ too: (colour, dash, point) differs for every i < 40.
std::string seriesColor(size_t i);
int seriesDash(size_t i);   // gnuplot dashtype: 1 solid for the first 10, then 2, 3, 4, 1, ...
int seriesPoint(size_t i);  // gnuplot pointtype (pngcairo/svg): 13 distinct, filled then open
size_t numSeriesColors();   // 10
// Every Okabe-Ito line colour (yellow left out), for plots whose series are neither models nor
// cases (the accuracy study's integrator families): 7 distinct colours.
std::string categoricalColor(size_t i);
// The three moments of Figs. 6-7 (tail, friction, inertial), never a model's colour.
std::string quantityColor(size_t i);

// gnuplot `set palette defined (...)` for values of both signs and differences, on a range
// centred on zero (blue - white - vermillion), and for one-signed values (white - orange - dark
// orange; dark_at_low: dark orange - orange - white, for values that are all negative).
std::string divergingPalette();
std::string sequentialPalette(bool dark_at_low = false);

// ---- words -----------------------------------------------------------------------------------
// Escapes gnuplot enhanced-text control characters (_ ^ @ & ~ { } \) in free text.
std::string gpText(const std::string& s);
// Plain text with tailsim's identifiers turned into enhanced-text symbols:
// "phi_net over theta0 and d_Q2B" -> "φ_{net} over θ_0 and d_{Q2B}"; everything else escaped.
std::string gpSymbols(const std::string& s);
// Same in plain Unicode for HTML/Markdown captions ("φ_net over θ0 and d_Q2B").
std::string plainSymbols(const std::string& s);

// ---- titles that fit ---------------------------------------------------------------------------
// Visible characters of enhanced text: markup (unescaped _ ^ { } @ & ~ and the backslash of an
// escape) counts nothing, a UTF-8 character one, a combining mark (U+0300-U+036F, the dot of φ̇)
// nothing. Subscripts count as full characters (a safe over-estimate).
size_t gpTextWidth(const std::string& enhanced);
// Enhanced text broken into lines ('\n' between them) of at most max_chars visible characters,
// at spaces outside {groups} only, preferring the " — " between a figure's name and what it shows;
// a word longer than a line stays whole. Text that fits is returned unchanged.
std::string wrapGpText(const std::string& enhanced, size_t max_chars);
// How many characters of a title line fit across width_px pixels in a font_pt Sans font (pngcairo
// and svg draw 15 pt Sans at ~9.7 px per character on average; 12 % is left for the margins).
size_t titleChars(int width_px, double font_pt);
// A title for `set title`, `set multiplot ... title`: wrapped to width_px and quoted (gpQuote
// writes the line breaks as "\n"). font_pt: the title's font (15 default, 17 multiplot titles).
std::string gpTitle(const std::string& enhanced, int width_px, double font_pt = 15);

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
// figureName in enhanced text: "Fig. 7 case with μ_s and μ_d swapped" with subscripts.
std::string gpFigureName(const std::string& description, const std::string& experiment);

}  // namespace tailsim
