// tailsim: how much can a planar robotic tail turn a standing quadruped?
//   tailsim run EXPERIMENT.yaml --out DIR      both models as the experiment lists, results in DIR
//   tailsim plot DIR | tailsim report DIR      figures / Markdown report from saved results
//   tailsim render EXPERIMENT.yaml --out DIR   headless MP4 + PNG of each case
//   tailsim mjcf [EXPERIMENT.yaml | --links N] (--out FILE | --menagerie DIR)
//                                              the MuJoCo model: one file, or robot + scene (mjcf/README.md)
//   tailsim accuracy EXPERIMENT.yaml --out DIR work-precision study of both models
//   tailsim optimize EXPERIMENT.yaml --out DIR best tail stroke (kind: optimize, docs/design-a-tail-stroke.md)
//   tailsim maneuver EXPERIMENT.yaml --out DIR turn to a heading, open- and closed-loop (kind: maneuver)
// Exit codes: see kExitCodes below (also printed by --help).
#include <CLI/CLI.hpp>
#include <dlfcn.h>

#include <algorithm>
#include <set>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "experiments/accuracy_study.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/settings_schema.h"
#include "experiments/render_case.h"
#include "experiments/sharding.h"
#include "mujoco_model/mjcf_generator.h"
#include "plotting/ladder.h"
#include "plotting/accuracy_plot.h"
#include "plotting/figure_sheet.h"
#include "plotting/plots.h"
#include "plotting/report.h"
#include "plotting/result_page.h"
#include "results/atomic_file.h"
#include "results/sha256.h"
#include "results/work_limits.h"
#include "tailsim_version.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

constexpr int kExitOk = 0, kExitError = 1, kExitUsage = 2, kExitRunsFailed = 3, kExitInterrupted = 130;
constexpr const char* kExitCodes =
    "Exit codes:\n"
    "  0    ok\n"
    "  1    error: bad input (named file:line:col) or a failure that stopped the command\n"
    "  2    usage error: unknown subcommand or option, missing or bad argument\n"
    "  3    run: some model runs failed (the rest is saved; see summary.json); optimize: a limit violated on the re-run;\n"
    "       maneuver: a run failed or the closed loop missed the heading\n"
    "  130  run: interrupted by Ctrl-C (SIGINT; finished cases are saved; run again to resume)\n"
    "  143  run: stopped by SIGTERM (a batch system's time limit), likewise\n"
    "  129  run: stopped by SIGHUP (the terminal closed), likewise";

std::string versionString() {
  std::string v = std::string("tailsim ") + kVersion;
  if (*kGitCommit) v += std::string(" (git ") + kGitCommit + ")";
  return v;
}

// `--case NAME` must name a case of the suite: an error listing the available ones otherwise.

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

