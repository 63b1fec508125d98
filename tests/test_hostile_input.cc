// Hostile and malformed experiment files: every one is refused
// quickly with "<file>:<line>:<col>: ..." naming what is wrong; none crashes, hangs, runs cases
// first or quotes megabytes back at the user.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "experiments/experiment_loader.h"
#include "rendering/render_settings.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;

class HostileInput : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "tailsim_hostile_XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& rel, const std::string& text) {
    const fs::path p = dir_ / rel;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  // A valid experiment (lines 1-4) followed by `rest` (from line 5).
  static std::string exp(const std::string& rest) {
    return "name: t\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nmodels: [analytic]\n" + rest;
  }
  // The ConfigError message of loading `text` as exp.yaml ("" and a test failure when it loads).
  std::string errorOf(const std::string& text, bool suite = false) {
    const std::string p = write("exp.yaml", text);
    try {
      if (suite) loadExperimentSuite(p);
      else loadExperiment(p);
    } catch (const ConfigError& e) {
      return e.what();
    }
    ADD_FAILURE() << "loaded without an error: " << text.substr(0, 200);
    return "";
  }
  // Expects the message to start with exp.yaml:<line>: and contain `what`.
  void expectAt(const std::string& msg, int line, const std::string& what) {
    const std::string prefix = (dir_ / "exp.yaml").string() + ":" + std::to_string(line) + ":";
    EXPECT_EQ(msg.rfind(prefix, 0), 0u) << msg << "\nexpected prefix " << prefix;
    EXPECT_NE(msg.find(what), std::string::npos) << msg << "\nexpected to contain: " << what;
    EXPECT_LT(msg.size(), 600u) << "error message too long";
  }
  fs::path dir_;
};

// ---------------------------------------------------------------- hostile YAML

TEST_F(HostileInput, Finding8_SelfReferentialAliasIsRefused) {
  // 11 bytes that made the loader recurse until it crashed.
  expectAt(errorOf("a: &a [*a]\n"), 1, "cycle");
  expectAt(errorOf(exp("description: &d {x: [1, {y: *d}]}\n")), 5, "cycle");
}

TEST_F(HostileInput, Finding8_AliasBombIsRefused) {
  // Each level lists the previous one 10 times: 10^9 values from ~600 bytes.
  std::string text = "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i <= 9; ++i) {
    const std::string p = "*l" + std::to_string(i - 1);
    text += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [" + p;
    for (int k = 1; k < 10; ++k) text += ", " + p;
    text += "]\n";
  }
  const std::string msg = errorOf(text);
  EXPECT_NE(msg.find("more than " + std::to_string(kMaxYamlNodes)), std::string::npos) << msg;
  EXPECT_NE(msg.find("alias"), std::string::npos) << msg;
  EXPECT_EQ(msg.rfind((dir_ / "exp.yaml").string() + ":", 0), 0u) << msg;
}

TEST_F(HostileInput, Finding8_PlainAliasesStillLoad) {
  const Experiment e = loadExperiment(write("exp.yaml", exp("description: &d some text\ntail: {links: &n 2}\n"
                                                            "quadruped: {d_Q2B_m: &b 0.125, d_Q2C_m: *b}\n")));
  ASSERT_EQ(e.cases.size(), 1u);
  EXPECT_EQ(e.description, "some text");
  EXPECT_EQ(e.cases[0].robot.numLinks(), 2);
  EXPECT_DOUBLE_EQ(e.cases[0].robot.quadruped.d_Q2C_m, 0.125);
}

TEST_F(HostileInput, Finding8_DeepNestingIsRefused) {
  const int n = 100000;
  expectAt(errorOf("a: " + std::string(n, '[') + std::string(n, ']') + "\n"), 1, "nested more than");
  // (yaml-cpp takes no flow map as a flow map key: a syntax error, still at file:line:col)
  expectAt(errorOf("a: " + std::string(n, '{') + std::string(n, '}') + "\n"), 1, "YAML syntax error");
  expectAt(errorOf("a: " + std::string(n, '{') + "\n"), 1, "");
  std::string mixed;
  for (int i = 0; i < n / 2; ++i) mixed += "{k: [";
  expectAt(errorOf("a: " + mixed + "\n"), 1, "nested more than");
  // Block style, one level per line.
  std::string block;
  for (int i = 0; i < 200; ++i) block += std::string(static_cast<size_t>(2 * i), ' ') + "k:\n";
  expectAt(errorOf(block), kMaxYamlDepth + 1, "nested more than " + std::to_string(kMaxYamlDepth));
  // An alias does not hide depth: 40 levels used twice.
  const std::string deep40 = std::string(40, '[') + std::string(40, ']');
  expectAt(errorOf("a: &a " + deep40 + "\nb: " + std::string(40, '[') + "*a" + std::string(40, ']') + "\n"), 2,
           "nested more than");
}

TEST_F(HostileInput, Finding8_TooManyNodesAreRefused) {
  std::string text = "a: [";
  for (long i = 0; i <= kMaxYamlNodes; ++i) text += "1,";
  text += "1]\n";
  expectAt(errorOf(text), 1, "more than " + std::to_string(kMaxYamlNodes));
}

