// Hostile text in design files (kind optimize, kind maneuver) and in every gnuplot script tailsim
// writes: a name is data, never a command; the design files accept exactly the names an experiment
// file accepts.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "design/maneuver.h"
#include "design/optimize_config.h"
#include "design/optimize_experiment.h"
#include "experiments/accuracy_study.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "plotting/accuracy_plot.h"
#include "plotting/gnuplot.h"
#include "plotting/plots.h"
#include "plotting/result_folder.h"
#include "settings/optimize_section.h"
#include "settings/trajectory_section.h"
#include "scratch_dir.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = TAILSIM_SOURCE_DIR;

class DesignInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "tailsim_design_inputs_XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
    std::ofstream(dir_ / "base.yaml") << "name: b\nrobot: " << kSourceDir
                                       << "/configs/robots/paper_quadruped.yaml\ntail: {links: 1}\n"
                                          "trajectory: {rule: eq25, thetadot_max_dps: 600, w_ss: 0.25}\nmodels: [analytic]\n";
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& rel, const std::string& text) {
    const fs::path p = dir_ / rel;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  // A YAML double-quoted scalar holding `s` (every byte outside printable ASCII as \xHH or \uHHHH).
  static std::string yamlQuoted(const std::string& s) {
    std::string out = "\"";
    char buf[8];
    for (const char c : s) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '"' || c == '\\') {
        out += '\\';
        out += c;
      } else if (u < 0x20 || u == 0x7f) {
        std::snprintf(buf, sizeof buf, "\\x%02x", u);
        out += buf;
      } else {
        out += c;
      }
    }
    return out + "\"";
  }
  std::string optimizeFile(const std::string& name, const std::string& extra = "") {
    return write("opt.yaml", "name: " + yamlQuoted(name) +
                                 "\nkind: optimize\nbase: base.yaml\noptimize:\n  family: split_cycle\n"
                                 "  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none}\n"
                                 "  islands: 1\n  population: 6\n  generations: 2\n  polish: none\n  seeds: [1]\n  pareto_points: 2\n"
                                 "  mujoco_check: false\n" + extra);
  }
  std::string maneuverFile(const std::string& name, const std::string& extra = "  mujoco: false\n") {
    return write("m.yaml", "name: " + yamlQuoted(name) + "\nkind: maneuver\nbase: base.yaml\nmaneuver:\n  heading_deg: 20\n" +
                               extra);
  }
  template <class Load>
  static std::string errorOf(const Load& load) {
    try {
      load();
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(no error)";
  }
  // Every file named PWNED under dir_ (where gnuplot's working directory and the folders above it are).
  std::vector<std::string> pwned() const {
    std::vector<std::string> found;
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      if (e.path().filename().string().find("PWNED") != std::string::npos) found.push_back(e.path().string());
    return found;
  }
  fs::path dir_;
};

using NoInputTextReachesAnInterpreterUnescaped = DesignInputs;
using UnboundedWorkRefusedAtLoad = DesignInputs;
using Smaller = DesignInputs;

// Names that would run a command, start a new gnuplot line or end the string early if pasted into
// a script between quotes.
std::vector<std::string> hostileTexts() {
  return {"Rone's stroke",
          "x' . system('touch PWNED1') . '",
          "x\" . system(\"touch PWNED2\") . \"",
          "`touch PWNED3`",
          "$(touch PWNED4)",
          "@PWNED5",
          "a\\",
          "back\\slash\\' . system('touch PWNED6') . '",
          "line\nsystem('touch PWNED7')",
          "cr\rsystem('touch PWNED8')",
          std::string("nul\0' . system('touch PWNED9') . '", 35),
          "tab\there ~{/Symbol f}_{net}^2 & more # not a comment",
          "UTF-8: φ_net Δθ 転回 \xF0\x9F\x90\x88",
          std::string(10000, '\'') + "system('touch PWNED10')",
          std::string(10240, 'x')};
}

// gpQuote is what every script quotes text with: gnuplot reads back exactly the text (control
// characters other than a line break as spaces) and runs nothing of it.
TEST_F(NoInputTextReachesAnInterpreterUnescaped, GpQuoteRoundTripsHostileText) {
  std::string body = "set print 'echo.txt'\n";
  std::string want;
  for (const std::string& s : hostileTexts()) {
    body += "print " + gpQuote(s) + "\n";
    std::string shown = s;
    for (char& c : shown)
      if ((static_cast<unsigned char>(c) < 0x20 && c != '\n') || c == 0x7f) c = ' ';
    want += shown + "\n";
  }
  body += "unset print\nset title " + gpQuote(hostileTexts()[1]) + " noenhanced\nplot x title " +
          gpQuote(hostileTexts()[8]) + "\n";
  GnuplotFigure fig;
  fig.stem = "hostile";
  fig.body = body;
  ASSERT_NO_THROW(renderFigure((dir_ / "plots").string(), fig));
  std::ifstream in(dir_ / "plots/echo.txt", std::ios::binary);
  std::stringstream got;
  got << in.rdbuf();
  EXPECT_EQ(got.str(), want);
  EXPECT_EQ(pwned(), std::vector<std::string>());
}

