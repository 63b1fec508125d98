// `tailsim optimize` as a module loaded at run time (dlopen by src/app/main.cc): pagmo2 (with TBB and
// Boost.Serialization) costs ~4,000 page faults and ~75 ms of static initialisation per process, which
// every `tailsim run` would pay if the program linked it (so every other command starts fast).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "design/maneuver.h"
#include "design/optimize_experiment.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"

namespace {
void copyMessage(const char* what, char* err, size_t err_len) {
  if (!err || err_len == 0) return;
  std::strncpy(err, what, err_len - 1);
  err[err_len - 1] = '\0';
}

// Runs an entry point's body; an exception becomes -1 (ConfigError) or -2 with its message in err.
template <class Body>
int guarded(char* err, size_t err_len, const Body& body) {
  try {
    return body();
  } catch (const tailsim::ConfigError& e) {
    copyMessage(e.what(), err, err_len);
    return -1;
  } catch (const std::exception& e) {
    copyMessage(e.what(), err, err_len);
    return -2;
  }
}
}  // namespace

// Returns the process exit code: 0 limits kept, 3 a limit violated on the re-run; -1 a ConfigError,
// -2 another error (message in err).
extern "C" __attribute__((visibility("default"))) int tailsim_optimize_main(const char* exp_path, const char* out_dir,
                                                                           int quiet, char* err, size_t err_len) {
  using namespace tailsim;
  return guarded(err, err_len, [&] {
    const OptimizeSpec spec = loadOptimizeSpec(exp_path);  // all errors before any work
    const FolderLock lock(out_dir);
    refuseRunResults(out_dir, "optimize");
    claimDesignFolder(out_dir, {"summary.json", "best.yaml", "best_analytic.csv", "best_perfoot.csv", "best_mujoco.csv",
                                "best_trajectory.csv", "history.csv", "pareto.csv", "plots/history.png",
                                "plots/history.svg", "plots/history.gp", "plots/pareto.png", "plots/pareto.svg",
                                "plots/pareto.gp"});
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
    if (!r.best_yaml_error.empty())
      std::fprintf(stderr, "warning: %s/best.yaml does not load back (%s): the re-runs used the search's trajectory\n",
                   out_dir, r.best_yaml_error.c_str());
    return r.limits_analytic.ok ? 0 : 3;
  });
}

// `tailsim maneuver`: the same module (it needs the design layer, not pagmo, but one module keeps the
// program's start-up free of both). Returns 0, or 3 when a run failed or missed the heading; -1 a
// ConfigError, -2 another error (message in err).
extern "C" __attribute__((visibility("default"))) int tailsim_maneuver_main(const char* exp_path, const char* out_dir,
                                                                           int quiet, int video, char* err, size_t err_len) {
  using namespace tailsim;
  return guarded(err, err_len, [&] {
    const ManeuverSpec spec = loadManeuverSpec(exp_path);  // all errors before any work
    const FolderLock lock(out_dir);
    refuseRunResults(out_dir, "maneuver");
    claimDesignFolder(out_dir, {"summary.json", "maneuver.csv", "strokes.csv", "yaw_map.csv", "plots/heading.png",
                                "plots/heading.svg", "plots/heading.gp"});
    const ManeuverReport r = runManeuver(spec, out_dir, video != 0, quiet == 0);
    bool all_ok = true;
    std::printf("%s: target %.4g deg, tolerance %.4g deg; analytic cycle %+.4f deg (stroke %+.4f, return %+.4f)\n",
                spec.name.c_str(), spec.settings.heading_deg, spec.settings.tolerance_deg, r.full_cycle.total() * 180 / M_PI,
                r.full_cycle.fast_rad * 180 / M_PI, r.full_cycle.back_rad * 180 / M_PI);
    for (const ManeuverRun& m : r.runs) {
      const bool reached = m.ok && std::abs(m.final_error_rad) <= spec.settings.tolerance();
      all_ok = all_ok && m.ok && (reached || m.label == "mujoco_open_loop");
      std::printf("  %-20s %s strokes %zu, final error %+.4f deg, overshoot %.4f deg, within tolerance from %s\n",
                  m.label.c_str(), m.ok ? "ok    " : "FAILED", m.strokes.size(), m.final_error_rad * 180 / M_PI,
                  m.overshoot_rad * 180 / M_PI, m.t_within_s >= 0 ? (std::to_string(m.t_within_s) + " s").c_str() : "never");
      if (!m.ok) std::printf("    error: %s\n", m.error.c_str());
    }
    for (const std::string& f : r.files) std::printf("%s/%s\n", out_dir, f.c_str());
    std::fflush(stdout);
    return all_ok ? 0 : 3;
  });
}
