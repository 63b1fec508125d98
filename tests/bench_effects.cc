// Simulate only what a scene calls for, measured in one run: wall time of the full
// scene against reduced scenes of the same case, for both models.
//   build/tests/bench_effects
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <unistd.h>

#include "analytic_test_util.h"
#include "experiments/experiment_runner.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;
using namespace tailsim::testing;

// Best of `reps` wall times [s] (shared machine: the minimum is the least disturbed run).
static double best(const std::function<void()>& f, int reps) {
  double b = 1e30;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    b = std::min(b, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return b;
}

int main() {
  const RobotParams robot = paperRobot(1, 0.1405);
  const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);
  Effects full;
  Effects floating;  // frictionless, weightless, no ground: free-floating in the plane
  floating.friction = FrictionLaw::kNone;
  floating.gravity = false;
  floating.ground_contact = false;
  Effects lean = full;
  lean.load_decomposition = false;

  std::printf("| scene | model | wall [ms] | vs full |\n|---|---|---|---|\n");
  const double a_full = best([&] { simulateAnalytic(robot, tr, {}, full, {}); }, 50);
  const double a_lean = best([&] { simulateAnalytic(robot, tr, {}, lean, {}); }, 50);
  const double a_float = best([&] { simulateAnalytic(robot, tr, {}, floating, {}); }, 50);
  // Kinematics only: the Fig. 10 L_F map (91 poses), no time integration at all.
  std::vector<std::vector<JointState>> poses;
  std::vector<RobotParams> robots;
  for (int d = 0; d <= 6; ++d)
    for (int th = -90; th <= 90; th += 15) {
      robots.push_back(paperRobot(1, 0.025 * d));
      poses.push_back({JointState{deg(th), 0, 0}});
    }
  const double a_pose = best([&] {
    for (size_t i = 0; i < poses.size(); ++i) evaluatePose(robots[i], poses[i], full);
  }, 50);
  std::printf("| full (stiction, translation, gravity, distributed L_F, load decomposition) | analytic | %.3f | 1.00 |\n", 1e3 * a_full);
  std::printf("| full without load decomposition | analytic | %.3f | %.2f |\n", 1e3 * a_lean, a_lean / a_full);
  std::printf("| frictionless free-floating | analytic | %.3f | %.2f |\n", 1e3 * a_float, a_float / a_full);
  std::printf("| kinematics only: Fig. 10 L_F map, 91 poses | analytic | %.3f | %.2f |\n", 1e3 * a_pose, a_pose / a_full);

  const double m_full = best([&] { simulateMujoco(robot, tr, {}, full, {}); }, 5);
  const double m_float = best([&] { simulateMujoco(robot, tr, {}, floating, {}); }, 5);
  std::printf("| full (contact, friction, gravity) | mujoco | %.3f | 1.00 |\n", 1e3 * m_full);
  std::printf("| frictionless free-floating (no contact, no gravity) | mujoco | %.3f | %.2f |\n", 1e3 * m_float,
              m_float / m_full);

  // A case with a render section, run without rendering (`tailsim run --no-render`) and with it.
  const auto dir = std::filesystem::temp_directory_path() / ("tailsim_bench_effects_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "render.yaml") << "name: render_case\nrobot: " << TAILSIM_SOURCE_DIR
                                     << "/configs/robots/paper_quadruped.yaml\ntail: {links: 1}\n"
                                        "trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n"
                                        "models: [analytic, mujoco]\nrender: {width: 320, height: 240}\n";
  const Experiment e = loadExperiment((dir / "render.yaml").string());
  auto runWith = [&](bool render) {
    RunOptions o;
    o.out_dir = (dir / (render ? "with" : "without")).string();
    o.progress = false;
    o.resume = false;
    o.render = render;
    runExperiment(e, o);
  };
  const double r_without = best([&] { runWith(false); }, 3);
  double r_with = -1;
  try {
    r_with = best([&] { runWith(true); }, 2);
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "render run unavailable here: %s\n", ex.what());
  }
  std::printf("| case with a render section, run rendering it | both + video | %.3f | 1.00 |\n", 1e3 * r_with);
  std::printf("| same case, --no-render (no GL context made) | both | %.3f | %.2f |\n", 1e3 * r_without,
              r_with > 0 ? r_without / r_with : 0.0);
  std::filesystem::remove_all(dir);
  return 0;
}
