// `tailsim render EXPERIMENT.yaml --out DIR`: headless MP4 + PNG of each case.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "app/commands.h"
#include "experiments/experiment_loader.h"
#include "experiments/robot_model_cases.h"
#include "experiments/experiment_runner.h"
#include "experiments/render_case.h"

namespace tailsim {
namespace fs = std::filesystem;

void addRenderCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string exp_path, case_name, out = "renders";
  };
  auto a = std::make_shared<Args>();
  auto* render = app.add_subcommand("render", "render each case of an experiment to MP4 + PNG (headless)");
  render->add_option("experiment", a->exp_path, "experiment YAML")->required()->check(CLI::ExistingFile);
  render->add_option("--case", a->case_name, "render only this case");
  render->add_option("--out", a->out, "output folder (default: renders/)")->check(nonEmptyPath());
  render->callback([a, &exit_code] {
    const std::vector<Experiment> suite = loadExperimentSuite(a->exp_path);
    refuseRobotModels(suite, "render");  // the articulated robot's videos are not drawn yet
    requireCase(suite, a->exp_path, a->case_name);
    for (const Experiment& e : suite) {
      const fs::path dir = fs::path(a->out) / e.name;
      for (ExperimentCase c : e.cases) {
        if (!a->case_name.empty() && c.name != a->case_name) continue;
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
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