// A design file's name is checked by the experiment loader's rule: what an experiment refuses
// (a line break, NUL, a slash) a design file refuses at the key, and the rest loads.
TEST_F(NoInputTextReachesAnInterpreterUnescaped, DesignFilesTakeTheExperimentNameRule) {
  for (const std::string& s : hostileTexts()) {
    const bool ok = experimentNameProblem(s).empty();
    std::string opt_err, man_err;
    try {
      loadOptimizeSpec(optimizeFile(s));
    } catch (const ConfigError& e) {
      opt_err = e.what();
    }
    try {
      loadManeuverSpec(maneuverFile(s));
    } catch (const ConfigError& e) {
      man_err = e.what();
    }
    if (ok) {
      EXPECT_EQ(opt_err, "") << s;
      EXPECT_EQ(man_err, "") << s;
    } else {
      EXPECT_NE(opt_err.find("opt.yaml:1:7: name: must be a folder name"), std::string::npos) << opt_err;
      EXPECT_NE(man_err.find("m.yaml:1:7: name: must be a folder name"), std::string::npos) << man_err;
    }
  }
  EXPECT_FALSE(experimentNameProblem("Rone's stroke") != "");
  EXPECT_NE(experimentNameProblem("line\nbreak"), "");
  EXPECT_NE(experimentNameProblem(std::string("nul\0x", 5)), "");
}

// optimize and maneuver with names made to escape their plot scripts finish, write their plots and
// summary.json, and run no command.
TEST_F(NoInputTextReachesAnInterpreterUnescaped, DesignPlotsRunNoCommand) {
  const std::vector<std::string> names = {"Rone's stroke", "x' . system('touch PWNED1') . '",
                                          "''`touch PWNED3` $(touch PWNED4) @PWNED5 ''''"};
  int k = 0;
  for (const std::string& n : names) {
    const std::string out = (dir_ / ("o" + std::to_string(k++))).string();
    ASSERT_NO_THROW(runOptimize(loadOptimizeSpec(optimizeFile(n)), out, false)) << n;
    EXPECT_TRUE(fs::is_regular_file(out + "/summary.json")) << n;
    EXPECT_TRUE(fs::is_regular_file(out + "/plots/history.png")) << n;
    const std::string mout = (dir_ / ("m" + std::to_string(k++))).string();
    ASSERT_NO_THROW(runManeuver(loadManeuverSpec(maneuverFile(n)), mout, false, false)) << n;
    EXPECT_TRUE(fs::is_regular_file(mout + "/summary.json")) << n;
    EXPECT_TRUE(fs::is_regular_file(mout + "/plots/heading.png")) << n;
  }
  EXPECT_EQ(pwned(), std::vector<std::string>());
}

// Names gnuplot would open as a shell pipe (`set output '|cmd'`, `plot '<cmd'`) or read as a
// datablock (`plot '$name'`) if a file name made from them began a script's file name. From a
// result folder's plots/, `cd ..; cd ..` reaches dir_.
std::vector<std::string> pipeNames() {
  return {"|cd ..; cd ..; touch PWNED_PIPE; cat > PWNED_SINK; true ", "<cd ..; cd ..; touch PWNED_LT; echo 0 0 ",
          "$PWNED_DATABLOCK"};
}

// Every file name in the .gp scripts under `dir` (what `set output` and `plot`/`every`/`using`
// take) as written, for names not starting with "./" ('' is gnuplot's "the previous file").
std::vector<std::string> unprefixedFileNames(const fs::path& dir) {
  std::vector<std::string> bad;
  const std::regex output(R"(set output '([^']*)')"), data(R"('([^']*)' (using|every) )");
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.path().extension() != ".gp") continue;
    std::ifstream in(e.path());
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string gp = ss.str();
    int names = 0;
    for (const std::regex* re : {&output, &data})
      for (auto it = std::sregex_iterator(gp.begin(), gp.end(), *re); it != std::sregex_iterator(); ++it, ++names)
        if (!(*it)[1].str().empty() && (*it)[1].str().rfind("./", 0) != 0) bad.push_back(e.path().filename().string() + ": " + (*it)[1].str());
    if (names == 0) bad.push_back(e.path().filename().string() + ": no file name found (the check is out of date)");
  }
  return bad;
}

