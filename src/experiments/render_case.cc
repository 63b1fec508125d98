#include "experiments/render_case.h"

#include <filesystem>

#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "models/mujoco/mjcf_generator.h"
#include "common/atomic_file.h"

namespace tailsim {

RenderStats renderCase(const ExperimentCase& c, const std::vector<RunResult>& runs, const std::string& out_dir,
                       const std::string& outline_label) {
  // The body: the run of the highest render rank; the outline (render.ghost): the run of rank 1
  // beside a higher one (ModelEntry::render_rank).
  const RunResult* solid = nullptr;
  const RunResult* outline = nullptr;
  const ModelEntry* solid_model = nullptr;
  const ModelEntry* outline_model = nullptr;
  for (const ModelEntry& m : modelRegistry())
    if (m.render_rank == 1 && !outline_model) outline_model = &m;
  for (const RunResult& r : runs) {
    const ModelEntry* e = findModel(r.summary.model);
    if (!e || e->render_rank <= 0) continue;
    if (!solid_model || e->render_rank > solid_model->render_rank) {
      solid = &r;
      solid_model = e;
    }
    if (e == outline_model) outline = &r;
  }
  if (!solid) throw std::runtime_error("case " + c.name + ": nothing to render (no model ran)");
  const TailTrajectory traj = c.trajectory();
  RenderInputs in;
  in.robot = &c.robot;
  in.trajectory = &traj;
  in.mujoco = &solid->series;
  in.analytic = (outline && outline != solid && c.render.ghost) ? &outline->series : nullptr;
  in.mjcf_xml = generateMjcf(c.robot, c.mujoco, c.effects);
  in.solid_label = solid_model->title;
  in.outline_label = !outline_label.empty() ? outline_label : outline_model ? outline_model->title : "analytic model";
  in.title = c.experiment + (c.name == "base" ? "" : " " + c.name);
  makeResultDir(out_dir);
  const std::string stem = (std::filesystem::path(out_dir) / caseDirName(c.name)).string();
  return renderVideo(in, c.render, stem + ".mp4", stem + ".png");
}

}  // namespace tailsim
