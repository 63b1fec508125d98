// `tailsim optimize` as a module loaded at run time (dlopen by src/app/main.cc): pagmo2 (with TBB and
// Boost.Serialization) costs ~4,000 page faults and ~75 ms of static initialisation per process, which
// every `tailsim run` would pay if the program linked it (issue 13: start fast).
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "design/optimize_experiment.h"
#include "experiments/experiment_loader.h"

namespace {
void copyMessage(const char* what, char* err, size_t err_len) {
  if (!err || err_len == 0) return;
  std::strncpy(err, what, err_len - 1);
  err[err_len - 1] = '\0';
}
}  // namespace

// Returns the process exit code: 0 limits kept, 3 a limit violated on the re-run; -1 a ConfigError,
// -2 another error (message in err).
extern "C" __attribute__((visibility("default"))) int tailsim_optimize_main(const char* exp_path, const char* out_dir,
                                                                           int quiet, char* err, size_t err_len) {
  using namespace tailsim;
  try {
    const OptimizeSpec spec = loadOptimizeSpec(exp_path);  // all errors before any work
    const OptimizeReport r = runOptimize(spec, out_dir, quiet == 0);
    const std::string mujoco =
        spec.mujoco_check ? (r.mujoco.ok ? std::to_string(r.mujoco.phi_net_deg) + " deg" : std::string("failed")) : "not run";
    std::printf("%s: %s %s = %.6g, phi_net %.4f deg (analytic re-run), MuJoCo %s; limits %s; "
                "%zu seeds spread %.3g %%; %ld evaluations, %.2f s wall\n",
                spec.name.c_str(), familyName(spec.problem.space.family), objectiveName(spec.problem.objective),
                r.per_seed[r.best_seed_index].best.objective, r.analytic.phi_net_deg, mujoco.c_str(),
                r.limits_analytic.ok ? "kept" : "VIOLATED", r.per_seed.size(), 100.0 * r.spread, r.evaluations, r.wall_s);
    for (const std::string& f : r.files) std::printf("%s/%s\n", out_dir, f.c_str());
    std::fflush(stdout);
    return r.limits_analytic.ok ? 0 : 3;
  } catch (const ConfigError& e) {
    copyMessage(e.what(), err, err_len);
    return -1;
  } catch (const std::exception& e) {
    copyMessage(e.what(), err, err_len);
    return -2;
  }
}
