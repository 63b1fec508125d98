// Mixed builds and conflicts in result folders (docs/ARCHITECTURE.md "Result folder"): every result
// names the tailsim build that computed it; resume and merge refuse another build's results (or, with
// allow_other_build, keep them and record it); merge refuses two different results for one case; an
// incomplete journal entry, or an HDF5 group missing a dataset or full of NaN, is not finished.
#include <gtest/gtest.h>

#include <dlfcn.h>
#include <link.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/experiment_runner.h"
#include "experiments/sharding.h"
#include "experiments/time_series_h5.h"
#include "common/atomic_file.h"
#include "common/sha256.h"
#include "tailsim_version.h"

using namespace tailsim;
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

fs::path tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tailsim_mixed_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// 4 analytic cases; output as given (none: cases.jsonl; hdf5: cases.jsonl + time_series.h5).
fs::path writeSweep(const fs::path& dir, const std::string& output) {
  const fs::path f = dir / "sweep.yaml";
  std::ofstream(f) << "name: mixed\nrobot: paper\ntail: {links: 1}\n"
                   << "trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.2, 0.4, 0.6, 0.8]}}\n"
                   << "models: [analytic]\noutput: " << output << "\n";
  return f;
}

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::vector<json> journal(const fs::path& dir) {
  std::vector<json> out;
  std::istringstream in(readAll(dir / "cases.jsonl"));
  for (std::string line; std::getline(in, line);) out.push_back(json::parse(line));
  return out;
}

void writeJournal(const fs::path& dir, const std::vector<json>& lines) {
  std::ofstream out(dir / "cases.jsonl", std::ios::binary | std::ios::trunc);
  for (const json& j : lines) out << j.dump() << "\n";
}

RunOptions options(const fs::path& out) {
  RunOptions o;
  o.out_dir = out.string();
  o.progress = false;
  o.threads = 1;
  return o;
}

}  // namespace

TEST(MixedBuilds, ResumeAndMergeRefuseAnotherBuildUnlessAllowed) {
  const fs::path dir = tempDir("build");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  const fs::path out = dir / "out";
  runExperiment(e, options(out));
  // The same results as computed by another build: version, commit and key as it writes them.
  const BuildId other{"0.0.1-other", "0123456789ab"};
  std::vector<json> lines = journal(out);
  ASSERT_EQ(lines.size(), 4u);
  for (json& j : lines) {
    j["tailsim_version"] = other.version;
    j["tailsim_git_commit"] = other.git_commit;
    for (const ExperimentCase& c : e.cases)
      if (c.name == j["name"]) j["key"] = sha256Hex(caseKeyText(c, false, other));
  }
  writeJournal(out, lines);
  const std::string before = readAll(out / "cases.jsonl");
  try {
    runExperiment(e, options(out));
    ADD_FAILURE() << "resume accepted another build's results";
  } catch (const std::runtime_error& ex) {
    EXPECT_NE(std::string(ex.what()).find("another tailsim build"), std::string::npos) << ex.what();
    EXPECT_NE(std::string(ex.what()).find("0.0.1-other"), std::string::npos) << ex.what();
    EXPECT_NE(std::string(ex.what()).find("--allow-other-build"), std::string::npos) << ex.what();
  }
  EXPECT_EQ(readAll(out / "cases.jsonl"), before) << "a refused resume changed the journal";
  // merge refuses them too
  EXPECT_THROW(mergeShards({out.string()}, (dir / "merged").string(), 1), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "merged"));
  fs::remove_all(dir);
}

