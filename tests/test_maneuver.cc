// Maneuvers to a heading (src/design/maneuver.h, controllers/heading_controller.h):
// the open-loop plan lands on the target in the model it was planned on, the slow return alone
// hardly turns the body, +-90 deg are mirror images, the closed loop reaches 90 deg in MuJoCo, and
// bad `maneuver:` settings are refused at file:line:col naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "controllers/heading_controller.h"
#include "design/maneuver.h"
#include "experiments/experiment_loader.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;
const std::string kSourceDir = TAILSIM_SOURCE_DIR;

ManeuverSpec spec90() { return loadManeuverSpec(kSourceDir + "/configs/design/maneuver_90.yaml"); }

TEST(HeadingController, PicksFullScaledAndReverseCycles) {
  ManeuverSettings s;  // target 90 deg, tolerance 1 deg
  YawMap map;
  map.scale = {0.1, 0.5, 1.0};
  map.yaw_rad = {-1 * kDeg, -5 * kDeg, -10 * kDeg};  // a positive stroke turns the body clockwise
  const HeadingController c(s, map);
  auto far = c.next(0.0);  // 90 deg to go: a full cycle, direction -1 (turns +10 deg)
  ASSERT_TRUE(far);
  EXPECT_EQ(far->scale, 1.0);
  EXPECT_EQ(far->direction, -1);
  auto near = c.next(87.0 * kDeg);  // 3 deg to go: between 0.1 (1 deg) and 0.5 (5 deg): 0.1 + 2/4 * 0.4
  ASSERT_TRUE(near);
  EXPECT_NEAR(near->scale, 0.3, 1e-12);
  EXPECT_EQ(near->direction, -1);
  auto over = c.next(93.0 * kDeg);  // overshoot: the other way
  ASSERT_TRUE(over);
  EXPECT_EQ(over->direction, 1);
  EXPECT_FALSE(c.next(89.5 * kDeg));  // within tolerance
}

TEST(Maneuver, SlowReturnAloneHardlyTurns) {
  const ManeuverSpec s = spec90();
  const CycleYaw y = analyticCycleYaw(s.base, s.settings, 1.0);
  EXPECT_GT(std::abs(y.fast_rad), 2.0 * kDeg);            // the fast stroke turns the body
  EXPECT_LT(std::abs(y.back_rad), 0.02 * std::abs(y.fast_rad));  // the slow return stays (nearly) stuck
  EXPECT_TRUE(y.at_rest);
}

TEST(Maneuver, OpenLoopPlanLandsOnTargetInTheAnalyticModel) {
  const ManeuverSpec s = spec90();
  const YawMap map = analyticYawMap(s.base, s.settings);
  const std::vector<StrokeCommand> plan = planOpenLoop(s.base, s.settings, map);
  ASSERT_GE(plan.size(), 2u);
  const ManeuverRun r = runAnalyticOpenLoop(s.base, s.settings, plan);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LE(std::abs(r.final_error_rad), s.settings.tolerance());
  // Independently: the chained series ends at the sum of the cycles' yaws, each simulated alone.
  double sum = 0;
  for (const StrokeCommand& c : plan) sum += c.direction * analyticCycleYaw(s.base, s.settings, c.scale).total();
  EXPECT_NEAR(s.settings.heading() - r.final_error_rad, sum, 1e-9);
  EXPECT_EQ(r.strokes.size(), plan.size());
  EXPECT_GE(r.t_within_s, 0.0);
}

// A heading a hair past whole cycles takes no extra cycle: the smallest cycle would overshoot by far
// more than the hair (an outside review: 10 deg by cycles of 1.995 ended at 10.977, not 9.975).
TEST(Maneuver, ARemainderSmallerThanTheSmallestCycleAddsNone) {
  ManeuverSpec s = spec90();
  const YawMap map = analyticYawMap(s.base, s.settings);
  s.settings.heading_deg = 3 * std::abs(map.full()) / kDeg + 0.02;
  const std::vector<StrokeCommand> plan = planOpenLoop(s.base, s.settings, map);
  ASSERT_EQ(plan.size(), 3u);
  const ManeuverRun r = runAnalyticOpenLoop(s.base, s.settings, plan);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(std::abs(r.final_error_rad), 0.02 * kDeg, 1e-6);
}

