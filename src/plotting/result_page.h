// The result page: DIR/index.html, an interactive page over a result folder that opens from the
// file system with no server and no network (docs/result-page.md).
//
//   DIR/index.html               the page shell (no text from the inputs in it)
//   DIR/page/tailsim.js          the page's own script (tables, heat maps, plots, 3D replay)
//   DIR/page/three.min.js, OrbitControls.js, three-LICENSE   three.js r111 from Debian's libjs-three
//   DIR/page/data.js             every experiment: swept keys, figures, notes and the results table
//                                as columnar arrays (tailsim.dataLoaded({...}))
//   DIR/page/cases/e<i>c<k>.js   one case's replay, loaded on demand by a <script> tag
//                                (tailsim.caseLoaded({...})): the robot's geometry from the compiled
//                                MJCF and each model's time series
//
// file:// pages cannot fetch() local files in Chromium, hence data as scripts. Every text that comes
// from the inputs (names, keys, values, warnings, errors) is written through jsString, the one
// escape; the HTML itself carries none.
#pragma once

#include <string>

namespace tailsim {

// s as a JavaScript/JSON string literal (with its quotes) that is safe inside an HTML <script>
// element and inside a .js file: ", \ and control characters (NUL included) escaped, <, >, & as
// \u003c \u003e \u0026 (no "</script>" or "<!--"), U+2028 and U+2029 escaped (line terminators in
// older JavaScript), and bytes that are not UTF-8 replaced by U+FFFD.
std::string jsString(const std::string& s);

// DIR/index.html.
std::string resultPagePath(const std::string& dir);

// Writes DIR/index.html and DIR/page/ (each file whole or not at all) for the result folder or
// suite folder DIR and returns the index's path. Throws std::runtime_error if DIR is no result
// folder, or if DIR/index.html exists and was not written by tailsim (a user's file is never
// replaced). Without Debian's three.js (libjs-three) the page has no 3D view and says so (a note
// on stderr too).
std::string writeResultPage(const std::string& dir);

}  // namespace tailsim