void printCases(const std::vector<Experiment>& suite, const std::string& out, bool is_suite, bool failures_only) {
  // A short table per case and model, read back from the result folder's summary.json (its
  // entries name each case's folder: "dir"): phi_net of a simulation, the pose's own quantity of
  // a pose study. A warning that differs between runs only in its numbers is printed once, with
  // the number of runs (each run keeps its own in results.csv and summary.json).
  // failures_only (run --quiet): one line per failed model run, "experiment/case: model: FAILED (why)".
  for (const Experiment& e : suite) {
    const fs::path dir = is_suite ? fs::path(out) / e.name : fs::path(out);
    std::ifstream in(dir / "summary.json");
    const nlohmann::json s = nlohmann::json::parse(in, nullptr, false);
    std::map<std::string, const nlohmann::json*> by_name;
    if (!s.is_discarded() && s.contains("cases") && s["cases"].is_array())
      for (const nlohmann::json& c : s["cases"])
        if (c.is_object() && c.contains("name") && c["name"].is_string()) by_name[c["name"].get<std::string>()] = &c;
    if (failures_only) {
      for (const ExperimentCase& c : e.cases) {
        const auto it = by_name.find(c.name);
        if (it == by_name.end() || !it->second->contains("runs") || !(*it->second)["runs"].is_object()) continue;
        for (const auto& [model, r] : (*it->second)["runs"].items())
          if (r.is_object() && !r.value("ok", false))
            std::printf("%s/%s: %s: FAILED (%s)\n", e.name.c_str(), c.name.c_str(), model.c_str(),
                        r.value("error", std::string()).c_str());
      }
      continue;
    }
    std::printf("%s -> %s\n", e.name.c_str(), dir.c_str());
    const bool pose = !s.is_discarded() && s.value("kind", std::string()) == "pose";
    std::optional<ExperimentResults> pose_results;
    if (pose) try {
        pose_results = loadResults(dir.string());
      } catch (const std::exception&) {
      }
    struct Shared {
      std::string model, text, first_case;
      int runs = 0;
    };
    std::vector<Shared> warnings;  // in order of first appearance
    std::map<std::pair<std::string, std::string>, size_t> by_shape;
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
    const bool table = e.cases.size() <= 60;  // a longer table scrolls away; summary.json has them all
    if (!table) {
      int warned = 0;  // runs whose result carries warnings (e.g. still moving at the end)
      for (const auto& [name, j] : by_name)
        if (j->contains("runs") && (*j)["runs"].is_object())
          for (const auto& [model, r] : (*j)["runs"].items())
            if (r.contains("warnings") && r["warnings"].is_array() && !r["warnings"].empty()) ++warned;
      std::printf("  %zu cases (see %s/summary.json)", e.cases.size(), dir.c_str());
      if (warned > 0) std::printf(", %d model runs with warnings", warned);
      std::printf("\n");
    }
    for (const ExperimentCase& c : e.cases) {
      if (!table) break;
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
      if (j.contains("verdict") && j["verdict"].is_string()) std::printf("    verdict: %s\n", j["verdict"].get<std::string>().c_str());
      for (const auto& [model, r] : j["runs"].items())
        if (r.contains("warnings") && r["warnings"].is_array())
          for (const auto& w : r["warnings"])
            if (w.is_string() && warnings[by_shape.at({model, warningShape(w.get<std::string>())})].runs == 1)
              std::printf("    warning (%s): %s\n", model.c_str(), w.get<std::string>().c_str());
    }
    for (const Shared& w : warnings)
      if (w.runs > 1 || !table)
        std::printf("  warning (%s), %d run%s (first: %s; each run's numbers in results.csv): %s\n", w.model.c_str(),
                    w.runs, w.runs == 1 ? "" : "s", w.first_case.c_str(), w.text.c_str());
  }
}

// Plots and reports of a folder whose cases kept no time series say so (on stderr): the figures
// over time are left out, those over the swept values come from the results table.
void printSeriesNotes(const std::string& dir) {
  try {
    for (const ExperimentResults& r : loadResultTree(dir))
      if (const std::string note = r.seriesNote(); !note.empty()) std::fprintf(stderr, "note: %s\n", note.c_str());
  } catch (const std::exception&) {  // the command itself reports an unreadable folder
  }
}

// The distinct MuJoCo models of a suite (by their single-file MJCF, as result folders name them
// mjcf/<hash>.xml), each with the first case that simulates it.
struct SuiteModel {
  const Experiment* experiment;
  const ExperimentCase* c;
  std::string xml;
};
std::vector<SuiteModel> distinctModels(const std::vector<Experiment>& suite, const std::string& only_case) {
  std::vector<SuiteModel> out;
  std::set<std::string> seen;
  for (const Experiment& e : suite)
    for (const ExperimentCase& c : e.cases) {
      if (!only_case.empty() && c.name != only_case) continue;
      std::string xml = generateMjcf(c.robot, c.mujoco, c.effects);
      if (seen.insert(xml).second) out.push_back({&e, &c, std::move(xml)});
    }
  return out;
}

// A file-name stem of [A-Za-z0-9._=,~-] from any text (others become '_').
std::string fileStem(const std::string& text) {
  std::string s;
  for (char ch : text) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
                    std::string("._=,~-").find(ch) != std::string::npos;
    s += ok ? ch : '_';
  }
  if (s.empty() || s[0] == '.' || s[0] == '-') s = "x" + s;
  return s.substr(0, 120);
}