TEST_F(HostileInput, Finding8_DeepSuiteChainIsRefused) {
  write("leaf.yaml", exp(""));
  const int n = 100;
  for (int i = 0; i < n; ++i)
    write("s" + std::to_string(i) + ".yaml",
          "experiments: [" + (i + 1 < n ? "s" + std::to_string(i + 1) + ".yaml" : std::string("leaf.yaml")) + "]\n");
  try {
    loadExperimentSuite((dir_ / "s0.yaml").string());
    ADD_FAILURE() << "a suite chain " << n << " deep loaded";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("nested more than " + std::to_string(kMaxSuiteDepth)), std::string::npos) << msg;
    EXPECT_NE(msg.find(".yaml:1:"), std::string::npos) << msg;
  }
  // 10 deep is fine.
  write("s10.yaml", "experiments: [leaf.yaml]\n");
  EXPECT_EQ(loadExperimentSuite((dir_ / "s1.yaml").string()).size(), 1u) << "s1 -> ... -> s10 -> leaf";
}

// ---------------------------------------------------------------- late or ugly errors

TEST_F(HostileInput, Finding10_NonUtf8TextIsRefusedAtLoad) {
  expectAt(errorOf("name: t\xff\n" + exp("").substr(8)), 1, "UTF-8");
  expectAt(errorOf(exp("description: \"caf\xe9\"\n")), 5, "byte 0xE9");
  expectAt(errorOf(exp("description: ok \xc0\xaf overlong\n")), 5, "UTF-8");  // overlong '/'
  // Valid UTF-8 (2-, 3- and 4-byte characters) loads.
  EXPECT_EQ(loadExperiment(write("ok.yaml", exp("description: \"caf\xc3\xa9 \xe2\x86\x92 \xf0\x9f\x90\x95\"\n")))
                .description,
            "caf\xc3\xa9 \xe2\x86\x92 \xf0\x9f\x90\x95");
}

TEST_F(HostileInput, Finding10_NonUtf8FilePathIsRefusedAtLoad) {
  // The path goes into summary.json (UTF-8 JSON): refused before any case runs.
  const std::string p = write("caf\xe9.yaml", exp(""));
  for (auto load : {+[](const std::string& f) { loadExperiment(f); },
                    +[](const std::string& f) { loadExperimentSuite(f); }}) {
    try {
      load(p);
      ADD_FAILURE() << "loaded";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("path is not UTF-8"), std::string::npos) << e.what();
    }
  }
}

TEST_F(HostileInput, Finding10_RenderLimitsAreCheckedAtLoad) {
  // Everything the renderer would refuse later, refused at load with file:line (render_settings.h).
  expectAt(errorOf(exp("render: {width: 10000}\n")), 5, "render.width: must be in 16..8192");
  expectAt(errorOf(exp("render: {width: 641}\n")), 5, "render.width: must be even");
  expectAt(errorOf(exp("render: {height: 481}\n")), 5, "render.height: must be even");
  expectAt(errorOf(exp("render: {fps: 500}\n")), 5, "render.fps: must be in 1..240");
  expectAt(errorOf(exp("render: {msaa: 32}\n")), 5, "render.msaa: must be in 0..4");
  expectAt(errorOf(exp("render: {msaa: 8}\n")), 5, "render.msaa: must be in 0..4");
  expectAt(errorOf(exp("render: {slowmo: 1e300}\n")), 5, "render.slowmo: must lie in [0.001, 1000]");
  expectAt(errorOf(exp("render: {slowmo: 1e-300}\n")), 5, "render.slowmo: must lie in");
  // A long run at high slow motion: too many frames, said before anything runs.
  expectAt(errorOf(exp("output: {duration_s: 200}\nrender: {fps: 240, slowmo: 1000}\n")), 6, "frames");
  // The limits themselves load.
  const Experiment e = loadExperiment(write("ok.yaml", exp("render: {width: 8192, height: 16, fps: 240, msaa: 4, "
                                                          "slowmo: 0.001}\n")));
  EXPECT_EQ(e.cases[0].render.width, kRenderMaxSize);
  EXPECT_EQ(e.cases[0].render.fps, kRenderMaxFps);
  EXPECT_EQ(e.cases[0].render.msaa, kRenderMaxMsaa);
}

TEST_F(HostileInput, Finding10_QuotedValuesAreTruncated) {
  // A robot "file" that is not YAML of ours: the message shows the start of it, not all of it.
  std::string passwd;
  for (int i = 0; i < 200; ++i) passwd += "user" + std::to_string(i) + ":x:1000:1000::/home/u:/bin/sh\n";
  write("passwd", passwd);
  try {
    loadExperiment(write("exp.yaml", "name: t\nrobot: ./passwd\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"));
    ADD_FAILURE() << "loaded";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_LT(msg.size(), 400u) << msg;
    EXPECT_NE(msg.find("user0:x:1000"), std::string::npos) << msg;
    EXPECT_NE(msg.find("..."), std::string::npos) << msg;
  }
  // A 1 MB value.
  const std::string big(1 << 20, 'z');
  expectAt(errorOf(exp("kind: " + big + "\n")), 5, "unknown value 'zzzz");
  expectAt(errorOf(exp("quadruped: {mass_kg: " + big + "}\n")), 5, "zzz...");
  expectAt(errorOf(exp(big + ": 1\n")), 5, "YAML syntax error");  // keys are at most 1024 characters
  expectAt(errorOf("name: t\nrobot: " + big + "\n"), 2, "unknown built-in robot 'zzz");
}

TEST_F(HostileInput, Finding10_UnreadableFileNamesTheOsError) {
  // /proc/self/mem opens but every read at offset 0 fails (EIO): the error names file and cause.
  try {
    loadExperiment("/proc/self/mem");
    ADD_FAILURE() << "loaded /proc/self/mem";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "/proc/self/mem: cannot read the file: Input/output error");
  }
  try {
    loadExperiment(write("exp.yaml", "name: t\nrobot: /proc/self/mem\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"));
    ADD_FAILURE() << "loaded";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/self/mem: cannot read the file: Input/output error"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace tailsim
