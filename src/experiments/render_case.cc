#include "experiments/render_case.h"

#include <filesystem>

#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "mujoco_model/mjcf_generator.h"
#include "results/atomic_file.h"

namespace tailsim {

RenderStats renderCase(const ExperimentCase& c, const std::vector<RunResult>& runs, const std::string& out_dir,
                       const std::string& outline_label) {
  const RunResult* mj = nullptr;
  const RunResult* an = nullptr;
  for (const RunResult& r : runs) {
    if (r.summary.model == "mujoco") mj = &r;
    if (r.summary.model == "analytic") an = &r;
  }
  if (!mj && !an) throw std::runtime_error("case " + c.name + ": nothing to render (no model ran)");
  const TailTrajectory traj = c.trajectory();
  RenderInputs in;
  in.robot = &c.robot;
  in.trajectory = &traj;
  in.mujoco = mj ? &mj->series : &an->series;
  in.analytic = (mj && an && c.render.ghost) ? &an->series : nullptr;
  in.mjcf_xml = generateMjcf(c.robot, c.mujoco, c.effects);
  const ModelEntry* solid = findModel(mj ? "mujoco" : "analytic");
  const ModelEntry* outline = findModel("analytic");
  in.solid_label = solid ? solid->title : "MuJoCo";
  in.outline_label = !outline_label.empty() ? outline_label : outline ? outline->title : "analytic model";
  in.title = c.experiment + (c.name == "base" ? "" : " " + c.name);
  makeResultDir(out_dir);
  const std::string stem = (std::filesystem::path(out_dir) / caseDirName(c.name)).string();
  return renderVideo(in, c.render, stem + ".mp4", stem + ".png");
}

}  // namespace tailsim
