// The result page's writer (src/plotting/result_page.h): the one escape of text from the inputs,
// and a user's DIR/index.html never replaced. The page in a browser: result_page_browser_test.py.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "plotting/result_page.h"

namespace fs = std::filesystem;
using tailsim::jsString;

namespace {

// What must never appear in a literal written into a <script> element or a .js file.
void expectInert(const std::string& lit) {
  ASSERT_GE(lit.size(), 2u);
  EXPECT_EQ(lit.front(), '"');
  EXPECT_EQ(lit.back(), '"');
  EXPECT_EQ(lit.find('<'), std::string::npos) << lit.substr(0, 80);
  EXPECT_EQ(lit.find('>'), std::string::npos) << lit.substr(0, 80);
  EXPECT_EQ(lit.find("\xE2\x80\xA8"), std::string::npos);  // U+2028
  EXPECT_EQ(lit.find("\xE2\x80\xA9"), std::string::npos);  // U+2029
  for (unsigned char c : lit) EXPECT_TRUE(c >= 0x20 && c != 0x7F) << "raw control byte " << int(c);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(ResultPageEscape, HostileTextRoundTripsAndCannotEndAScript) {
  const std::vector<std::string> hostile = {
      "</script><script>alert(1)</script>",
      "<!-- <script>",
      "\"double\" 'single' `back` \\ backslash & amp",
      std::string("nul\0inside", 10),
      "tab\tnewline\ncarriage\rbell\x07 del\x7F esc\x1B",
      "line\xE2\x80\xA8separator\xE2\x80\xA9paragraph",
      "unicode: \xCE\xB8\xE2\x82\x80 \xF0\x9F\x90\x95 (theta0, a dog)",
      std::string(10000, 'n') + "</SCRIPT>",
      "",
  };
  for (const std::string& s : hostile) {
    const std::string lit = jsString(s);
    expectInert(lit);
    // The literal is JSON too (JavaScript reads it the same): it parses back to the text.
    EXPECT_EQ(nlohmann::json::parse(lit).get<std::string>(), s) << lit.substr(0, 80);
  }
}

TEST(ResultPageEscape, BytesThatAreNotUtf8BecomeReplacementCharacters) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"a\xFF" "b", "a\xEF\xBF\xBD" "b"},                  // not a lead byte
      {"\xC3", "\xEF\xBF\xBD"},                              // truncated sequence
      {"\xC0\xAF", "\xEF\xBF\xBD\xEF\xBF\xBD"},              // overlong '/'
      {"\xED\xA0\x80", "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD"},  // a UTF-16 surrogate
  };
  for (const auto& [in, want] : cases) {
    const std::string lit = jsString(in);
    expectInert(lit);
    EXPECT_EQ(nlohmann::json::parse(lit).get<std::string>(), want);
  }
}

TEST(ResultPage, NeverReplacesAUserIndex) {
  const fs::path dir = fs::temp_directory_path() / ("tailsim_page_user_index_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string mine = "<html><body>my own notes</body></html>\n";
  { std::ofstream(dir / "index.html") << mine; }
  try {
    tailsim::writeResultPage(dir.string());
    ADD_FAILURE() << "a user's index.html was not refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not written by tailsim"), std::string::npos) << e.what();
  }
  EXPECT_EQ(slurp(dir / "index.html"), mine);
  EXPECT_FALSE(fs::exists(dir / "page"));
  fs::remove_all(dir);
}