TEST(Maneuver, MinusNinetyIsTheMirrorOfPlusNinety) {
  ManeuverSpec s = spec90();
  const YawMap map = analyticYawMap(s.base, s.settings);
  const std::vector<StrokeCommand> plus = planOpenLoop(s.base, s.settings, map);
  const ManeuverRun rp = runAnalyticOpenLoop(s.base, s.settings, plus);
  s.settings.heading_deg = -90;
  const std::vector<StrokeCommand> minus = planOpenLoop(s.base, s.settings, map);
  const ManeuverRun rm = runAnalyticOpenLoop(s.base, s.settings, minus);
  ASSERT_EQ(plus.size(), minus.size());
  for (std::size_t k = 0; k < plus.size(); ++k) {
    EXPECT_DOUBLE_EQ(plus[k].scale, minus[k].scale);
    EXPECT_EQ(plus[k].direction, -minus[k].direction);
  }
  const auto& pp = rp.series.values("phi_deg");
  const auto& pm = rm.series.values("phi_deg");
  ASSERT_EQ(pp.size(), pm.size());
  for (std::size_t k = 0; k < pp.size(); k += 97) EXPECT_NEAR(pp[k], -pm[k], 1e-9) << "row " << k;
  EXPECT_NEAR(rp.final_error_rad, -rm.final_error_rad, 1e-9);
}

TEST(Maneuver, ClosedLoopReachesNinetyDegreesInMujoco) {
  const ManeuverSpec s = spec90();
  const YawMap map = analyticYawMap(s.base, s.settings);
  const ManeuverRun r = runMujocoClosedLoop(s.base, s.settings, map, 30.0);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LE(std::abs(r.final_error_rad), s.settings.tolerance()) << "final error " << r.final_error_rad / kDeg << " deg";
  EXPECT_GE(r.t_within_s, 0.0);
  EXPECT_GE(r.strokes.size(), 2u);
  // Every cycle starts with the tail back at 0 and the heading it measured then.
  for (std::size_t k = 1; k < r.strokes.size(); ++k)
    EXPECT_NEAR(r.strokes[k].heading_before_rad, r.strokes[k - 1].heading_after_rad, 1e-12);
}

class ManeuverFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tailsim_maneuver_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    fs::copy_file(kSourceDir + "/configs/design/base/eq25_n1.yaml", dir_ / "base.yaml", fs::copy_options::overwrite_existing);
    // The base names its robot relative to configs/design/base.
    std::ifstream in(dir_ / "base.yaml");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string from = "../../robots/paper_quadruped.yaml";
    text.replace(text.find(from), from.size(), kSourceDir + "/configs/robots/paper_quadruped.yaml");
    std::ofstream(dir_ / "base.yaml") << text;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string error(const std::string& maneuver_section) {
    const fs::path p = dir_ / "m.yaml";
    std::ofstream(p) << "name: m\nkind: maneuver\nbase: base.yaml\nmaneuver:\n" << maneuver_section;
    try {
      loadManeuverSpec(p.string());
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(ManeuverFileTest, GoodFileLoads) { EXPECT_EQ(error("  heading_deg: 45\n"), ""); }

TEST_F(ManeuverFileTest, BadSettingsNameFileLineColumnAndKey) {
  const std::string f = (dir_ / "m.yaml").string();
  std::string e = error("  heading_deg: 90\n  tolerance_deg: -1\n");
  EXPECT_EQ(e.rfind(f + ":6:18: maneuver.tolerance_deg: must lie in (0, 45]", 0), 0u) << e;
  e = error("  heading: 90\n");
  EXPECT_EQ(e.rfind(f + ":5:3: maneuver.heading: unknown key", 0), 0u) << e;
  e = error("  max_strokes: 2.5\n");
  EXPECT_EQ(e.rfind(f + ":5:16: maneuver.max_strokes:", 0), 0u) << e;
  e = error("  stroke_w_ss: 1\n");
  EXPECT_EQ(e.rfind(f + ":5:16: maneuver.stroke_w_ss: must lie in (0, 1)", 0), 0u) << e;
  e = error("  mujoco: maybe\n");
  EXPECT_EQ(e.rfind(f + ":5:11: maneuver.mujoco:", 0), 0u) << e;
}

// Every kind: maneuver file shipped in configs/design loads.
TEST(ShippedConfigs, ManeuverFilesLoad) {
  int loaded = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(kSourceDir) / "configs/design")) {
    if (entry.path().filename().string().rfind("maneuver_", 0) != 0) continue;
    try {
      const ManeuverSpec s = loadManeuverSpec(entry.path().string());
      EXPECT_EQ(s.base.robot.numLinks(), 1);
    } catch (const ConfigError& e) {
      ADD_FAILURE() << e.what();
    }
    ++loaded;
  }
  EXPECT_GE(loaded, 3);
}

}  // namespace
}  // namespace tailsim
