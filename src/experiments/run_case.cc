#include "experiments/run_job.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>
#include <nlohmann/json.hpp>

#include "experiments/folder_inputs.h"
#include "experiments/render_case.h"
#include "experiments/robot_model_cases.h"
#include "experiments/settings_json.h"
#include "experiments/verdict.h"
#include "experiments/work_estimate.h"
#include "models/analytic/analytic_simulation.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_simulation.h"
#include "common/atomic_file.h"
#include "results/csv.h"
#include "results/columns.h"
#include "common/sha256.h"
#include "results/thin_series.h"
#include "tailsim_version.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;

// ---- Resume key ----------------------------------------------------------------------------
// The SHA-256 of the canonical resolved case (settings_json.h: every declared setting, so a new
// setting is in the key by being declared), the models run, the render switch and settings, and
// the tailsim version and git commit.
std::string caseKey(const ExperimentCase& c, bool render) { return sha256Hex(caseKeyText(c, render)); }

// A name made only of [A-Za-z0-9.=,_-], not starting with '.' or '-', at most kMaxPlainDirName
// characters, is its own folder name. Any other name maps to its sanitized, shortened form plus
// "~" and 16 hex digits of its SHA-256: '~' never occurs in a plain name, so a plain and a mapped
// name never meet, and two mapped names meet only if their hashes do (checked in prepare()).
std::string caseDirName(const std::string& name) {
  constexpr size_t kMaxPlainDirName = 100, kMaxReadable = 80;
  auto allowed = [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '=' || ch == ',' ||
           ch == '_';
  };
  bool plain = !name.empty() && name.size() <= kMaxPlainDirName && name[0] != '.' && name[0] != '-';
  for (char ch : name) plain = plain && allowed(ch);
  if (plain) return name;
  std::string d;
  for (char ch : name.substr(0, kMaxReadable)) d += allowed(ch) ? ch : '_';
  if (!d.empty() && (d[0] == '.' || d[0] == '-')) d[0] = '_';
  if (d.empty()) d = "case";
  return d + "~" + sha256Hex(name).substr(0, 16);
}

json summaryJson(const RunSummary& s) {
  json j;
  j["ok"] = s.ok;
  // A failed run has no phi_net (null, never a number a reader could take for a result).
  j["phi_net_deg"] = s.ok && std::isfinite(s.phi_net_deg) ? json(s.phi_net_deg) : json(nullptr);
  j["t_stop_s"] = s.t_stop_s;
  j["stick_slip_events"] = s.stick_slip_events;
  j["wall_time_s"] = s.wall_time_s;
  j["solver_steps"] = s.solver_steps;
  if (!s.error.empty()) j["error"] = s.error;
  // A finished run: was the body at rest at the end, and what makes the result doubtful.
  j["at_rest"] = s.ok ? json(s.at_rest) : json(nullptr);
  j["warnings"] = s.warnings;
  for (const auto& [k, v] : s.extra) j["extra"][k] = std::isfinite(v) ? json(v) : json(nullptr);
  return j;
}

std::vector<RunResult> runCase(const ExperimentCase& c, RunContext* ctx) {
  std::vector<RunResult> out;
  if (c.robot_model && !c.robot_derived)  // the caller derives it first (resolveRobotModels)
    throw std::invalid_argument("case " + c.name + ": its robot's model file " + c.robot_model->file +
                                " was not stood and measured before the run (resolveRobotModels)");
  if (c.kind == CaseKind::kPose) {
    std::vector<JointState> js(c.robot.numLinks());
    for (size_t i = 0; i < js.size(); ++i)
      js[i] = {c.pose.theta_rad.at(i), c.pose.thetadot_radps.at(i), c.pose.thetaddot_radps2.at(i)};
    out.push_back(evaluatePose(c.robot, js, c.effects));
    return out;
  }
  for (const std::string& m : c.models) {
    const ModelEntry* model = findModel(m);
    if (!model) throw std::invalid_argument("unknown model '" + m + "'");  // the loader refuses it first
    out.push_back(model->run(c, ctx));
    if (const std::string w = jointSpeedWarning(c); !w.empty()) out.back().summary.warnings.push_back(w);
  }
  return out;
}

