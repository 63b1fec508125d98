// The MuJoCo contact model ("the ADAMS model" of the paper, Sec. 3.2): the quadruped standing on
// four feet with soft MuJoCo contacts, the tail following its split-cycle trajectory under PD
// servos. Writes the time-series columns of docs/ARCHITECTURE.md. See docs/mujoco-model.md.
#pragma once

#include <functional>

#include <mujoco/mujoco.h>

#include "mujoco_model/mujoco_settings.h"
#include "results/output_settings.h"
#include "results/time_series.h"
#include "robot/robot_params.h"
#include "robot/scene_effects.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

// Called once per output sample, just before the step that starts at the sample time: d->time,
// d->qpos, d->qvel are that state (derived fields such as xpos are one step old: mj_forward a
// copy of d if you need them). For tests and replay recording.
using MujocoSampleObserver = std::function<void(double t_s, const mjModel* m, const mjData* d)>;

// Runs t = 0 .. duration (output.duration_s, or trajectory.endTime() + output.settle_s) after a
// settling pre-roll of settings.settle_s with the tail held at theta(0). Samples on
// t_k = k * output.sample_dt_s. Throws std::invalid_argument on bad input (before any work);
// a run that goes unstable (any MuJoCo warning, NaN) returns summary.ok = false with the reason
// and the rows up to that point.
RunResult simulateMujoco(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
                         const Effects& effects, const OutputSettings& output,
                         const MujocoSampleObserver& observer = nullptr);

}  // namespace tailsim