// merge names the shard folder that holds another build's cases (not "finished in none of the
// shard folders", not its staging folder), refused and, with allow_other_build, in the warning.
TEST(MixedBuilds, MergeOfAnotherBuildsShardNamesTheShard) {
  const fs::path dir = tempDir("mergebuild");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  const fs::path shard = dir / "shard_of_other_build";
  runExperiment(e, options(shard));
  const BuildId other{"0.0.1-other", "0123456789ab"};
  std::vector<json> lines = journal(shard);
  for (json& j : lines) {
    j["tailsim_version"] = other.version;
    j["tailsim_git_commit"] = other.git_commit;
    for (const ExperimentCase& c : e.cases)
      if (c.name == j["name"]) j["key"] = sha256Hex(caseKeyText(c, false, other));
  }
  writeJournal(shard, lines);
  try {
    mergeShards({shard.string()}, (dir / "merged").string(), 1);
    ADD_FAILURE() << "merge accepted another build's shard";
  } catch (const std::runtime_error& ex) {
    const std::string m = ex.what();
    EXPECT_NE(m.find("another tailsim build"), std::string::npos) << m;
    EXPECT_NE(m.find(shard.string()), std::string::npos) << m;
    EXPECT_EQ(m.find("finished in none"), std::string::npos) << m;
    EXPECT_EQ(m.find(".merge.tmp."), std::string::npos) << m;
  }
  testing::internal::CaptureStderr();
  mergeShards({shard.string()}, (dir / "merged").string(), 1, true);
  const std::string warning = testing::internal::GetCapturedStderr();
  EXPECT_NE(warning.find(shard.string()), std::string::npos) << warning;
  EXPECT_EQ(warning.find(".merge.tmp."), std::string::npos) << warning;
  fs::remove_all(dir);
}

TEST(MixedBuilds, ResumeOfAnotherBuildAllowedIsRecorded) {
  const fs::path dir = tempDir("buildallowed");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  const fs::path out = dir / "out";
  runExperiment(e, options(out));
  const BuildId other{"0.0.1-other", "0123456789ab"};
  std::vector<json> lines = journal(out);
  for (json& j : lines) {
    j["tailsim_version"] = other.version;
    j["tailsim_git_commit"] = other.git_commit;
    for (const ExperimentCase& c : e.cases)
      if (c.name == j["name"]) j["key"] = sha256Hex(caseKeyText(c, false, other));
  }
  writeJournal(out, lines);
  // Allowed: kept (none run again), recorded in summary.json.
  RunOptions o = options(out);
  o.allow_other_build = true;
  const RunStats s = runExperiment(e, o);
  EXPECT_EQ(s.resumed, 4);
  EXPECT_EQ(s.ran, 0);
  const json summary = json::parse(readAll(out / "summary.json"));
  ASSERT_TRUE(summary.contains("other_builds")) << summary.dump();
  EXPECT_EQ(summary["other_builds"].begin().value(), 4);
  EXPECT_EQ(summary["cases"][0].value("tailsim_version", ""), other.version);
  fs::remove_all(dir);
}

TEST(MixedBuilds, MergeRefusesTwoDifferentResultsForOneCase) {
  const fs::path dir = tempDir("conflict");
  for (const char* output : {"{time_series: none}", "{sample_dt_s: 0.01}"}) {
    const Experiment e = loadExperiment(writeSweep(dir, output).string());
    const fs::path a = dir / "a", b = dir / "b";
    fs::remove_all(a);
    fs::remove_all(b);
    runExperiment(e, options(a));
    runExperiment(e, options(b));
    // Identical duplicates (wall times aside) merge.
    EXPECT_NO_THROW(mergeShards({a.string(), b.string()}, (dir / "m1").string(), 1)) << output;
    fs::remove_all(dir / "m1");
    // One case's result changed in b: refused, naming the case and both folders.
    if (fs::exists(b / "cases.jsonl")) {
      std::vector<json> lines = journal(b);
      lines[1]["runs"]["analytic"]["phi_net_deg"] = 1.5;
      writeJournal(b, lines);
    } else {
      const fs::path rj = b / "cases" / "w_ss=0.4" / "result.json";
      json j = json::parse(readAll(rj));
      j["runs"]["analytic"]["phi_net_deg"] = 1.5;
      std::ofstream(rj, std::ios::trunc) << j.dump(1);
    }
    try {
      mergeShards({a.string(), b.string()}, (dir / "m2").string(), 1);
      ADD_FAILURE() << output << ": merge accepted two different results for w_ss=0.4";
    } catch (const std::runtime_error& ex) {
      const std::string w = ex.what();
      EXPECT_NE(w.find("w_ss=0.4"), std::string::npos) << w;
      EXPECT_NE(w.find(a.string()), std::string::npos) << w;
      EXPECT_NE(w.find(b.string()), std::string::npos) << w;
    }
    EXPECT_FALSE(fs::exists(dir / "m2"));
  }
  fs::remove_all(dir);
}

