// Settings declared once and the resolved case: the declarations drive
// the loader, validation, the resolved JSON and the resume key.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/settings_json.h"
#include "experiments/settings_schema.h"
#include "scratch_dir.h"

using namespace tailsim;
using tailsim::testing::ScratchDir;
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string loadError(const fs::path& dir, const std::string& yaml) {
  const fs::path f = dir / "e.yaml";
  std::ofstream(f) << yaml;
  try {
    loadExperiment(f.string());
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

const char* kBase = "name: s\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n";

// Changes each declared field of a struct in turn (numbers up, bools flipped, enums to the next
// value, strings appended) and calls back after each change.
struct Perturb {
  explicit Perturb(int t) : target(t) {}
  int target, index = 0;
  bool done = false;
  std::string key;
  bool hit() {
    if (done || index++ != target) return false;
    done = true;
    return true;
  }
  void number(const settings::Field& f, double& x, const settings::Limits&) {
    if (hit()) x = x == 0 ? 0.5 : x * 1.25, key = f.key;
  }
  void integer(const settings::Field& f, int& x, const settings::Limits&, const settings::IntSet& = {}) {
    if (hit()) x += 2, key = f.key;
  }
  void boolean(const settings::Field& f, bool& x) {
    if (hit()) x = !x, key = f.key;
  }
  template <class E>
  void choice(const settings::Field& f, E& x, const settings::EnumNames<E>& names) {
    if (hit()) x = names[(static_cast<int>(x) + 1) % names.size()].value, key = f.key;
  }
  void text(const settings::Field& f, std::string& x, const settings::TextRule&) {
    if (hit()) x += "x", key = f.key;
  }
  template <std::size_t N>
  void numbers(const settings::Field& f, std::array<double, N>& x) {
    if (hit()) x[0] *= 1.25, key = f.key;
  }
  template <class T>
  void internal(const settings::Field& f, T& x) {
    if (!hit()) return;
    key = f.key;
    if constexpr (std::is_same_v<T, bool>) x = !x;
    else x += 1;
  }
};

// Every declared field of the struct `pick` selects changes the resume key.
template <class Pick>
void expectEveryFieldInKey(const ExperimentCase& c, bool render, Pick pick, const char* what) {
  const std::string k0 = caseKey(c, render);
  for (int i = 0;; ++i) {
    ExperimentCase d = c;
    Perturb p(i);
    declareFields(p, pick(d));
    if (!p.done) {
      EXPECT_GT(i, 0) << what;
      break;
    }
    EXPECT_NE(caseKey(d, render), k0) << what << "." << p.key << " is not in the resume key";
  }
}

}  // namespace

// case -> JSON -> case -> JSON is exact for every case of the paper suite (defaults included).
TEST(ResolvedCase, RoundTripsEveryPaperCase) {
  const auto suite = loadExperimentSuite(std::string(TAILSIM_SOURCE_DIR) + "/configs/paper/all.yaml");
  int n = 0;
  for (const Experiment& e : suite)
    for (const ExperimentCase& c : e.cases) {
      const json j1 = resolvedJson(c);
      const ExperimentCase c2 = caseFromResolved(j1);
      ASSERT_EQ(j1.dump(), resolvedJson(c2).dump()) << e.name << "/" << c.name;
      EXPECT_EQ(caseKey(c, true), caseKey(c2, true));
      EXPECT_EQ(c2.robot.tail.size(), c.robot.tail.size());
      for (size_t i = 0; i < c.joints.size(); ++i) EXPECT_EQ(c2.joints[i].theta0_rad, c.joints[i].theta0_rad);
      ++n;
    }
  EXPECT_EQ(n, 264);  // the paper suite's cases (400 model runs)
}

TEST(ResolvedCase, ReaderNamesAMissingKey) {
  const ScratchDir dir("settings_missing");
  std::ofstream(dir / "e.yaml") << kBase;
  json j = resolvedJson(loadExperiment((dir / "e.yaml").string()).cases.at(0));
  j["mujoco"].erase("timestep_s");
  try {
    caseFromResolved(j);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("mujoco.timestep_s is missing"), std::string::npos) << e.what();
  }
}

