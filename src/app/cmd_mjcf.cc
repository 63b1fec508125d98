// `tailsim mjcf [EXPERIMENT.yaml | --links N] (--out FILE | --menagerie DIR)`: the MuJoCo model, as
// one file or as robot + scene (mjcf/README.md).
#include <cstdio>
#include <memory>
#include <set>
#include <stdexcept>

#include "app/commands.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/robot_model_cases.h"
#include "models/mujoco/mjcf_generator.h"
#include "common/atomic_file.h"
#include "common/number_text.h"
#include "common/sha256.h"
#include "common/work_limits.h"

namespace tailsim {

namespace {

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

// Refuses, before any file is written, a menagerie of more than limits::kMaxMenagerieModels models,
// with the number of models, files and bytes it would write.
void refuseLargeMenagerie(const std::string& exp_path, const std::vector<Experiment>& suite,
                          const std::vector<SuiteModel>& models) {
  if (models.size() <= static_cast<std::size_t>(limits::kMaxMenagerieModels)) return;
  std::size_t cases = 0;
  for (const Experiment& e : suite) cases += e.cases.size();
  const SuiteModel& m = models[0];
  const MenagerieFiles one = generateMenagerie(m.c->robot, m.c->mujoco, m.c->effects, "x");
  const double bytes = static_cast<double>(models.size()) * static_cast<double>(one.robot_xml.size() + one.scene_xml.size());
  throw ConfigError(exp_path + ":1:1: the " + std::to_string(cases) + " cases have " + std::to_string(models.size()) +
                    " distinct MuJoCo models: --menagerie would write " + std::to_string(2 * models.size()) +
                    " files (about " + formatG(bytes, 2) + " bytes), more than the limit of " +
                    std::to_string(limits::kMaxMenagerieModels) +
                    " models (docs/experiment-format.md \"Limits\"): pick one with --case NAME");
}

// `tailsim mjcf EXPERIMENT.yaml ...`: the models of an experiment's cases. Returns the exit code.
int writeExperimentMjcf(const std::string& exp_path, const std::string& only_case, const std::string& out,
                        const std::string& menagerie_dir) {
  const std::vector<Experiment> suite = loadExperimentSuite(exp_path);  // all errors before any work
  refuseRobotModels(suite, "mjcf");
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
    const bool to_stream = writeUserFile(out, models[0].xml, kGeneratedMjcfMarker);
    std::fprintf(to_stream ? stderr : stdout, "wrote %s (case %s)\n", out == "-" ? "the MJCF to stdout" : out.c_str(),
                 models[0].c->name.c_str());
    return kExitOk;
  }
  refuseLargeMenagerie(exp_path, suite, models);
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

struct MjcfArgs {
  int links = 1;
  std::string out, exp, case_name, menagerie;
};

int mjcfCommand(const MjcfArgs& a) {
  if (a.out.empty() && a.menagerie.empty()) {
    std::fprintf(stderr, "error: tailsim mjcf needs --out FILE or --menagerie DIR\nRun 'tailsim mjcf --help' for the options.\n");
    return kExitUsage;
  }
  if (!a.exp.empty()) return writeExperimentMjcf(a.exp, a.case_name, a.out, a.menagerie);
  if (!a.menagerie.empty()) {
    const std::vector<std::string> paths = writeMenagerieFiles(a.links, a.menagerie);
    std::printf("wrote %s + %s\n", paths[0].c_str(), paths[1].c_str());
    return kExitOk;
  }
  const bool to_stream = writeMjcfFile(a.links, a.out);
  // XML on stdout stays XML: the message goes to stderr when the model went to a stream.
  std::fprintf(to_stream ? stderr : stdout, "wrote %s\n", a.out == "-" ? "the MJCF to stdout" : a.out.c_str());
  return kExitOk;
}

}  // namespace

void addMjcfCommand(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<MjcfArgs>();
  auto* mjcf = app.add_subcommand("mjcf", "write the MuJoCo model (MJCF) of the paper robot or of an experiment's cases");
  auto* exp_opt = mjcf->add_option("experiment", a->exp, "experiment YAML: the models its cases simulate")
                      ->check(CLI::ExistingFile);
  mjcf->add_option("--links", a->links, "the paper robot with an n-link tail (1..6; default 1)")
      ->check(CLI::Range(1, 6))
      ->excludes(exp_opt);
  mjcf->add_option("--case", a->case_name, "only this case's model")->needs(exp_opt);
  auto* out_opt = mjcf->add_option("--out", a->out, "one self-contained .xml, the model tailsim simulates (- = stdout)")
                      ->check(nonEmptyPath());
  mjcf->add_option("--menagerie", a->menagerie,
                   "folder for the Menagerie form: tailsim_<name>.xml (robot) + scene_<name>.xml (mjcf/README.md)")
      ->excludes(out_opt)
      ->check(nonEmptyPath());
  mjcf->callback([a, &exit_code] { exit_code = mjcfCommand(*a); });
}

}  // namespace tailsim