// A name starting with '|', '<' or '$' is refused at the name key by the one rule every file
// kind uses (experiment, suite member, optimize, maneuver).
TEST_F(NoInputTextReachesAnInterpreterUnescaped, PipeAndDatablockNamesAreRefusedAtLoad) {
  for (const std::string& n : pipeNames()) {
    EXPECT_NE(experimentNameProblem(n), "") << n;
    EXPECT_NE(errorOf([&] { loadOptimizeSpec(optimizeFile(n)); }).find("opt.yaml:1:7: name: must be a folder name"),
              std::string::npos) << n;
    EXPECT_NE(errorOf([&] { loadManeuverSpec(maneuverFile(n)); }).find("m.yaml:1:7: name: must be a folder name"),
              std::string::npos) << n;
    const std::string exp = write("e.yaml", "name: " + yamlQuoted(n) + "\nrobot: paper\ntail: {links: 1}\n"
                                            "trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.5}\n");
    EXPECT_NE(errorOf([&] { loadExperiment(exp); }).find("e.yaml:1:7: name: must be a folder name"), std::string::npos)
        << n;
    write("suite.yaml", "experiments: [e.yaml]\n");
    EXPECT_NE(errorOf([&] { loadExperimentSuite((dir_ / "suite.yaml").string()); }).find("name: must be a folder name"),
              std::string::npos) << n;
  }
  EXPECT_EQ(experimentNameProblem("a|b <c $d"), "");  // only the first character matters to gnuplot
}

// Whatever a name holds, no file name in a script tailsim writes starts with it: `run --plot` and
// `plot` (plotExperiment: one case and a sweep), optimize, maneuver and accuracy write file names
// that start with "./", so gnuplot opens no pipe and reads no datablock (the loader's rule bypassed:
// the results renamed after loading).
TEST_F(NoInputTextReachesAnInterpreterUnescaped, ScriptFileNamesStartWithDotSlash) {
  const std::string one = write("one.yaml", "name: one\nrobot: paper\ntail: {links: 1}\n"
                                            "trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.5}\n"
                                            "models: [analytic]\n");
  const std::string sweep = write("sweep.yaml", "name: sweep\nrobot: paper\ntail: {links: 1}\n"
                                                "trajectory: {theta0_deg: 45, dtheta_deg: {sweep: [-90, 90]}, dT_s: 0.25, "
                                                "w_ss: {sweep: [0.25, 0.5]}}\nmodels: [analytic]\n");
  for (const std::string& f : {one, sweep}) {
    RunOptions o;
    o.out_dir = (dir_ / fs::path(f).stem()).string();
    o.progress = false;
    o.threads = 1;
    runExperiment(loadExperiment(f), o);
    ExperimentResults r = loadResults(o.out_dir);
    for (const std::string& n : pipeNames()) {
      r.name = n;
      EXPECT_NO_THROW(plotExperiment(r)) << n;
    }
  }
  EXPECT_NO_THROW(runOptimize(loadOptimizeSpec(optimizeFile("opt")), (dir_ / "o").string(), false));
  EXPECT_NO_THROW(runManeuver(loadManeuverSpec(maneuverFile("man")), (dir_ / "m").string(), false, false));
  AccuracyStudy st;
  st.case_name = pipeNames()[0];
  for (int i = 1; i <= 3; ++i) {
    AccuracyRow row;
    row.model = "analytic";
    row.family = "adaptive";
    row.value = std::pow(10.0, -i);
    row.is_default = i == 2;
    row.err_phi_net_deg = std::pow(10.0, -2 * i);
    row.wall_s = 1e-3 * i;
    st.rows.push_back(row);
  }
  fs::create_directories(dir_ / "acc");
  EXPECT_NO_THROW(plotAccuracy({st, st}, (dir_ / "acc").string()));
  // The names' own data files hold PWNED in their names: look for what the shell would create.
  std::vector<std::string> made;
  for (const auto& e : fs::recursive_directory_iterator(dir_))
    for (const char* f : {"PWNED_PIPE", "PWNED_SINK", "PWNED_LT"})
      if (e.path().filename() == f) made.push_back(e.path().string());
  EXPECT_EQ(made, std::vector<std::string>());
  EXPECT_EQ(unprefixedFileNames(dir_), std::vector<std::string>());
}

// optimize writes best.yaml as the experiment <name>_best: an optimize name leaves room for the
// suffix (refused at the key past 95 bytes), and best.yaml of the longest name loads back.
TEST_F(NoInputTextReachesAnInterpreterUnescaped, OptimizeNamesLeaveRoomForTheBestExperiment) {
  const std::size_t longest = kMaxNameChars - std::string(kBestNameSuffix).size();
  const std::string e = errorOf([&] { loadOptimizeSpec(optimizeFile(std::string(longest + 1, 'n'))); });
  EXPECT_NE(e.find("opt.yaml:1:7: name: must be a folder name: 1 to 95 characters"), std::string::npos) << e;
  EXPECT_EQ(errorOf([&] { loadManeuverSpec(maneuverFile(std::string(kMaxNameChars, 'n'))); }), "(no error)");
  const OptimizeReport rep = runOptimize(loadOptimizeSpec(optimizeFile(std::string(longest, 'n'))),
                                         (dir_ / "o").string(), false);
  EXPECT_EQ(rep.best_yaml_error, "");
  EXPECT_EQ(loadExperiment((dir_ / "o/best.yaml").string()).name, std::string(longest, 'n') + "_best");
}