// result.json holds the resolved case: defaults, tail links, per-joint trajectory, version.
TEST(ResolvedCase, ResultJsonHoldsEverySettingTheRunUsed) {
  const ScratchDir dir("settings_result");
  std::ofstream(dir / "e.yaml") << "name: r\nrobot: paper\ntail: {links: 2}\n"
                                   "trajectory: {theta0_deg: [10, 20], dtheta_deg: -30, dT_s: 0.2}\n";
  const Experiment e = loadExperiment((dir / "e.yaml").string());
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  runExperiment(e, o);
  std::ifstream in(dir / "out" / "cases" / "base" / "result.json");
  const json r = json::parse(in);
  ASSERT_TRUE(r.contains("resolved"));
  const json& v = r["resolved"];
  EXPECT_EQ(v["tail"].size(), 2u);
  EXPECT_DOUBLE_EQ(v["tail"][1]["mass_kg"].get<double>(), 1.20);  // Table 2, n = 2
  EXPECT_DOUBLE_EQ(v["joints"][1]["theta0_rad"].get<double>(), 20 * M_PI / 180);
  EXPECT_EQ(v["analytic"]["solver"], "adaptive");  // a default, written out
  EXPECT_EQ(v["mujoco"]["integrator"], "implicit");
  EXPECT_DOUBLE_EQ(v["friction"]["mu_d"].get<double>(), 0.30);
  EXPECT_TRUE(r.contains("tailsim_version"));
  // result.json leaves out where the values were read from (a re-run from the folder's copies
  // writes the same file); the rest reads back to the same case.
  EXPECT_FALSE(v.contains("robot_file"));
  EXPECT_FALSE(v.contains("source_file"));
  json back = resolvedJson(caseFromResolved(v));
  back.erase("robot_file");
  back.erase("source_file");
  EXPECT_EQ(back.dump(), v.dump());
  EXPECT_EQ(r["key"], caseKey(e.cases.at(0), false));
}

// A setting is in the resume key by being declared: each declared field changes the key.
TEST(ResumeKey, EveryDeclaredFieldIsInTheKey) {
  const ScratchDir dir("settings_key");
  std::ofstream(dir / "e.yaml") << kBase << "render: {}\n";
  const ExperimentCase c = loadExperiment((dir / "e.yaml").string()).cases.at(0);
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> QuadrupedParams& { return d.robot.quadruped; }, "quadruped");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> FrictionParams& { return d.robot.friction; }, "friction");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> TailLink& { return d.robot.tail[0]; }, "tail");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> SplitCycleParams& { return d.joints[0]; }, "joint");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> AnalyticSettings& { return d.analytic; }, "analytic");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> MujocoSettings& { return d.mujoco; }, "mujoco");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> Effects& { return d.effects; }, "effects");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> OutputSettings& { return d.output; }, "output");
  expectEveryFieldInKey(c, true, [](ExperimentCase& d) -> RenderSettings& { return d.render; }, "render");
  // Not rendered: the render settings do not matter.
  ExperimentCase d = c;
  d.render.fps = 60;
  EXPECT_EQ(caseKey(d, false), caseKey(c, false));
  EXPECT_NE(caseKey(d, true), caseKey(c, true));
}

// The loader refuses, at file:line:col, every render value the renderer would refuse (the same
// declared limits): fps above 240, odd or tiny sizes, msaa, crf, preset.
TEST(DeclaredLimits, LoaderRefusesWhatTheRendererRefuses) {
  const ScratchDir dir("settings_render");
  const std::string f = (dir / "e.yaml").string();
  for (const auto& [yaml, key] : std::vector<std::pair<std::string, std::string>>{
           {"{fps: 1000}", "render.fps"},
           {"{width: 641}", "render.width"},
           {"{height: 8}", "render.height"},
           {"{msaa: 5}", "render.msaa"},
           {"{crf: 52}", "render.crf"},
           {"{preset: quick}", "render.preset"},
           {"{camera: side}", "render.camera"},
           {"{slowmo: 0}", "render.slowmo"}}) {
    const std::string err = loadError(dir, std::string(kBase) + "render: " + yaml + "\n");
    EXPECT_EQ(err.rfind(f + ":4:", 0), 0u) << yaml << " -> " << err;
    EXPECT_NE(err.find(key + ": "), std::string::npos) << err;
  }
  // What the loader accepts, the renderer's check (the same declarations) accepts.
  std::ofstream(f) << kBase << "render: {fps: 240, width: 8192, height: 16, msaa: 4, crf: 51, preset: placebo}\n";
  const RenderSettings s = loadExperiment(f).cases.at(0).render;
  EXPECT_NO_THROW(settings::validateFields(s, "render."));
}

// The declared ranges also check a struct built in code (robot_params.cc's validate()).
TEST(DeclaredLimits, ValidateUsesTheDeclarations) {
  RobotParams p;
  p.tail = {paperTailLink(1)};
  EXPECT_NO_THROW(validate(p));
  p.quadruped.l_F_m = 0;
  try {
    validate(p);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "quadruped.l_F_m must be > 0, got 0");
  }
}

TEST(Schema, DescribesEveryDeclaredSection) {
  const json s = experimentSchema();
  const json& exp = s["oneOf"][0]["properties"];
  EXPECT_EQ(exp["render"]["anyOf"][1]["properties"]["fps"]["anyOf"][0]["maximum"], kRenderMaxFps);
  EXPECT_EQ(exp["mujoco"]["properties"]["condim"]["anyOf"][0]["enum"], json({1, 3, 4, 6}));
  EXPECT_EQ(exp["analytic"]["properties"]["solver"]["anyOf"][0]["enum"], json({"adaptive", "fixed"}));
  EXPECT_FALSE(exp["analytic"]["properties"].contains("max_steps"));  // internal, not a YAML key
  const std::string md = settingsMarkdown();
  EXPECT_NE(md.find("| `fps` | integer, in 1..240 | 30 |"), std::string::npos) << md;
}
