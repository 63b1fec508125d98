// The speed of the MuJoCo loop, measured in one run: steps per second of tailsim's MuJoCo loop (controller,
// friction update, warning checks and 1 ms logging included) against `mujoco-testspeed` on the
// same generated XML and timestep. testspeed runs the model with ctrl = 0 noise, i.e. the tail
// held still, so the loop is timed on the same scene: the tail held at theta_0 for 4 s.
//   build/tests/bench_mujoco_testspeed
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "../tests/analytic_test_util.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;

static double testspeed(const std::string& xml, int steps) {
  const std::string cmd = "mujoco-testspeed " + xml + " " + std::to_string(steps) + " 1 0 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  if (!p) return 0;
  char line[512];
  double sps = 0;
  while (std::fgets(line, sizeof line, p.get()))
    if (std::sscanf(line, " Steps per second : %lf", &sps) == 1) break;
  return sps;
}

int main() {
  const int steps = 20000;
  std::printf("| n | tailsim loop [steps/s] | mujoco-testspeed [steps/s] | ratio |\n|---|---|---|---|\n");
  for (int n : {1, 6}) {
    const RobotParams robot = testing::paperRobot(n);
    const MujocoSettings ms;
    const std::string xml = (std::filesystem::temp_directory_path() / ("tailsim_ts_n" + std::to_string(n) + ".xml")).string();
    std::ofstream(xml) << generateMjcf(robot, ms, Effects{});
    double best_loop = 0, best_ts = 0;
    for (int rep = 0; rep < 3; ++rep) {  // interleaved, best of 3 each (shared machine)
      OutputSettings o;
      o.duration_s = steps * ms.timestep_s;
      const RunResult r = simulateMujoco(robot, testing::sameMove(n, 0, 0, 0.25, 0.25), ms, Effects{}, o);
      if (!r.summary.ok) {
        std::fprintf(stderr, "run failed: %s\n", r.summary.error.c_str());
        return 1;
      }
      best_loop = std::max(best_loop, r.summary.solver_steps / r.summary.wall_time_s);
      best_ts = std::max(best_ts, testspeed(xml, steps));
    }
    std::printf("| %d | %.0f | %.0f | %.3f |\n", n, best_loop, best_ts, best_ts > 0 ? best_loop / best_ts : 0.0);
    std::filesystem::remove(xml);
  }
  return 0;
}