// `tailsim mjcf EXPERIMENT.yaml ...`: the models of an experiment's cases. Returns the exit code.
int writeExperimentMjcf(const std::string& exp_path, const std::string& only_case, const std::string& out,
                        const std::string& menagerie_dir) {
  const std::vector<Experiment> suite = loadExperimentSuite(exp_path);  // all errors before any work
  requireCase(suite, exp_path, only_case);
  const std::vector<SuiteModel> models = distinctModels(suite, only_case);
  if (!out.empty()) {
    if (models.size() != 1) {
      std::string names;
      for (size_t i = 0; i < models.size() && i < 5; ++i) names += (i ? ", " : "") + models[i].c->name;
      throw std::runtime_error(exp_path + " has " + std::to_string(models.size()) +
                               " distinct MuJoCo models (cases " + names + (models.size() > 5 ? ", ..." : "") +
                               "); pick one with --case NAME, or write them all with --menagerie DIR");
    }
    const bool to_stream = writeUserFile(out, models[0].xml);
    std::fprintf(to_stream ? stderr : stdout, "wrote %s (case %s)\n", out == "-" ? "the MJCF to stdout" : out.c_str(),
                 models[0].c->name.c_str());
    return kExitOk;
  }
  std::set<std::string> stems;
  for (const SuiteModel& m : models) {
    std::string stem = fileStem(models.size() == 1 && only_case.empty()
                                    ? m.experiment->name
                                    : m.experiment->name + "_" + caseDirName(m.c->name));
    if (!stems.insert(stem).second) stem += "_" + sha256Hex(m.xml).substr(0, 8);
    stems.insert(stem);
    const std::vector<std::string> paths =
        writeMenagerie(generateMenagerie(m.c->robot, m.c->mujoco, m.c->effects, stem), menagerie_dir);
    std::printf("wrote %s + %s (case %s)\n", paths[0].c_str(), paths[1].c_str(), m.c->name.c_str());
  }
  return kExitOk;
}

}  // namespace

// --out and --menagerie: a folder or file name, never empty (an empty path would mean "here"
// to some calls and an error to others).
const CLI::Validator kNonEmptyPath(
    [](std::string& v) { return v.empty() ? std::string("is empty: give a folder or file name") : std::string(); },
    "PATH");

