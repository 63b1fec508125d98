// `tailsim accuracy EXPERIMENT.yaml --out DIR`: work-precision study of both models' solver settings.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands.h"
#include "experiments/accuracy_study.h"
#include "experiments/experiment_loader.h"
#include "experiments/robot_model_cases.h"
#include "plotting/accuracy_plot.h"

namespace tailsim {

void addAccuracyCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string exp_path, out;
    bool quick = false, no_mujoco = false;
    int repeats = 3;
  };
  auto a = std::make_shared<Args>();
  auto* accuracy = app.add_subcommand("accuracy", "work-precision study of both models' solver settings");
  accuracy->add_option("experiment", a->exp_path, "experiment YAML (every simulate case is studied)")
      ->required()->check(CLI::ExistingFile);
  accuracy->add_option("--out", a->out, "output folder")->required()->check(nonEmptyPath());
  accuracy->add_option("--repeats", a->repeats, "runs per setting; wall time is their median")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  accuracy->add_flag("--quick", a->quick, "a reduced grid");
  accuracy->add_flag("--no-mujoco", a->no_mujoco, "analytic model only");
  accuracy->callback([a, &exit_code] {
    const Experiment e = loadExperiment(a->exp_path);
    refuseRobotModels({e}, "accuracy");
    std::filesystem::create_directories(a->out);
    checkAccuracyTables(a->out);
    AccuracyOptions ao;
    ao.repeats = a->repeats;
    ao.quick = a->quick;
    ao.mujoco = !a->no_mujoco;
    const auto studies = runAccuracyStudy(e, ao);
    writeAccuracyTables(studies, a->out);
    for (const std::string& png : plotAccuracy(studies, a->out)) std::printf("%s\n", png.c_str());
    std::printf("%s/accuracy.md\n%s/accuracy.csv\n", a->out.c_str(), a->out.c_str());
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