TEST(MixedBuilds, IncompleteJournalEntryRunsAgain) {
  const fs::path dir = tempDir("incomplete");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  const fs::path out = dir / "out";
  runExperiment(e, options(out));
  std::vector<json> lines = journal(out);
  lines[2]["runs"] = json::object();
  writeJournal(out, lines);
  const RunStats s = runExperiment(e, options(out));
  EXPECT_EQ(s.ran, 1);
  EXPECT_EQ(s.resumed, 3);
  const std::string csv = readAll(out / "results.csv");
  EXPECT_NE(csv.find(lines[2]["name"].get<std::string>()), std::string::npos) << csv;
  fs::remove_all(dir);
}

// An entry is whole only with every field a run writes, of its type: each edit below makes its case
// run again (never resumed, never published as a result).
TEST(MixedBuilds, JournalEntryWithAMissingOrMistypedFieldRunsAgain) {
  const fs::path dir = tempDir("mistyped");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  const fs::path out = dir / "out";
  runExperiment(e, options(out));
  const std::vector<json> clean = journal(out);
  const std::vector<std::pair<std::string, std::function<void(json&)>>> edits = {
      {"runs: {analytic: {ok: true}}", [](json& r) { r = json{{"ok", true}}; }},
      {"phi_net_deg a string", [](json& r) { r["phi_net_deg"] = "abc"; }},
      {"phi_net_deg null with ok true", [](json& r) { r["phi_net_deg"] = nullptr; }},
      {"phi_net_deg missing", [](json& r) { r.erase("phi_net_deg"); }},
      {"warnings a string", [](json& r) { r["warnings"] = "x"; }},
      {"solver_steps a string", [](json& r) { r["solver_steps"] = "12"; }},
      {"t_stop_s missing", [](json& r) { r.erase("t_stop_s"); }},
      {"at_rest a number", [](json& r) { r["at_rest"] = 1; }},
      {"error a number", [](json& r) { r["error"] = 3; }},
  };
  for (const auto& [what, edit] : edits) {
    std::vector<json> lines = clean;
    edit(lines[1]["runs"]["analytic"]);
    writeJournal(out, lines);
    const RunStats s = runExperiment(e, options(out));
    EXPECT_EQ(s.ran, 1) << what;
    EXPECT_EQ(s.resumed, 3) << what;
    json now = journal(out)[1]["runs"]["analytic"], was = clean[1]["runs"]["analytic"];
    now.erase("wall_time_s");
    was.erase("wall_time_s");
    EXPECT_EQ(now, was) << what;
  }
  fs::remove_all(dir);
}

// An entry whose own version or commit label disagrees with its key (this build's) is not this
// build's: its case runs again, and no result labelled with another build is published as this one's.
TEST(MixedBuilds, JournalEntryWithEditedBuildLabelsIsNotThisBuilds) {
  const fs::path dir = tempDir("labels");
  const Experiment e = loadExperiment(writeSweep(dir, "{time_series: none}").string());
  const fs::path out = dir / "out";
  runExperiment(e, options(out));
  const std::vector<json> clean = journal(out);
  const std::vector<std::pair<std::string, std::function<void(json&)>>> edits = {
      {"tailsim_version 0.0.9", [](json& j) { j["tailsim_version"] = "0.0.9"; }},
      {"tailsim_git_commit changed", [](json& j) { j["tailsim_git_commit"] = "0123456789ab"; }},
      {"tailsim_version deleted", [](json& j) { j.erase("tailsim_version"); }},
  };
  for (const auto& [what, edit] : edits) {
    std::vector<json> lines = clean;
    edit(lines[0]);
    writeJournal(out, lines);
    const RunStats s = runExperiment(e, options(out));
    EXPECT_EQ(s.ran, 1) << what;
    EXPECT_EQ(s.resumed, 3) << what;
    const json summary = json::parse(readAll(out / "summary.json"));
    EXPECT_FALSE(summary.contains("other_builds")) << what;
    for (const json& c : summary["cases"]) {  // this build's cases carry no label of their own (the header's)
      EXPECT_EQ(c.value("tailsim_version", std::string(kVersion)), kVersion) << what;
      EXPECT_EQ(c.value("tailsim_git_commit", std::string(kGitCommit)), kGitCommit) << what;
    }
  }
  fs::remove_all(dir);
}

