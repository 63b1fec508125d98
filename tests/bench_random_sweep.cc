// The random analytic sweep as a command: work per case (solver steps, deterministic) and wall
// time, the median and the worst cases. Usage: bench_random_sweep [N=5000] [SEED=20261123]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "random_cases.h"

using namespace tailsim;
using namespace tailsim::testing;

int main(int argc, char** argv) {
  const int N = argc > 1 ? std::atoi(argv[1]) : 5000;
  const unsigned seed = argc > 2 ? static_cast<unsigned>(std::atoll(argv[2])) : 20261123u;
  RandomCases gen(seed);
  struct Row { int k; long steps; double wall; int events; bool ok; std::string what; };
  std::vector<Row> rows;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < N; ++k) {
    const RandomCase c = gen.next();
    const RunResult r = simulateAnalytic(c.robot, c.trajectory, c.settings, c.effects, {});
    rows.push_back({k, r.summary.solver_steps, r.summary.wall_time_s, r.summary.stick_slip_events, r.summary.ok, describe(c)});
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<long> steps;
  int failed = 0;
  for (const Row& r : rows)
    if (r.ok) steps.push_back(r.steps);
    else ++failed;
  std::sort(steps.begin(), steps.end());
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.steps > b.steps; });
  std::printf("cases %d (seed %u): %d failed (tipping), sweep wall %.3f s\n", N, seed, failed, wall);
  std::printf("solver steps: median %ld, worst %ld (%.1fx median)\n", steps[steps.size() / 2], steps.back(),
              double(steps.back()) / steps[steps.size() / 2]);
  for (int i = 0; i < 5 && i < static_cast<int>(rows.size()); ++i)
    std::printf("  case %d: %ld steps, %d events, %.2f ms: %s\n", rows[i].k, rows[i].steps, rows[i].events,
                1e3 * rows[i].wall, rows[i].what.c_str());
  return 0;
}