namespace runner {

namespace {

// Stage 1: a case's entry before its runs: who it is, where its results come from, its key and
// build, its settings (case folders only) and its swept values.
json caseEntryHeader(const Job& job, size_t i) {
  const ExperimentCase& c = job.e->cases[i];
  json j;
  j["name"] = c.name;
  j["dir"] = job.dirs[i];
  j["experiment"] = job.e->name;
  j["source"] = job.source;
  j["key"] = job.keys[i];
  j["tailsim_version"] = kVersion;
  if (*kGitCommit) j["tailsim_git_commit"] = kGitCommit;
  // Every parameter the run used, defaults included, in a case folder's result.json. A case
  // without a folder (a line of DIR/cases.jsonl, one of up to 10^5) leaves it out: it is 80 % of
  // the line, and the folder's experiment.yaml resolves every case the same (ExperimentResults).
  if (c.output.caseFolder()) {
    j["resolved"] = resolvedJson(c);
    // ... but not where they were read from: a folder re-run from its own copies (robot.yaml,
    // experiment.yaml) must write the same result.json; "source" above names the original input.
    j["resolved"].erase("source_file");
    j["resolved"].erase("robot_file");
  }
  j["sweep"] = json::object();
  for (const auto& [key, v] : c.sweep_values) j["sweep"][key] = v;
  j["runs"] = json::object();
  return j;
}

// Stage 2: each model's time series (its CSV in the case folder, or its groups in the case's HDF5
// part, returned unpublished) and its summary in the entry; then the case's verdict.
std::unique_ptr<TimeSeriesH5Writer> writeRuns(const Job& job, size_t i, const std::vector<RunResult>& runs, json& j,
                                              int& failed_runs) {
  const ExperimentCase& c = job.e->cases[i];
  const fs::path dir = job.root / "cases" / job.dirs[i];
  const bool folder = c.output.caseFolder();
  const bool thin = c.output.time_series == TimeSeriesOutput::kThin;
  const std::vector<double> marks = thin && c.kind == CaseKind::kSimulate ? c.trajectory().breakpoints() : std::vector<double>{};
  std::unique_ptr<TimeSeriesH5Writer> part;  // this case's DIR/time_series.h5.d/<dir>.h5
  if (inH5(c)) {
    makeResultDir((job.root / kH5Parts).string());
    part = std::make_unique<TimeSeriesH5Writer>(h5PartPath(job, i).string(), H5Storage::kMemory);
  }
  for (const RunResult& r : runs) {
    // Every model's CSV in the one column order (docs/ARCHITECTURE.md "Time-series columns").
    if (keepsSeries(c)) {
      TimeSeries ordered = col::inColumnOrder(r.series, modelColumnOrder(col::links(r.series)));
      if (thin && !r.series_thinned) ordered = thinRows(ordered, marks);
      if (folder) writeCsvAtomic((dir / (r.summary.model + ".csv")).string(), ordered);
      else part->write(job.dirs[i], c.name, job.keys[i], c.sweep_values, r.summary.model,
                       settings::nameOf(timeSeriesOutputNames(), c.output.time_series), ordered);
    }
    j["runs"][r.summary.model] = summaryJson(r.summary);
    if (!r.summary.ok) ++failed_runs;
  }
  {
    std::vector<RunSummary> sums;
    for (const RunResult& r : runs) sums.push_back(r.summary);
    if (std::string v = caseVerdict(sums); !v.empty()) j["verdict"] = std::move(v);
  }
  return part;
}

// Stage 3: the MJCF a model's run simulated, once per distinct model (mjcf/<hash>.xml); none when
// the model could not be built (the run's error says why).
void writeCaseMjcf(const Job& job, const ExperimentCase& c, json& j) {
  const bool simulates_mjcf = std::any_of(c.models.begin(), c.models.end(), [](const std::string& m) {
    const ModelEntry* e = findModel(m);
    return e && e->simulates_mjcf;
  });
  if (c.kind != CaseKind::kPose && simulates_mjcf) {
    std::string xml;
    try {
      xml = c.robot_model ? articulatedMjcf(c) : generateMjcf(c.robot, c.mujoco, c.effects);
    } catch (const std::exception&) {
    }
    if (!xml.empty()) {
      const std::string name = mjcfFileName(xml);
      makeResultDir((job.root / "mjcf").string());
      if (!fs::exists(job.root / name)) writeFileAtomic((job.root / name).string(), xml);
      j["mjcf"] = name;
    }
  }
}

// Stage 5: the case's HDF5 part on disk, named with its content in its folder's manifest before
// it takes its name (before the journal line).
void publishPart(const Job& job, size_t i, TimeSeriesH5Writer& part) {
  part.publish([&](const std::string& temp) {
    const std::optional<std::string> hash = sha256OfFile(temp);
    if (!hash) throw std::runtime_error("cannot read back " + temp);
    recordHashInManifest((job.root / kH5Parts).string(), job.dirs[i] + ".h5", *hash);
  });
}

}  // namespace

// Runs one case and writes its folder; result.json last, as the "finished" marker.
std::string runAndWrite(const Job& job, size_t i, int& failed_runs, RunContext& ctx) {
  const ExperimentCase& c = job.e->cases[i];
  const std::vector<RunResult> runs = runCase(c, &ctx);
  const fs::path dir = job.root / "cases" / job.dirs[i];
  const bool folder = c.output.caseFolder();
  if (folder) makeResultDir(dir.string());
  json j = caseEntryHeader(job, i);
  const std::unique_ptr<TimeSeriesH5Writer> part = writeRuns(job, i, runs, j, failed_runs);
  writeCaseMjcf(job, c, j);
  if (job.render) renderCase(c, runs, (job.root / "renders").string());  // Stage 4: the video or still
  if (part) publishPart(job, i, *part);
  // Stage 6: the entry, the case's "finished" marker: its result.json, or one line, one write().
  std::string line = j.dump();
  if (folder) writeFileAtomic((dir / "result.json").string(), j.dump(1));
  else job.journal->append(line + "\n");  // one line, one write(): the case is finished
  return line;
}

}  // namespace runner
}  // namespace tailsim
