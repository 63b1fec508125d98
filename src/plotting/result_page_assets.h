// The result page's fixed parts (result_page.h): its style sheet, the body of DIR/index.html and
// its script DIR/page/tailsim.js. None holds text from the inputs; the script puts every such text
// on the page with textContent (never innerHTML).
#pragma once

namespace tailsim {

extern const char* const kResultPageCss;
extern const char* const kResultPageBody;
extern const char* const kResultPageJs;

}  // namespace tailsim