int main(int argc, char** argv) {
  CLI::App app{"tailsim: quadruped yaw turning with a planar robotic tail (Rone & Ben-Tzvi 2016)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", versionString(), "print the version and exit");
  app.footer(kExitCodes);

  std::string exp_path, out_dir, case_name;
  int threads = 0;
  bool no_render = false, fresh = false, quiet = false, plots = false;
  auto* run = app.add_subcommand("run", "run an experiment (or a suite such as configs/paper/all.yaml)");
  run->add_option("experiment", exp_path, "experiment YAML")->required()->check(CLI::ExistingFile);
  run->add_option("--out", out_dir, "result folder")->required()->check(kNonEmptyPath);
  run->add_option("--threads", threads, "worker threads (default 0: all cores; at most 1024)")
      ->check(CLI::Range(0, limits::kMaxThreads));
  run->add_option("--case", case_name, "run only this case");
  run->add_flag("--no-render", no_render, "skip the render section");
  run->add_flag("--fresh", fresh, "start from an empty result folder (deletes tailsim's results in --out, also another experiment's)");
  bool allow_other_build = false;
  run->add_flag("--allow-other-build", allow_other_build,
                "resume cases computed by another tailsim version or commit (warned, recorded in summary.json) instead of refusing them");
  run->add_flag("--quiet", quiet, "print only errors and the final line (cases run, resumed, failed)");
  run->add_flag("--plot", plots, "draw the plots and the report afterwards");
  std::string shard_text;
  run->add_option("--shard", shard_text,
                  "K/N: run only shard K of N (cases balanced by expected cost; join the shards with tailsim merge)");
  std::vector<std::string> merge_dirs;
  std::string merge_out;
  auto* merge = app.add_subcommand("merge", "join the result folders of `run --shard K/N` into one folder");
  merge->add_option("shards", merge_dirs, "the shards' result folders")->required()->check(CLI::ExistingDirectory);
  merge->add_option("--out", merge_out, "the merged result folder (new or empty)")->required()->check(kNonEmptyPath);
  merge->add_option("--threads", threads, "worker threads (default 0: all cores; at most 1024)")
      ->check(CLI::Range(0, limits::kMaxThreads));
  merge->add_flag("--allow-other-build", allow_other_build,
                  "keep cases computed by another tailsim version or commit (warned, recorded in summary.json) instead of refusing them");
  std::vector<std::string> only_models;
  run->add_option("--models", only_models, "run only these models (analytic, perfoot, mujoco) of each case")
      ->check(CLI::IsMember(modelNames()));

  int links = 1;
  std::string mjcf_out, mjcf_exp, mjcf_case, mjcf_menagerie;
  auto* mjcf = app.add_subcommand("mjcf", "write the MuJoCo model (MJCF) of the paper robot or of an experiment's cases");
  auto* mjcf_exp_opt = mjcf->add_option("experiment", mjcf_exp, "experiment YAML: the models its cases simulate")
                           ->check(CLI::ExistingFile);
  mjcf->add_option("--links", links, "the paper robot with an n-link tail (1..6; default 1)")
      ->check(CLI::Range(1, 6))
      ->excludes(mjcf_exp_opt);
  mjcf->add_option("--case", mjcf_case, "only this case's model")->needs(mjcf_exp_opt);
  auto* mjcf_out_opt = mjcf->add_option("--out", mjcf_out, "one self-contained .xml, the model tailsim simulates (- = stdout)")
                            ->check(kNonEmptyPath);
  mjcf->add_option("--menagerie", mjcf_menagerie,
                   "folder for the Menagerie form: tailsim_<name>.xml (robot) + scene_<name>.xml (mjcf/README.md)")
      ->excludes(mjcf_out_opt)
      ->check(kNonEmptyPath);

  std::string render_out = "renders";
  auto* render = app.add_subcommand("render", "render each case of an experiment to MP4 + PNG (headless)");
  render->add_option("experiment", exp_path, "experiment YAML")->required()->check(CLI::ExistingFile);
  render->add_option("--case", case_name, "render only this case");
  render->add_option("--out", render_out, "output folder (default: renders/)")->check(kNonEmptyPath);

  std::string result_dir;
  auto* plot = app.add_subcommand("plot", "redraw the figures of a result folder (no simulation)");
  plot->add_option("dir", result_dir, "result folder")->required()->check(CLI::ExistingDirectory);
  PlotOptions plot_opt;
  bool no_titles = false;
  std::string plot_size;
  plot->add_flag("--no-titles", no_titles, "no title drawn in the figures (figures.html's captions keep them)");
  plot->add_option("--size", plot_size, "W,H: every figure W x H pixels (PNG; the SVG in points)");
  plot->add_option("--font-scale", plot_opt.font_scale, "every font scaled by this factor (default 1)")
      ->check(CLI::PositiveNumber);
  auto* report = app.add_subcommand("report", "write DIR/report.md: plots and the paper's findings checked");
  report->add_option("dir", result_dir, "result folder")->required()->check(CLI::ExistingDirectory);
  auto* ladder = app.add_subcommand("ladder", "write DIR/ladder.md: the gap ladder of a configs/ladder/ result folder");
  ladder->add_option("dir", result_dir, "result folder")->required()->check(CLI::ExistingDirectory);

  int trust_exit = -1;
  addTrustCommand(app, trust_exit);
  std::string acc_out;
  bool acc_quick = false, acc_no_mujoco = false;
  int acc_repeats = 3;
  auto* accuracy = app.add_subcommand("accuracy", "work-precision study of both models' solver settings");
  accuracy->add_option("experiment", exp_path, "experiment YAML (every simulate case is studied)")
      ->required()->check(CLI::ExistingFile);
  accuracy->add_option("--out", acc_out, "output folder")->required()->check(kNonEmptyPath);
  accuracy->add_option("--repeats", acc_repeats, "runs per setting; wall time is their median")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  accuracy->add_flag("--quick", acc_quick, "a reduced grid");
  accuracy->add_flag("--no-mujoco", acc_no_mujoco, "analytic model only");

  bool schema_markdown = false, schema_robot = false;
  auto* schema = app.add_subcommand("schema", "print the JSON Schema of experiment and suite files (for editors)");
  schema->add_flag("--robot", schema_robot, "the schema of robot files instead");
  schema->add_flag("--markdown", schema_markdown, "the key tables of docs/experiment-format.md instead");
  std::string opt_out;
  bool opt_quiet = false;
  auto* optimize = app.add_subcommand("optimize", "optimise a tail stroke (kind: optimize experiment)");
  optimize->add_option("experiment", exp_path, "optimize experiment YAML")->required()->check(CLI::ExistingFile);
  optimize->add_option("--out", opt_out, "result folder")->required()->check(kNonEmptyPath);
  optimize->add_flag("--quiet", opt_quiet, "no progress lines");
  std::string man_out;
  bool man_quiet = false, man_video = false;
  auto* maneuver = app.add_subcommand("maneuver", "turn to a heading with tail strokes, open- and closed-loop (kind: maneuver experiment)");
  maneuver->add_option("experiment", exp_path, "maneuver experiment YAML")->required()->check(CLI::ExistingFile);
  maneuver->add_option("--out", man_out, "result folder")->required()->check(kNonEmptyPath);
  maneuver->add_flag("--video", man_video, "also render the closed-loop turn (renders/<name>.mp4)");
  maneuver->add_flag("--quiet", man_quiet, "no progress lines");

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 says "A subcommand is required" for `tailsim rn`: name the word it did not know.
    const std::string first = argc > 1 ? argv[1] : "";
    if (!first.empty() && first[0] != '-' && app.get_subcommands().empty()) {
      std::string names;
      for (const CLI::App* sc : app.get_subcommands([](CLI::App*) { return true; })) names += (names.empty() ? "" : ", ") + sc->get_name();
      std::fprintf(stderr, "error: unknown subcommand '%s' (one of: %s)\nRun with --help for more information.\n",
                   first.c_str(), names.c_str());
    } else {
      // CLI11 checks required arguments before unknown ones ("--out is required" for
      // `tailsim run --bogus`): name an unknown option first, it is the likelier mistake (and name it
      // the same way when nothing else is wrong).
      std::string unknown, where = "tailsim";
      for (const std::string& a : app.remaining())
        if (unknown.empty() && a.size() > 1 && a[0] == '-') unknown = a;
      for (const CLI::App* sc : app.get_subcommands())
        for (const std::string& a : sc->remaining())
          if (unknown.empty() && a.size() > 1 && a[0] == '-') {
            unknown = a;
            where = "tailsim " + sc->get_name();
          }
      if (!unknown.empty())
        std::fprintf(stderr, "error: unknown option '%s' for '%s'\nRun '%s --help' for the options.\n", unknown.c_str(),
                     where.c_str(), where.c_str());
      else
        app.exit(e);  // CLI11's message names the option or argument
    }
    return kExitUsage;
  }

  if (trust_exit >= 0) return trust_exit;
  try {
    if (*run) {
      ShardSpec shard{};
      if (!shard_text.empty()) {
        try {
          shard = parseShard(shard_text);
        } catch (const std::invalid_argument& e) {  // a usage error, like any other bad option
          std::fprintf(stderr, "error: %s\n", e.what());
          return kExitUsage;
        }
      }
      std::vector<Experiment> suite = loadExperimentSuite(exp_path);  // all errors before any work
      selectModels(suite, only_models, exp_path);
      RunOptions o;
      o.out_dir = out_dir;
      o.threads = threads;
      o.render = !no_render;
      o.resume = !fresh;
      o.progress = !quiet;
      o.only_case = case_name;
      o.stop_on_sigint = true;
      o.allow_other_build = allow_other_build;
      if (!shard_text.empty()) {
        o.shard_index = shard.index;
        o.shard_count = shard.count;
      }
      requireCase(suite, exp_path, case_name);
      const RunStats s = runSuite(suite, o);
      std::printf("%d cases%s: %d run, %d resumed, %d failed model runs, %.3f s wall\n", s.total,
                  shard_text.empty() ? "" : (" in shard " + shard_text).c_str(), s.ran, s.resumed, s.failed,
                  s.wall_time_s);
      if (s.interrupted) {
        std::fflush(stdout);
        std::fprintf(stderr, "interrupted: %d of %d cases saved in %s; run the same command again to resume\n",
                     s.ran + s.resumed, s.total, out_dir.c_str());
        // 128 + the signal, as a shell reports a process it ended (SIGINT 130, SIGTERM 143, SIGHUP 129).
        return s.stop_signal > 0 ? 128 + s.stop_signal : kExitInterrupted;
      }
      // --quiet: the failed runs and the line above only
      if (shard_text.empty()) printCases(suite, out_dir, suite.size() > 1, quiet);  // a shard's table is mostly "not run"
      if (plots) {
        if (!quiet) printSeriesNotes(out_dir);
        const std::string report_path = writeReport(out_dir);
        if (!quiet) std::printf("report: %s\n", report_path.c_str());
        const std::string page_path = writeResultPage(out_dir);
        if (!quiet) std::printf("page: %s\n", page_path.c_str());
      }
      return s.failed ? kExitRunsFailed : kExitOk;
    }
    if (*merge) {
      const MergeStats m = mergeShards(merge_dirs, merge_out, threads, allow_other_build);
      if (m.stop_signal > 0) {
        const char* name = m.stop_signal == SIGTERM ? "SIGTERM" : m.stop_signal == SIGHUP ? "SIGHUP" : "Ctrl-C";
        std::fprintf(stderr, "interrupted by %s: merge stopped, nothing written to %s; run the same command again\n", name,
                     merge_out.c_str());
        return 128 + m.stop_signal;
      }
      std::printf("merged %d shards: %d cases, %d files into %s\n", m.shards, m.cases, m.files_copied, merge_out.c_str());
      return kExitOk;
    }
    if (*mjcf) {
      if (mjcf_out.empty() && mjcf_menagerie.empty()) {
        std::fprintf(stderr, "error: tailsim mjcf needs --out FILE or --menagerie DIR\nRun 'tailsim mjcf --help' for the options.\n");
        return kExitUsage;
      }
      if (!mjcf_exp.empty()) return writeExperimentMjcf(mjcf_exp, mjcf_case, mjcf_out, mjcf_menagerie);
      if (!mjcf_menagerie.empty()) {
        const std::vector<std::string> paths = writeMenagerieFiles(links, mjcf_menagerie);
        std::printf("wrote %s + %s\n", paths[0].c_str(), paths[1].c_str());
        return kExitOk;
      }
      const bool to_stream = writeMjcfFile(links, mjcf_out);
      // XML on stdout stays XML: the message goes to stderr when the model went to a stream.
      std::fprintf(to_stream ? stderr : stdout, "wrote %s\n", mjcf_out == "-" ? "the MJCF to stdout" : mjcf_out.c_str());
      return kExitOk;
    }
    if (*render) {
      const std::vector<Experiment> suite = loadExperimentSuite(exp_path);
      requireCase(suite, exp_path, case_name);
      for (const Experiment& e : suite) {
        const fs::path dir = fs::path(render_out) / e.name;
        for (ExperimentCase c : e.cases) {
          if (!case_name.empty() && c.name != case_name) continue;
          if (!c.render.enabled) c.render.enabled = true;  // defaults when the file has no render section
          checkRenderPrerequisites(c.render, dir.string());  // before simulating
          if (c.kind != CaseKind::kSimulate) throw std::runtime_error("only kind: simulate experiments can be rendered");
          c.models = {"analytic", "mujoco"};
          const std::vector<RunResult> runs = runCase(c);
          for (const RunResult& r : runs)
            if (!r.summary.ok) std::fprintf(stderr, "warning: %s run failed: %s\n", r.summary.model.c_str(), r.summary.error.c_str());
          const RenderStats st = renderCase(c, runs, dir.string());
          std::printf("%s/%s.mp4: %ld frames %dx%d, %.1f frames/s\n", dir.c_str(), caseDirName(c.name).c_str(),
                      st.frames, st.width, st.height, st.fps);
        }
      }
      return kExitOk;
    }
    if (*accuracy) {
      const Experiment e = loadExperiment(exp_path);
      fs::create_directories(acc_out);
      AccuracyOptions ao;
      ao.repeats = acc_repeats;
      ao.quick = acc_quick;
      ao.mujoco = !acc_no_mujoco;
      const auto studies = runAccuracyStudy(e, ao);
      writeAccuracyTables(studies, acc_out);
      for (const std::string& png : plotAccuracy(studies, acc_out)) std::printf("%s\n", png.c_str());
      std::printf("%s/accuracy.md\n%s/accuracy.csv\n", acc_out.c_str(), acc_out.c_str());
      return kExitOk;
    }
    if (*schema) {
      if (schema_markdown) std::printf("%s", settingsMarkdown().c_str());
      else std::printf("%s\n", (schema_robot ? robotSchema() : experimentSchema()).dump(2).c_str());
      return kExitOk;
    }
    if (*optimize || *maneuver) {
      // The optimiser and the maneuvers live in a module loaded only here (src/app/modules/optimize.cc):
      // pagmo's start-up cost stays out of every other command.
      const fs::path exe = fs::read_symlink("/proc/self/exe");
      std::string tried;
      void* lib = nullptr;
      for (const fs::path& p : {exe.parent_path() / "tailsim_optimize.so",
                                exe.parent_path().parent_path() / "lib" / "tailsim" / "tailsim_optimize.so"}) {
        lib = ::dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (lib) break;
        const char* why = ::dlerror();
        tried += "\n  " + p.string() + ": " + (why ? why : "?");
      }
      const char* what = *optimize ? "optimize" : "maneuver";
      if (!lib) throw std::runtime_error(std::string(what) + ": cannot load the optimiser module:" + tried);
      char err[8192] = {0};
      int rc = 0;
      if (*optimize) {
        using Entry = int (*)(const char*, const char*, int, char*, size_t);
        const auto entry = reinterpret_cast<Entry>(::dlsym(lib, "tailsim_optimize_main"));
        if (!entry) throw std::runtime_error("optimize: the optimiser module has no tailsim_optimize_main");
        rc = entry(exp_path.c_str(), opt_out.c_str(), opt_quiet ? 1 : 0, err, sizeof err);
      } else {
        using Entry = int (*)(const char*, const char*, int, int, char*, size_t);
        const auto entry = reinterpret_cast<Entry>(::dlsym(lib, "tailsim_maneuver_main"));
        if (!entry) throw std::runtime_error("maneuver: the optimiser module has no tailsim_maneuver_main");
        rc = entry(exp_path.c_str(), man_out.c_str(), man_quiet ? 1 : 0, man_video ? 1 : 0, err, sizeof err);
      }
      if (rc == -1) throw ConfigError(err);
      if (rc < 0) throw std::runtime_error(err);
      return rc == 0 ? kExitOk : kExitRunsFailed;
    }
    if (*plot) {
      plot_opt.titles = !no_titles;
      if (!plot_size.empty()) {
        int w = 0, h = 0;
        char extra = 0;
        if (std::sscanf(plot_size.c_str(), "%d,%d%c", &w, &h, &extra) != 2 || w < 100 || h < 100 || w > 30000 ||
            h > 30000) {
          std::fprintf(stderr, "error: --size %s: expected W,H in pixels, each 100..30000 (e.g. --size 1600,1000)\n",
                       plot_size.c_str());
          return kExitUsage;
        }
        plot_opt.width_px = w, plot_opt.height_px = h;
      }
      printSeriesNotes(result_dir);
      const auto files = plotResults(result_dir, plot_opt);
      for (const auto& f : files) std::printf("%s\n", f.png.c_str());
      std::printf("%s\n", writeResultPage(result_dir).c_str());
      std::printf("%s\n", figureSheetPath(result_dir).c_str());
      return kExitOk;
    }
    if (*report) {
      printSeriesNotes(result_dir);
      std::printf("%s\n", writeReport(result_dir).c_str());
      return kExitOk;
    }
    if (*ladder) {
      for (const std::string& f : writeLadder(result_dir)) std::printf("%s\n", f.c_str());
      return kExitOk;
    }
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitError;
  }
  return kExitOk;
}