// A result folder read back by `plot` and `report` is input too: an experiment name, case folder
// or model name in it that the loader or the runner would never write is refused naming the file,
// before any figure is drawn (summary.json's name once ran a shell command through `plot` and wrote
// '../../EVIL_phi.gp' outside the folder).
TEST_F(NoInputTextReachesAnInterpreterUnescaped, ResultFolderNamesAreCheckedWhenReadBack) {
  const std::string f = write("ok.yaml", "name: ok\nrobot: paper\ntail: {links: 1}\n"
                                         "trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.5}\n"
                                         "models: [analytic]\n");
  RunOptions o;
  o.out_dir = (dir_ / "base").string();
  o.progress = false;
  o.threads = 1;
  runExperiment(loadExperiment(f), o);
  auto edited = [&](const std::string& folder, const std::function<void(nlohmann::json&)>& edit) {
    const fs::path d = dir_ / "sub" / folder;
    fs::create_directories(d.parent_path());
    fs::copy(dir_ / "base", d, fs::copy_options::recursive);
    nlohmann::json s;
    {
      std::ifstream in(d / "summary.json");
      in >> s;
    }
    edit(s);
    std::ofstream(d / "summary.json") << s.dump(1);
    return d.string();
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {edited("pipe", [](nlohmann::json& s) { s["experiment"] = "|cd ..; cd ..; cd ..; touch PWNED_SUMMARY; true "; }),
       "summary.json: experiment name '|cd ..; cd ..; cd ..; touch PWNED_SUMMARY; true ' must be a folder name"},
      {edited("evil", [](nlohmann::json& s) { s["experiment"] = "../../EVIL"; }),
       "summary.json: experiment name '../../EVIL' must be a folder name"},
      {edited("dir", [](nlohmann::json& s) { s["cases"][0]["dir"] = "../../elsewhere"; }),
       "summary.json: case 'base' has the folder '../../elsewhere', which tailsim never writes"},
      {edited("model", [](nlohmann::json& s) {
         s["cases"][0]["runs"]["../../../EVILMODEL"] = s["cases"][0]["runs"]["analytic"];
       }),
       "case 'base' has a run of the model '../../../EVILMODEL', a name that must be a folder name"}};
  for (const auto& [d, want] : cases) {
    std::string err = "(no error)";
    try {
      plotResults(d);
    } catch (const std::exception& e) {
      err = e.what();
    }
    EXPECT_NE(err.find(want), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(fs::path(d) / "plots")) << d;
  }
  std::vector<std::string> outside;
  for (const auto& e : fs::recursive_directory_iterator(dir_))
    if (e.path().filename().string().find("EVIL") != std::string::npos ||
        e.path().filename().string().find("PWNED") != std::string::npos)
      outside.push_back(e.path().string());
  EXPECT_EQ(outside, std::vector<std::string>());
  EXPECT_NO_THROW(plotResults((dir_ / "base").string()));  // the folder as written plots
}

// directions: enumerate searches 2^n patterns: a tail of more than 12 links is refused at the key
// (n = 13 took minutes and n = 20 2.9 GB; n = 32 shifted 1 << 32 and searched one pattern).
TEST_F(UnboundedWorkRefusedAtLoad, EnumeratedDirectionsAreBounded) {
  for (const int n : {13, 20, 32}) {
    std::string links;
    for (int i = 0; i < n; ++i) links += (i ? ", " : "") + std::string("{mass_kg: 0.1, izz_kgm2: 0.0001, length_m: 0.05}");
    std::ofstream(dir_ / "base.yaml") << "name: b\nrobot: paper\ntail: {custom: [" << links
                                       << "]}\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nmodels: [analytic]\n";
    const std::string e = errorOf([&] { loadOptimizeSpec(optimizeFile("o", "  directions: enumerate\n")); });
    EXPECT_NE(e.find("opt.yaml:14:15: optimize.directions: enumerate would search 2^" + std::to_string(n)), std::string::npos)
        << e;
    EXPECT_NE(e.find("more than 2^12 = 4096"), std::string::npos) << e;
  }
}

// The analytic runs of a whole optimize file are estimated at load; the documented maxima (about
// 1e11 runs) are refused with the estimate, a small file loads.
TEST_F(UnboundedWorkRefusedAtLoad, OptimizeRunsAreEstimatedAndBounded) {
  const std::string big = write("big.yaml", "name: big\nkind: optimize\nbase: base.yaml\noptimize:\n  family: split_cycle\n"
                                            "  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none}\n"
                                            "  islands: 64\n  population: 1000\n  generations: 10000\n");
  const std::string e = errorOf([&] { loadOptimizeSpec(big); });
  EXPECT_NE(e.find("big.yaml:5:3: optimize: the search would run the analytic model about 640064202 times"), std::string::npos) << e;
  EXPECT_NE(e.find("more than the limit 100000000 ("), std::string::npos) << e;
  const OptimizeSpec ok = loadOptimizeSpec(optimizeFile("o"));
  // 2 (start) + 1 island x 6 x (2 generations + 1): 20 runs per search, x (1 seed + 2 Pareto points).
  EXPECT_EQ(optimizeRunEstimate(ok), 60.0);
}

