// `tailsim optimize` as a module loaded at run time (dlopen by src/app/main.cc): pagmo2 (with TBB and
// Boost.Serialization) costs ~4,000 page faults and ~75 ms of static initialisation per process, which
// every `tailsim run` would pay if the program linked it (so every other command starts fast).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "common/stop_signals.h"
#include "design/maneuver.h"
#include "design/optimize_experiment.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "common/units.h"

namespace {
// The files a design folder holds: its inputs (replaced by the next run's), and its results (the
// previous run's removed before a new one starts, so a stopped or failed run never leaves an old
// summary beside new inputs, nor an old pareto.csv beside a run without one).
const std::vector<std::string> kOptimizeInputs = {"optimize.yaml", "base.yaml", "robot.yaml"};
const std::vector<std::string> kOptimizeOutputs = {
    "summary.json",     "best.yaml",         "best_analytic.csv", "best_perfoot.csv",  "best_mujoco.csv",
    "best_trajectory.csv", "history.csv",    "pareto.csv",        "plots/history.png", "plots/history.svg",
    "plots/history.gp", "plots/pareto.png",  "plots/pareto.svg",  "plots/pareto.gp"};
const std::vector<std::string> kManeuverInputs = {"maneuver.yaml", "base.yaml", "robot.yaml", "stroke.yaml",
                                                  "stroke_robot.yaml"};
const std::vector<std::string> kManeuverOutputs = {"summary.json",      "maneuver.csv",      "strokes.csv",
                                                   "yaw_map.csv",       "plots/heading.png", "plots/heading.svg",
                                                   "plots/heading.gp"};

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

// Returns the process exit code: 0 limits kept, 3 a limit violated on the re-run or no stroke within
// the limits turns the body (the message says what would); -1 a ConfigError,
// -2 another error (message in err).
extern "C" __attribute__((visibility("default"))) int tailsim_optimize_main(const char* exp_path, const char* out_dir,
                                                                           int quiet, char* err, size_t err_len) {
  using namespace tailsim;
  return guarded(err, err_len, [&] {
    const OptimizeSpec spec = loadOptimizeSpec(exp_path);  // all errors before any work
    const FolderLock lock(out_dir);
    refuseRunResults(out_dir, "optimize");
    claimDesignFolder(out_dir, kOptimizeInputs);
    claimDesignFolder(out_dir, kOptimizeOutputs);
    removeDesignOutputs(out_dir, kOptimizeOutputs);  // an old summary never sits beside new inputs
    StopSignals signals;  // before the search's threads start: they inherit the mask
    const OptimizeReport r = runOptimize(spec, out_dir, quiet == 0, [&signals] { return signals.pending(); });
    if (r.per_seed.empty()) {
      std::fprintf(stderr, "optimize %s: stopped by %s before a seed finished: nothing written but the inputs; run it "
                   "again\n", spec.name.c_str(), StopSignals::name(r.stop_signal));
      return 128 + r.stop_signal;
    }
    // One line in signed degrees: the search's optimum, the three models' re-runs, the limits.
    const StrokeEvaluation& b = r.per_seed[r.best_seed_index].best;
    const StrokeLimits& L = spec.problem.space.limits;
    auto deg = [](const RunSummary& m, bool run) {
      char v[48];
      if (!run) return std::string("not run");
      if (!m.ok) return std::string("failed");
      std::snprintf(v, sizeof v, "%+.4f deg", m.phi_net_deg);
      return std::string(v);
    };
    char tau_lim[32] = "none";
    if (!L.joints.empty()) std::snprintf(tau_lim, sizeof tau_lim, "per joint");
    else if (L.torque_max_Nm > 0) std::snprintf(tau_lim, sizeof tau_lim, "%.4g N m", L.torque_max_Nm);
    char speed_lim[32];
    if (!L.joints.empty()) std::snprintf(speed_lim, sizeof speed_lim, "per joint");
    else std::snprintf(speed_lim, sizeof speed_lim, "%.4g", units::degrees(L.thetadot_max_radps));
    // The limits the optimum uses up, joint by joint (the constraint that binds).
    const std::vector<std::string> binding = bindingLimits(r.limits_analytic.figures, L);
    std::string binds;
    for (std::size_t k = 0; k < binding.size() && k < 3; ++k) binds += (k ? ", " : "") + binding[k];
    if (binding.size() > 3) binds += ", ...";
    if (binds.empty()) binds = "none";
    std::printf("%s: %s, best %s %+.6g %s (phi_net %+.4f deg, %s search%s); re-runs: analytic %s, per-foot %s, "
                "MuJoCo %s; peak joint torque %.4g N m (limit %s), peak joint speed %.4g deg/s (limit %s); limits %s (binding: %s); "
                "%zu seeds, spread %.3g %%; %ld runs, %.2f s wall\n",
                spec.name.c_str(), familyName(spec.problem.space.family), objectiveName(spec.problem.objective),
                signedObjectiveDeg(b.objective, b.phi_net_rad), objectiveUnit(spec.problem.objective),
                units::degrees(b.phi_net_rad), objectiveModelName(spec.problem.search_model),
                r.rerank.empty() ? "" : (", MuJoCo re-rank of " + std::to_string(r.rerank.size()) + " candidates").c_str(),
                deg(r.analytic, true).c_str(), deg(r.perfoot, true).c_str(),
                deg(r.mujoco, spec.mujoco_check).c_str(), r.limits_analytic.figures.peak_torque_Nm, tau_lim,
                units::degrees(r.limits_analytic.figures.peak_speed_radps), speed_lim,
                r.infeasible.infeasible ? "kept, but the turn is below min_turn_deg" : r.limits_analytic.ok ? "kept" : "VIOLATED",
                binds.c_str(),
                r.per_seed.size(), 100.0 * r.spread, r.evaluations, r.wall_s);
    for (const std::string& f : r.files) std::printf("%s/%s\n", out_dir, f.c_str());
    std::fflush(stdout);
    if (!r.best_yaml_error.empty())
      std::fprintf(stderr, "warning: %s/best.yaml does not load back (%s): the re-runs used the search's trajectory\n",
                   out_dir, r.best_yaml_error.c_str());
    if (r.stop_signal) {
      std::fprintf(stderr, "optimize %s: stopped by %s after %zu of %zu seeds: the best of those is written (summary.json "
                   "\"stopped_by\"); run it again for all\n", spec.name.c_str(), StopSignals::name(r.stop_signal),
                   r.per_seed.size(), spec.seeds.size());
      return 128 + r.stop_signal;
    }
    if (r.infeasible.infeasible) {
      std::fprintf(stderr, "error: %s: %s (summary.json \"infeasible\")\n", spec.name.c_str(), r.infeasible.message.c_str());
      return 3;
    }
    if (!r.limits_analytic.ok)
      std::fprintf(stderr, "error: %s: the re-run of the best stroke violates its limits: see summary.json "
                   "resimulated.analytic.violations\n", spec.name.c_str());
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
    claimDesignFolder(out_dir, kManeuverInputs);
    claimDesignFolder(out_dir, kManeuverOutputs);
    removeDesignOutputs(out_dir, kManeuverOutputs);
    StopSignals signals;
    const ManeuverReport r = runManeuver(spec, out_dir, video != 0, quiet == 0, [&signals] { return signals.pending(); });
    if (r.stop_signal) {
      std::fprintf(stderr, "maneuver %s: stopped by %s: nothing written but the inputs (its results are whole or not "
                   "at all); run it again\n", spec.name.c_str(), StopSignals::name(r.stop_signal));
      return 128 + r.stop_signal;
    }
    bool all_ok = true;
    std::vector<std::string> reasons;  // why the exit is not 0, one line each
    std::printf("%s: target %.4g deg, tolerance %.4g deg, min_scale %.4g (%s); analytic cycle %+.4f deg (stroke %+.4f, return %+.4f)\n",
                spec.name.c_str(), spec.settings.heading_deg, spec.settings.tolerance_deg, r.min_scale,
                spec.min_scale_given ? "given" : "derived from the tolerance", units::degrees(r.full_cycle.total()),
                units::degrees(r.full_cycle.fast_rad), units::degrees(r.full_cycle.back_rad));
    for (const ManeuverRun& m : r.runs) {
      const bool reached = m.ok && std::abs(m.final_error_rad) <= spec.settings.tolerance();
      const bool counts = m.label != "mujoco_open_loop";  // the open-loop MuJoCo run may miss: that is what is measured
      const bool run_ok = m.ok && (reached || !counts);
      all_ok = all_ok && run_ok;
      std::printf("  %-20s %s strokes %zu, final error %+.4f deg, overshoot %.4f deg, within tolerance from %s\n",
                  m.label.c_str(), m.ok ? (run_ok ? "ok    " : "MISSED") : "FAILED", m.strokes.size(),
                  units::degrees(m.final_error_rad), units::degrees(m.overshoot_rad),
                  m.t_within_s >= 0 ? (std::to_string(m.t_within_s) + " s").c_str() : "never");
      if (!m.ok) {
        std::printf("    error: %s\n", m.error.c_str());
        reasons.push_back(m.label + " failed: " + m.error);
      } else if (!run_ok) {
        char b[256];
        std::snprintf(b, sizeof b, "%s ended %+.4f deg from the target, outside the tolerance %.4g deg", m.label.c_str(),
                      units::degrees(m.final_error_rad), spec.settings.tolerance_deg);
        reasons.push_back(b);
      }
      for (const std::string& w : m.warnings) std::printf("    warning: %s\n", w.c_str());
    }
    for (const std::string& f : r.files) std::printf("%s/%s\n", out_dir, f.c_str());
    std::fflush(stdout);
    for (const std::string& why : reasons) std::fprintf(stderr, "error: %s: %s\n", spec.name.c_str(), why.c_str());
    return all_ok ? 0 : 3;
  });
}
