// `tailsim run EXPERIMENT.yaml --out DIR`: run an experiment or a suite, then print a table per case.
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "app/commands.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/sharding.h"
#include "experiments/robot_model_cases.h"
#include "plotting/report.h"
#include "plotting/result_folder.h"
#include "plotting/result_page.h"
#include "common/work_limits.h"

namespace tailsim {
namespace fs = std::filesystem;

namespace {

// The quantity of a pose case (kind: pose has no motion, so no phi_net): the tail moment M_zT, its
// tangential and centripetal parts over I_zz when the CSV has them, and the friction moment arm
// L_F, from the first row of the model's CSV. Empty if the CSV cannot be read.
std::string poseQuantity(const ExperimentResults* r, const std::string& case_name, const std::string& model) {
  if (!r) return {};
  for (const CaseRecord& c : r->cases) {
    if (c.name != case_name) continue;
    try {
      const TimeSeries s = r->series(c, model);
      if (s.numRows() == 0) return {};
      auto at = [&](const char* col) { return s.has(col) ? s.values(col)[0] : std::nan(""); };
      char b[200];
      std::string out;
      if (s.has("MzT_Nm")) std::snprintf(b, sizeof b, "M_zT %+.4f N m", at("MzT_Nm")), out += b;
      if (s.has("MzT_tan_over_Izz_radps2") && s.has("MzT_cen_over_Izz_radps2"))
        std::snprintf(b, sizeof b, " (tan/I_zz %+.3f, cen/I_zz %+.3f rad/s^2)", at("MzT_tan_over_Izz_radps2"),
                      at("MzT_cen_over_Izz_radps2")),
            out += b;
      if (s.has("LF_m")) std::snprintf(b, sizeof b, "%sL_F %.1f mm", out.empty() ? "" : ", ", 1e3 * at("LF_m")), out += b;
      return out;
    } catch (const std::exception&) {
      return {};
    }
  }
  return {};
}

// One experiment's summary.json read back: its cases by name (entries of `summary`).
struct CaseSummaries {
  nlohmann::json summary;
  std::map<std::string, const nlohmann::json*> by_name;
};
void readCaseSummaries(const fs::path& dir, CaseSummaries& out) {
  std::ifstream in(dir / "summary.json");
  out.summary = nlohmann::json::parse(in, nullptr, false);
  const nlohmann::json& s = out.summary;
  if (!s.is_discarded() && s.contains("cases") && s["cases"].is_array())
    for (const nlohmann::json& c : s["cases"])
      if (c.is_object() && c.contains("name") && c["name"].is_string()) out.by_name[c["name"].get<std::string>()] = &c;
}

// run --quiet: one line per failed model run, "experiment/case: model: FAILED (why)".
void printFailures(const Experiment& e, const std::map<std::string, const nlohmann::json*>& by_name) {
  for (const ExperimentCase& c : e.cases) {
    const auto it = by_name.find(c.name);
    if (it == by_name.end() || !it->second->contains("runs") || !(*it->second)["runs"].is_object()) continue;
    for (const auto& [model, r] : (*it->second)["runs"].items())
      if (r.is_object() && !r.value("ok", false))
        std::printf("%s/%s: %s: FAILED (%s)\n", e.name.c_str(), c.name.c_str(), model.c_str(),
                    r.value("error", std::string()).c_str());
  }
}

// The experiment's warnings, one per model and shape (the text with its numbers blanked), with the
// number of runs that gave it, in order of first appearance.
struct SharedWarnings {
  struct Shared {
    std::string model, text, first_case;
    int runs = 0;
  };
  std::vector<Shared> warnings;
  std::map<std::pair<std::string, std::string>, size_t> by_shape;
  int runsOf(const std::string& model, const std::string& text) const {
    return warnings[by_shape.at({model, warningShape(text)})].runs;
  }
};
SharedWarnings collectWarnings(const Experiment& e, const std::map<std::string, const nlohmann::json*>& by_name) {
  SharedWarnings sw;
  std::vector<SharedWarnings::Shared>& warnings = sw.warnings;
  std::map<std::pair<std::string, std::string>, size_t>& by_shape = sw.by_shape;
  for (const ExperimentCase& c : e.cases) {
    const auto it = by_name.find(c.name);
    if (it == by_name.end() || !it->second->contains("runs") || !(*it->second)["runs"].is_object()) continue;
    for (const auto& [model, r] : (*it->second)["runs"].items())
      if (r.contains("warnings") && r["warnings"].is_array())
        for (const auto& w : r["warnings"]) {
          if (!w.is_string()) continue;
          const auto key = std::make_pair(model, warningShape(w.get<std::string>()));
          const auto [slot, added] = by_shape.emplace(key, warnings.size());
          if (added) warnings.push_back({model, w.get<std::string>(), c.name});
          ++warnings[slot->second].runs;
        }
  }
  return sw;
}

// Instead of the table (too many cases): the case count and the runs with warnings.
void printCaseCount(const Experiment& e, const fs::path& dir, const std::map<std::string, const nlohmann::json*>& by_name) {
  int warned = 0;  // runs whose result carries warnings (e.g. still moving at the end)
  for (const auto& [name, j] : by_name)
    if (j->contains("runs") && (*j)["runs"].is_object())
      for (const auto& [model, r] : (*j)["runs"].items())
        if (r.contains("warnings") && r["warnings"].is_array() && !r["warnings"].empty()) ++warned;
  std::printf("  %zu cases (see %s/summary.json)", e.cases.size(), dir.c_str());
  if (warned > 0) std::printf(", %d model runs with warnings", warned);
  std::printf("\n");
}

// One table row per case: each model's phi_net (a simulation) or the pose's quantity, its verdict,
// and the warnings only this run gave.
void printCaseRows(const Experiment& e, const std::map<std::string, const nlohmann::json*>& by_name, bool pose,
                   const std::optional<ExperimentResults>& pose_results, const SharedWarnings& sw) {
  for (const ExperimentCase& c : e.cases) {
    std::printf("  %-40s", c.name.c_str());
    const auto it = by_name.find(c.name);
    if (it == by_name.end()) { std::printf(" (not run)\n"); continue; }
    const nlohmann::json& j = *it->second;
    if (!j.contains("runs") || !j["runs"].is_object()) { std::printf(" (unreadable)\n"); continue; }
    for (const auto& [model, r] : j["runs"].items()) {
      if (!r.value("ok", false)) std::printf(" %s: FAILED (%s)", model.c_str(), r.value("error", std::string()).c_str());
      else if (pose) {
        const std::string q = poseQuantity(pose_results ? &*pose_results : nullptr, c.name, model);
        std::printf(" %s: %s", model.c_str(), q.empty() ? "ok" : q.c_str());
      } else if (r["phi_net_deg"].is_number())
        std::printf(" %s: phi_net %s deg (%.2f ms)", model.c_str(), readRunRecord(r).phiText().c_str(),
                    1e3 * r.value("wall_time_s", 0.0));
      else std::printf(" %s: ok", model.c_str());
    }
    std::printf("\n");
    if (j.contains("verdict") && j["verdict"].is_string())
      std::printf("    verdict: %s\n", j["verdict"].get<std::string>().c_str());
    for (const auto& [model, r] : j["runs"].items())
      if (r.contains("warnings") && r["warnings"].is_array())
        for (const auto& w : r["warnings"])
          if (w.is_string() && sw.runsOf(model, w.get<std::string>()) == 1)
            std::printf("    warning (%s): %s\n", model.c_str(), w.get<std::string>().c_str());
  }
}

// A short table per case and model, read back from the result folder's summary.json (its entries
// name each case's folder: "dir"): phi_net of a simulation, the pose's own quantity of a pose
// study. A warning that differs between runs only in its numbers is printed once, with the number
// of runs (each run keeps its own in results.csv and summary.json). failures_only (run --quiet):
// the failed model runs only.
void printCases(const std::vector<Experiment>& suite, const std::string& out, bool is_suite, bool failures_only) {
  for (const Experiment& e : suite) {
    const fs::path dir = is_suite ? fs::path(out) / e.name : fs::path(out);
    CaseSummaries cs;
    readCaseSummaries(dir, cs);
    if (failures_only) {
      printFailures(e, cs.by_name);
      continue;
    }
    std::printf("%s -> %s\n", e.name.c_str(), dir.c_str());
    const bool pose = !cs.summary.is_discarded() && cs.summary.value("kind", std::string()) == "pose";
    std::optional<ExperimentResults> pose_results;
    if (pose) try {
        pose_results = loadResults(dir.string());
      } catch (const std::exception&) {
      }
    const SharedWarnings sw = collectWarnings(e, cs.by_name);
    const bool table = e.cases.size() <= 60;  // a longer table scrolls away; summary.json has them all
    if (table) printCaseRows(e, cs.by_name, pose, pose_results, sw);
    else printCaseCount(e, dir, cs.by_name);
    for (const SharedWarnings::Shared& w : sw.warnings)
      if (w.runs > 1 || !table)
        std::printf("  warning (%s), %d run%s (first: %s; each run's numbers in results.csv): %s\n", w.model.c_str(),
                    w.runs, w.runs == 1 ? "" : "s", w.first_case.c_str(), w.text.c_str());
  }
}

struct RunArgs {
  std::string exp_path, out_dir, case_name, shard_text;
  std::vector<std::string> only_models;
  int threads = 0;
  bool no_render = false, fresh = false, quiet = false, plots = false, allow_other_build = false;
};

int runCommand(const RunArgs& a) {
  ShardSpec shard{};
  if (!a.shard_text.empty()) {
    try {
      shard = parseShard(a.shard_text);
    } catch (const std::invalid_argument& e) {  // a usage error, like any other bad option
      std::fprintf(stderr, "error: %s\n", e.what());
      return kExitUsage;
    }
  }
  std::vector<Experiment> suite = loadExperimentSuite(a.exp_path);  // all errors before any work
  resolveRobotModels(suite);  // robots from their model files, before any case runs
  selectModels(suite, a.only_models, a.exp_path);
  RunOptions o;
  o.out_dir = a.out_dir;
  o.threads = a.threads;
  o.render = !a.no_render;
  o.resume = !a.fresh;
  o.progress = !a.quiet;
  o.only_case = a.case_name;
  o.stop_on_sigint = true;
  o.allow_other_build = a.allow_other_build;
  if (!a.shard_text.empty()) {
    o.shard_index = shard.index;
    o.shard_count = shard.count;
  }
  requireCase(suite, a.exp_path, a.case_name);
  const RunStats s = runSuite(suite, o);
  std::printf("%d cases%s: %d run, %d resumed, %d failed model runs, %.3f s wall\n", s.total,
              a.shard_text.empty() ? "" : (" in shard " + a.shard_text).c_str(), s.ran, s.resumed, s.failed,
              s.wall_time_s);
  if (s.interrupted) {
    std::fflush(stdout);
    std::fprintf(stderr, "interrupted: %d of %d cases saved in %s; run the same command again to resume\n",
                 s.ran + s.resumed, s.total, a.out_dir.c_str());
    // 128 + the signal, as a shell reports a process it ended (SIGINT 130, SIGTERM 143, SIGHUP 129).
    return s.stop_signal > 0 ? 128 + s.stop_signal : kExitInterrupted;
  }
  // --quiet: the failed runs and the line above only
  if (a.shard_text.empty()) printCases(suite, a.out_dir, suite.size() > 1, a.quiet);  // a shard's table is mostly "not run"
  if (a.plots) {
    if (!a.quiet) printSeriesNotes(a.out_dir);
    const std::string report_path = writeReport(a.out_dir);
    if (!a.quiet) std::printf("report: %s\n", report_path.c_str());
    const std::string page_path = writeResultPage(a.out_dir);
    if (!a.quiet) std::printf("page: %s\n", page_path.c_str());
  }
  return s.failed ? kExitRunsFailed : kExitOk;
}

}  // namespace

void addRunCommand(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<RunArgs>();
  auto* run = app.add_subcommand("run", "run an experiment (or a suite such as configs/paper/all.yaml)");
  run->add_option("experiment", a->exp_path, "experiment YAML")->required()->check(CLI::ExistingFile);
  run->add_option("--out", a->out_dir, "result folder")->required()->check(nonEmptyPath());
  run->add_option("--threads", a->threads, "worker threads (default 0: all cores; at most 1024)")
      ->check(CLI::Range(0, limits::kMaxThreads));
  run->add_option("--case", a->case_name, "run only this case");
  run->add_flag("--no-render", a->no_render, "skip the render section");
  run->add_flag("--fresh", a->fresh, "start from an empty result folder (deletes tailsim's results in --out, also another experiment's)");
  run->add_flag("--allow-other-build", a->allow_other_build,
                "resume cases computed by another tailsim version or commit (warned, recorded in summary.json) instead of refusing them");
  run->add_flag("--quiet", a->quiet, "print only errors and the final line (cases run, resumed, failed)");
  run->add_flag("--plot", a->plots, "draw the plots and the report afterwards");
  run->add_option("--shard", a->shard_text,
                  "K/N: run only shard K of N (cases balanced by expected cost; join the shards with tailsim merge)");
  run->add_option("--models", a->only_models, "run only these models (analytic, perfoot, mujoco) of each case")
      ->check(CLI::IsMember(modelNames()));
  run->callback([a, &exit_code] { exit_code = runCommand(*a); });
}

}  // namespace tailsim