// A run's cost is the base's: with a 1e-7 s fixed analytic step (6e6 steps, 3.4 s a run) 20,200 runs
// (about 19 hours) were accepted and started; the steps are estimated (runs x steps a run) and bounded.
TEST_F(UnboundedWorkRefusedAtLoad, OptimizeStepsAreEstimatedAndBounded) {
  std::ofstream(dir_ / "slow.yaml") << "name: s\nrobot: " << kSourceDir
                                     << "/configs/robots/paper_quadruped.yaml\ntail: {links: 1}\n"
                                        "trajectory: {rule: eq25, thetadot_max_dps: 600, w_ss: 0.25}\nmodels: [analytic]\n"
                                        "analytic: {solver: fixed, fixed_dt_s: 1e-7}\n";
  const std::string slow = write("slow_opt.yaml", "name: slow\nkind: optimize\nbase: slow.yaml\noptimize:\n"
                                                  "  family: split_cycle\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none}\n"
                                                  "  islands: 2\n  population: 100\n  generations: 100\n  seeds: [1]\n");
  const std::string e = errorOf([&] { loadOptimizeSpec(slow); });
  EXPECT_NE(e.find("slow_opt.yaml:5:3: optimize: the search would take about "), std::string::npos) << e;
  EXPECT_NE(e.find(" analytic solver steps (about "), std::string::npos) << e;
  EXPECT_NE(e.find(" runs x at least "), std::string::npos) << e;
  EXPECT_NE(e.find("more than the limit 1e+11"), std::string::npos) << e;
  // The same search on the default (adaptive) step loads.
  EXPECT_EQ(errorOf([&] {
              loadOptimizeSpec(write("fast_opt.yaml", "name: fast\nkind: optimize\nbase: base.yaml\noptimize:\n"
                                                      "  family: split_cycle\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none}\n"
                                                      "  islands: 2\n  population: 100\n  generations: 100\n  seeds: [1]\n"));
            }),
            "(no error)");
}

// The longest MuJoCo run of a maneuver (the closed loop, max_strokes cycles) is estimated at load.
TEST_F(UnboundedWorkRefusedAtLoad, ManeuverRunsAreEstimatedAndBounded) {
  const std::string e = errorOf([&] {
    loadManeuverSpec(maneuverFile("m", "  max_strokes: 1000\n  return_dT_s: 10\n  rest_s: 10\n  mujoco: true\n"));
  });
  EXPECT_NE(e.find("m.yaml:6:16: maneuver.max_strokes: the MuJoCo closed loop may run"), std::string::npos) << e;
  EXPECT_NE(e.find("= 30400.5 s: "), std::string::npos) << e;
  EXPECT_EQ(errorOf([&] { loadManeuverSpec(maneuverFile("m", "  mujoco: true\n")); }), "(no error)");
}

// Limits no stroke can keep are refused at load (they ran the whole search and exited 3,
// "limits VIOLATED"); the shipped limits load (ShippedConfigs.OptimizeFilesLoad).
TEST_F(UnboundedWorkRefusedAtLoad, ImpossibleOptimizeLimitsAreRefused) {
  auto file = [&](const std::string& limits) {
    return write("lim.yaml", "name: l\nkind: optimize\nbase: base.yaml\noptimize:\n  family: split_cycle\n  limits: " + limits +
                                 "\n  seeds: [1]\n");
  };
  std::string e = errorOf([&] { loadOptimizeSpec(file("{theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: 1e-9}")); });
  EXPECT_NE(e.find("lim.yaml:6:11: optimize.limits: no stroke keeps these limits"), std::string::npos) << e;
  e = errorOf([&] { loadOptimizeSpec(file("{theta_deg: [-90, 90], thetadot_max_dps: 1, dT_s: [0.05, 0.1], torque_max_Nm: none}")); });
  EXPECT_NE(e.find("peaks at 20 deg/s (limit 1)"), std::string::npos) << e;
  e = errorOf([&] { loadOptimizeSpec(file("{theta_deg: [10, 10.5], thetadot_max_dps: 600, torque_max_Nm: none}")); });
  EXPECT_NE(e.find("needs a range of 1 deg (have 0.5)"), std::string::npos) << e;
  EXPECT_EQ(errorOf([&] { loadOptimizeSpec(file("{theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: 1}")); }),
            "(no error)");
}

// (b) A maneuver's strokes are checked as the experiment loader checks a trajectory, at the key.
TEST_F(Smaller, ManeuverValuesAreCheckedAtLoadWithLocation) {
  std::string e = errorOf([&] { loadManeuverSpec(maneuverFile("m", "  min_scale: 0.000001\n  mujoco: false\n")); });
  EXPECT_NE(e.find("m.yaml:6:14: maneuver.min_scale: the shortest stroke"), std::string::npos) << e;
  e = errorOf([&] { loadManeuverSpec(maneuverFile("m", "  stroke_w_ss: 0.001\n")); });
  EXPECT_NE(e.find("m.yaml:6:16: maneuver.stroke_w_ss: must lie in [0.01, 0.99]"), std::string::npos) << e;
  e = errorOf([&] { loadManeuverSpec(maneuverFile("m", "  return_dT_s: 0.0000001\n")); });
  EXPECT_NE(e.find("m.yaml:6:16: maneuver.return_dT_s: must be at least 0.001 s"), std::string::npos) << e;
}

