// The MuJoCo contact model ("the ADAMS model" of the paper, Sec. 3.2): the quadruped standing on
// four feet with soft MuJoCo contacts, the tail following its split-cycle trajectory under PD
// servos. Writes the time-series columns of docs/ARCHITECTURE.md. See docs/mujoco-model.md.
#pragma once

#include <functional>
#include <memory>

#include <mujoco/mujoco.h>

#include "models/mujoco/mujoco_settings.h"
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

// Called once per output sample with the same state as MujocoSampleObserver plus the body's
// unwrapped yaw phi (the phi_deg column, in radians): a trajectory decided while the run goes
// (maneuvers: controllers/heading_controller.h) replaces `reference` (the tail's current
// reference trajectory, absolute times) and returns true; false keeps it. The new reference takes
// effect from the next step; it should continue the old one at t_s (no step in theta_ref).
using MujocoTrajectoryHook =
    std::function<bool(double t_s, double phi_rad, const mjModel* m, const mjData* d, TailTrajectory& reference)>;

// The settled initial states of the MuJoCo models of one run. Every case starts with
// the same pre-roll (settings.settle_s with the tail held at theta(0)); cases that share the model
// (the generated MJCF), the settle-relevant settings and the tail's reference at t = 0 share its
// end state, so it is simulated once and copied. The copy is the whole MuJoCo state the next step
// reads (qpos, qvel, act, ctrl, applied forces, the solver's warm start, the run-time foot friction)
// plus the standing monitor's record: a run from the cache is bit-for-bit the run without it
// (tested). Thread safe; holds at most `max_entries` states (a few hundred bytes each), beyond that
// new models are settled every time. Pre-rolls that fail or produce MuJoCo messages are not kept.
class MujocoSettleCache {
 public:
  explicit MujocoSettleCache(std::size_t max_entries = 4096);
  ~MujocoSettleCache();
  MujocoSettleCache(const MujocoSettleCache&) = delete;
  MujocoSettleCache& operator=(const MujocoSettleCache&) = delete;
  long hits() const;    // runs that started from a cached state
  long misses() const;  // pre-rolls simulated
  long settleSteps() const;  // MuJoCo steps spent in pre-rolls (deterministic work count)
  struct Impl;  // mujoco_simulation.cc
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// Runs t = 0 .. duration (output.duration_s, or trajectory.endTime() + output.settle_s) after a
// settling pre-roll of settings.settle_s with the tail held at theta(0). Samples on
// t_k = k * output.sample_dt_s. Throws std::invalid_argument on bad input (before any work);
// a run that goes unstable (any MuJoCo warning, NaN) returns summary.ok = false with the reason
// and the rows up to that point. `settle_cache`: optional, shared by the cases of a run (above).
RunResult simulateMujoco(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
                         const Effects& effects, const OutputSettings& output,
                         const MujocoSampleObserver& observer = nullptr, MujocoSettleCache* settle_cache = nullptr,
                         const MujocoTrajectoryHook& hook = nullptr);

}  // namespace tailsim