namespace {
// libhdf5 as tailsim loaded it (dlopen, RTLD_LOCAL): found among the loaded objects by name.
void* loadedHdf5() {
  std::string path;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* data) {
        if (info->dlpi_name && std::strstr(info->dlpi_name, "libhdf5")) *static_cast<std::string*>(data) = info->dlpi_name;
        return 0;
      },
      &path);
  return path.empty() ? nullptr : ::dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD);
}
}  // namespace

TEST(MixedBuilds, Hdf5GroupMissingADatasetOrFullOfNaNRunsAgain) {
  const fs::path dir = tempDir("h5");
  const Experiment e = loadExperiment(writeSweep(dir, "{sample_dt_s: 0.01, time_series_file: hdf5}").string());
  const fs::path out = dir / "out";
  runExperiment(e, options(out));
  // w_ss=0.2: one dataset deleted (through libhdf5 itself: H5Fopen, H5Ldelete, H5Fclose).
  { const TimeSeriesH5Reader loads((out / "time_series.h5").string()); }
  void* lib = loadedHdf5();
  ASSERT_NE(lib, nullptr);
  using Open = int64_t (*)(const char*, unsigned, int64_t);
  using Delete = int (*)(int64_t, const char*, int64_t);
  using Close = int (*)(int64_t);
  const auto open = reinterpret_cast<Open>(::dlsym(lib, "H5Fopen"));
  const auto del = reinterpret_cast<Delete>(::dlsym(lib, "H5Ldelete"));
  const auto close = reinterpret_cast<Close>(::dlsym(lib, "H5Fclose"));
  ASSERT_TRUE(open && del && close);
  const int64_t f = open((out / "time_series.h5").c_str(), 1u /* H5F_ACC_RDWR */, 0 /* H5P_DEFAULT */);
  ASSERT_GE(f, 0);
  EXPECT_GE(del(f, "w_ss=0.2/analytic/phi_deg", 0), 0);
  EXPECT_GE(del(f, "w_ss=0.4", 0), 0);  // its group only in the file of NaN below
  EXPECT_GE(close(f), 0);
  ::dlclose(lib);
  // w_ss=0.4: its series replaced by one of NaN (same key, same columns) in its own case file.
  {
    const TimeSeriesH5Reader r((out / "time_series.h5").string());
    const TimeSeries ts = r.read("w_ss=0.6", "analytic");
    TimeSeries nan;
    for (const std::string& n : ts.names()) nan.addColumn(n);
    nan.appendRow(std::vector<double>(ts.numColumns(), std::nan("")));
    TimeSeriesH5Writer w((dir / "nan.h5").string());
    std::string key;
    for (const ExperimentCase& c : e.cases)
      if (c.name == "w_ss=0.4") key = caseKey(c, false);
    w.write("w_ss=0.4", "w_ss=0.4", key, {{"trajectory.w_ss", "0.4"}}, "analytic", "full", nan);
    w.publish();
    fs::create_directories(out / "time_series.h5.d");
    fs::rename(dir / "nan.h5", out / "time_series.h5.d" / "w_ss=0.4.h5");
  }
  // Both files named as tailsim's in their manifests (else they are not read at all: the test
  // Hdf5Damaged.NeverCrashesResumeOrMerge): the groups themselves must be vetted.
  recordHashInManifest(out.string(), "time_series.h5", sha256OfFile((out / "time_series.h5").string()).value());
  recordHashInManifest((out / "time_series.h5.d").string(), "w_ss=0.4.h5",
                       sha256OfFile((out / "time_series.h5.d" / "w_ss=0.4.h5").string()).value());
  const RunStats s = runExperiment(e, options(out));
  EXPECT_EQ(s.ran, 2) << "a group missing a dataset or full of NaN was taken as finished";
  EXPECT_EQ(s.resumed, 2);
  const TimeSeriesH5Reader r((out / "time_series.h5").string());
  EXPECT_TRUE(r.read("w_ss=0.2", "analytic").has("phi_deg"));
  fs::remove_all(dir);
}