// (e) A plan longer than max_strokes is an error at max_strokes (file:line:col), and the folder gets
// nothing (it was left with an empty plots/).
TEST_F(Smaller, ManeuverPlanOverMaxStrokesNamesTheKey) {
  const std::string f = write("m.yaml", "name: m\nkind: maneuver\nbase: base.yaml\nmaneuver:\n  heading_deg: 170\n"
                                        "  mujoco: false\n  max_strokes: 1\n");
  const fs::path out = dir_ / "mo";
  const std::string e = errorOf([&] { runManeuver(loadManeuverSpec(f), out.string(), false, false); });
  EXPECT_EQ(e.rfind(f + ":7:16: maneuver.max_strokes: the plan needs ", 0), 0u) << e;
  EXPECT_NE(e.find("more than max_strokes = 1"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(out / "plots"));
}

// (d) A write error in optimize (here best_perfoot.csv cannot replace a folder of that name) ends
// the command with the error; it is not reported as a failure of the per-foot model.
TEST_F(Smaller, OptimizeWriteErrorIsNotAModelFailure) {
  const fs::path out = dir_ / "res";
  fs::create_directories(out / "best_perfoot.csv");
  std::ofstream(out / "best_perfoot.csv" / "keep") << "x";
  try {
    runOptimize(loadOptimizeSpec(optimizeFile("o")), out.string(), false);
    ADD_FAILURE() << "optimize finished without the write error";
  } catch (const ConfigError& e) {
    ADD_FAILURE() << e.what();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("best_perfoot.csv"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

// (f) Empty and comment-only design files: an error at line 1 in tailsim's words.
TEST_F(Smaller, EmptyDesignFilesAreRefusedWithLocation) {
  for (const std::string& text : {std::string(""), std::string("# only a comment\n\n")}) {
    const std::string f = write("empty.yaml", text);
    for (const std::string& e : {errorOf([&] { loadOptimizeSpec(f); }), errorOf([&] { loadManeuverSpec(f); }),
                                 errorOf([&] { loadExperiment(f); })})
      EXPECT_EQ(e.rfind(f + ":1:1: the file holds no YAML value (it is empty or only comments)", 0), 0u) << e;
  }
}

// A base path the file system cannot hold (a name over NAME_MAX, found by the fuzzer): an error at
// the base key, not an uncaught filesystem_error.
TEST_F(Smaller, BasePathTooLongForTheFileSystemIsAConfigError) {
  const std::string base = "base: " + std::string(5000, 'b') + ".yaml\n";
  const std::string o = write("long_o.yaml", "name: o\nkind: optimize\n" + base + "optimize:\n  family: split_cycle\n");
  const std::string m = write("long_m.yaml", "name: m\nkind: maneuver\n" + base + "maneuver:\n  heading_deg: 20\n");
  const std::string eo = errorOf([&] { loadOptimizeSpec(o); }), em = errorOf([&] { loadManeuverSpec(m); });
  EXPECT_EQ(eo.rfind(o + ":3:7: base: no such experiment file: ", 0), 0u) << eo;
  EXPECT_EQ(em.rfind(m + ":3:7: base: no such experiment file: ", 0), 0u) << em;
}

// The optimize section's declaration (settings/optimize_section.h) is what `tailsim schema` and
// docs/experiment-format.md show as defaults: they must be the ones the optimiser applies.
TEST(OptimizeSectionDeclaration, DefaultsAreTheOptimizersDefaults) {
  const OptimizeSection d;
  const OptimizerSettings os;
  const OptimizeSpec spec;
  const StrokeSpace sp;
  EXPECT_EQ(d.algorithm, os.algorithm);
  EXPECT_EQ(d.islands, os.islands);
  EXPECT_EQ(d.population, os.population);
  EXPECT_EQ(d.generations, os.generations);
  EXPECT_EQ(d.restarts, os.restarts);
  EXPECT_EQ(d.restart_growth, os.restart_growth);
  EXPECT_EQ(d.refine_generations, os.refine_generations);
  EXPECT_EQ(d.local_restarts, os.local_restarts);
  EXPECT_EQ(d.local_step, os.local_step);
  EXPECT_EQ(d.directions == "enumerate", os.enumerate_directions);
  EXPECT_EQ(d.directions_kept, os.directions_kept);
  EXPECT_EQ(d.polish, os.polish);
  EXPECT_EQ(d.polish_evaluations, os.polish_evaluations);
  EXPECT_EQ(d.max_runs, os.max_runs);
  EXPECT_EQ(d.pareto_points, spec.pareto_points);
  EXPECT_EQ(d.mujoco_check, spec.mujoco_check);
  EXPECT_EQ(d.min_turn_deg, spec.min_turn_deg);
  EXPECT_EQ(d.knots, sp.knots);
  EXPECT_EQ(d.objective, "phi_net");
  EXPECT_EQ(spec.problem.objective, StrokeObjective::kPhiNet);
  EXPECT_EQ(d.limits.end == "start", sp.limits.end == StrokeEnd::kAtStart);
  EXPECT_EQ(d.limits.dT_s[0], sp.limits.dT_min_s);
  EXPECT_EQ(d.limits.dT_s[1], sp.limits.dT_max_s);
  EXPECT_EQ(d.limits.w_ss[0], sp.limits.w_ss_min);
  EXPECT_EQ(d.limits.w_ss[1], sp.limits.w_ss_max);
  EXPECT_EQ(d.limits.start_delay_s, sp.limits.t0_max_s);
}

// An unknown key of the optimize section and of its limits lists the declared keys, in their order.
TEST(OptimizeSectionDeclaration, UnknownKeysListTheDeclaredKeys) {
  const fs::path dir = fs::temp_directory_path() / ("tailsim_optsec_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "base.yaml") << "name: b\nrobot: paper\ntail: {links: 1}\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n";
  auto message = [&](const std::string& section) {
    std::ofstream(dir / "opt.yaml") << "name: o\nkind: optimize\nbase: base.yaml\noptimize:\n" << section;
    try {
      loadOptimizeSpec((dir / "opt.yaml").string());
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto allowed = [](const std::vector<std::string>& keys) {
    std::string s;
    for (const std::string& k : keys) s += (s.empty() ? "" : ", ") + k;
    return "(allowed here: " + s + ")";
  };
  EXPECT_NE(message("  family: spline\n  limits: {}\n  isalnds: 2\n").find(allowed(settings::declaredKeys<OptimizeSection>())),
            std::string::npos);
  EXPECT_NE(message("  family: spline\n  limits: {dt_s: [0.1, 0.2]}\n").find(allowed(settings::declaredKeys<OptimizeLimitsSection>())),
            std::string::npos);
  EXPECT_NE(message("  family: spline\n  objective: {qty: phi_net}\n  limits: {}\n")
                .find(allowed(settings::declaredKeys<OptimizeObjectiveSection>())),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tailsim

namespace tailsim {
using testing::ScratchDir;

// Writes DIR/name; returns its path.
std::string writeIn(const ScratchDir& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return (dir / name).string();
}

// A design file whose base experiment takes its robot from a model file: refused at the base line
// with the way that works (before: after the limits, "cannot copy into the result folder: the
// robot was not derived", with a lock and an empty plots/ left in --out).
TEST(DesignInputsRobot, DesignCommandsNameTheWayToAnImportedRobot) {
  const ScratchDir t("design_model_base");
  const auto write = [&](const std::string& name, const std::string& text) { return writeIn(t, name, text); };
  write("box.xml", "<mujoco/>\n");  // the loader reads the keys only: nothing is derived
  write("base.yaml", "name: b\nrobot: {mjcf: box.xml}\ntail: {mount: {pos_m: [-0.25, 0, 0]}, links: 1}\n"
                     "trajectory: {rule: eq25, thetadot_max_dps: 600}\n");
  const std::string opt = write(
      "opt.yaml",
      "name: o\nkind: optimize\nbase: base.yaml\noptimize:\n  family: split_cycle\n  objective: phi_net\n"
      "  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none, dT_s: [0.05, 1.0], start_delay_s: 0.1}\n");
  const std::string man = write("man.yaml", "name: m\nkind: maneuver\nbase: base.yaml\nmaneuver: {heading_deg: 90}\n");
  for (const auto& [file, load] : std::vector<std::pair<std::string, std::function<void()>>>{
           {opt, [&] { loadOptimizeSpec(opt); }}, {man, [&] { loadManeuverSpec(man); }}}) {
    try {
      load();
      ADD_FAILURE() << file << " was taken";
    } catch (const ConfigError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(file + ":3:7: base: the base experiment takes its robot from a model file", 0), 0u) << m;
      EXPECT_NE(m.find("tailsim robot MODEL --write-robot ROBOT.yaml"), std::string::npos) << m;
    }
  }
}


// A limit in the design file that differs from the robot file's is noted (a start_here preset
// copied for one's own robot kept the paper's limits over the robot's 6 N m, silently); one that
// equals it, or that the robot file does not give, is not.
TEST(DesignInputsRobot, ADesignLimitReplacingTheRobotFilesIsNoted) {
  const ScratchDir t("design_overrides");
  const auto write = [&](const std::string& name, const std::string& text) { return writeIn(t, name, text); };
  write("robot.yaml", "quadruped: {mass_kg: 8, size_m: [0.45, 0.25, 0.18]}\nfriction: {mu_s: 0.5, mu_d: 0.45}\n"
                      "gravity_mps2: 9.81\ntails:\n  2: {mass_kg: 0.25, izz_kgm2: 4.7e-4, length_m: 0.15, torque_max_Nm: 6, "
                      "thetadot_max_dps: 500, theta_min_deg: -80, theta_max_deg: 80}\n");
  write("base.yaml", "name: b\nrobot: robot.yaml\ntail: {links: 2}\ntrajectory: {rule: eq25, thetadot_max_dps: 500, w_ss: 0.25}\n");
  const auto spec = [&](const std::string& limits) {
    return loadOptimizeSpec(write("o.yaml", "name: o\nkind: optimize\nbase: base.yaml\noptimize:\n  family: split_cycle\n"
                                            "  objective: phi_net\n  limits: " + limits + "\n"));
  };
  const OptimizeSpec over = spec("{theta_deg: [-90, 90], thetadot_max_dps: 500, torque_max_Nm: none}");
  ASSERT_EQ(over.limit_overrides.size(), 4u);
  EXPECT_NE(over.limit_overrides[0].find("joint 1 theta_deg: [-90, 90] deg from "), std::string::npos) << over.limit_overrides[0];
  EXPECT_NE(over.limit_overrides[0].find("o.yaml replaces the robot file's [-80, 80] deg"), std::string::npos);
  EXPECT_NE(over.limit_overrides[1].find("joint 1 torque_max_Nm: none from "), std::string::npos) << over.limit_overrides[1];
  EXPECT_NE(over.limit_overrides[1].find("replaces the robot file's 6 N m"), std::string::npos);
  EXPECT_TRUE(spec("{}").limit_overrides.empty());
  EXPECT_TRUE(spec("{thetadot_max_dps: 500, torque_max_Nm: 6}").limit_overrides.empty());
}


// A base that is a folder, or a design file (the optimize file itself), is named as such at the
// base key (before: "no such experiment file", or "run it with tailsim optimize" without a line).
TEST(DesignInputsRobot, ABaseThatIsAFolderOrADesignFileIsNamedAtItsKey) {
  const ScratchDir t("design_base_kinds");
  const auto write = [&](const std::string& name, const std::string& text) { return writeIn(t, name, text); };
  fs::create_directories(t / "afolder");
  const std::string head = "kind: optimize\noptimize: {family: split_cycle, objective: phi_net, limits: {}}\n";
  const std::string folder = write("folder.yaml", "name: a\nbase: afolder\n" + head);
  const std::string self = write("self.yaml", "name: b\nbase: self.yaml\n" + head);
  for (const auto& [file, want] : {std::make_pair(folder, "afolder is a folder: base names a one-case experiment file"),
                                   std::make_pair(self, "self.yaml is a kind: optimize file: base names a one-case")}) {
    try {
      loadOptimizeSpec(file);
      ADD_FAILURE() << file;
    } catch (const ConfigError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(file + ":2:7: base: ", 0), 0u) << m;
      EXPECT_NE(m.find(want), std::string::npos) << m;
    }
  }
}


// A maneuver's fast stroke beyond the robot file's actuator limits is refused at its key (an outside
// review ran a 95 N m stroke on a 6 N m robot with no warning); within them it loads.
TEST(DesignInputsRobot, AManeuverStrokeBeyondTheRobotsLimitsIsRefused) {
  const ScratchDir t("design_maneuver_limits");
  const auto write = [&](const std::string& name, const std::string& text) { return writeIn(t, name, text); };
  write("robot.yaml", "quadruped: {mass_kg: 8, size_m: [0.45, 0.25, 0.18]}\nfriction: {mu_s: 0.5, mu_d: 0.45}\n"
                      "gravity_mps2: 9.81\ntails:\n  2: {mass_kg: 0.25, izz_kgm2: 4.7e-4, length_m: 0.15, torque_max_Nm: 6, "
                      "thetadot_max_dps: 2000, theta_min_deg: -80, theta_max_deg: 80}\n");
  write("base.yaml", "name: b\nrobot: robot.yaml\ntail: {links: 2}\ntrajectory: {rule: eq25, thetadot_max_dps: 500, w_ss: 0.25}\n"
                     "models: [analytic]\n");
  const std::string fast = write("fast.yaml", "name: m\nkind: maneuver\nbase: base.yaml\n"
                                              "maneuver: {heading_deg: 20, stroke_deg: 120, stroke_dT_s: 0.08, mujoco: false}\n");
  try {
    loadManeuverSpec(fast);
    ADD_FAILURE() << "a stroke over the robot's 6 N m was taken";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(fast + ":4:", 0), 0u) << m;
    EXPECT_NE(m.find("over its 6 N m at joint 1 (the robot file's tail entry"), std::string::npos) << m;
  }
  EXPECT_NO_THROW(loadManeuverSpec(write("slow.yaml", "name: m\nkind: maneuver\nbase: base.yaml\n"
                                                      "maneuver: {heading_deg: 20, stroke_deg: 120, stroke_dT_s: 0.6, mujoco: false}\n")));
}

}  // namespace tailsim
