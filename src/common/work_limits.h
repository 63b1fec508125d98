// Limits on the work one case may ask for, and on the inputs that set it (docs/experiment-format.md
// "Limits"). Each limit is declared here once: the loader refuses a case whose estimate
// (experiments/work_estimate.h) exceeds one, naming file:line:col of the key; the models and the
// renderer enforce the same numbers at run time, so a case built in code cannot hang or overflow.
#pragma once

namespace tailsim::limits {

// Work per model run of one case.
constexpr double kMaxRowsPerRun = 1e6;      // output rows (time-series samples) per model run
constexpr double kCsvBytesPerValue = 12.0;  // estimate of one CSV value ("%.9g" plus the separator)
constexpr double kMaxCsvBytesPerRun = 5e8;  // estimated CSV size per model run  [B]
constexpr double kMaxAnalyticSteps = 1e7;   // accepted analytic solver steps per run
constexpr double kMaxMujocoSteps = 1e7;     // mj_step calls per run (settling included)
constexpr double kMaxRenderFrames = 1e5;    // video frames per case (~55 min at 30 fps; hours of rendering)

// Worker threads of one run (--threads, tailsim.run(threads=...), merge --threads): far more than
// any machine's cores; beyond it a run only spends memory on stacks (8 MB each) and may not start.
constexpr int kMaxThreads = 1024;

// Work of a whole experiment (all cases, all models), so a legal file cannot ask for months of
// computing or terabytes of output.
constexpr double kMaxExperimentSteps = 1e10;  // analytic solver steps + mj_step calls, summed over the cases
constexpr double kMaxExperimentBytes = 1e11;  // estimated time-series output (100 GB), summed  [B]
// Rendering: frames x width x height x MSAA samples (1 without MSAA), summed over the cases. OSMesa
// shades about 2e7 such samples a second on one core here (an 8192 x 8192 frame with msaa 4 took
// 16 s), so the limit is about 14 hours of rendering.
constexpr double kMaxExperimentRenderSamples = 1e12;

// `tailsim mjcf EXPERIMENT --menagerie DIR`: distinct MuJoCo models written (two files each, a
// robot and a scene, about 7 kB together for the paper robot). A sweep of a robot dimension has as
// many models as cases (up to 10^5); a few hundred is more than anyone opens one by one.
constexpr int kMaxMenagerieModels = 200;

// Work of an optimize file (every seed and Pareto point): analytic model runs, and the
// joint-direction patterns `directions: enumerate` searches (2^n for an n-link tail).
constexpr double kMaxOptimizeRuns = 1e8;
// ... and their analytic solver steps (runs x the base's steps a run): about three days of one core at
// 2.5 us a step. A base with a 1e-7 s fixed step (6e6 steps, 3.4 s a run) made 20,000 runs 19 hours.
constexpr double kMaxOptimizeSteps = 1e11;
constexpr int kMaxEnumeratedLinks = 12;  // 4096 patterns
// The optimize section's counts (design/optimize_config.h; the schema of `tailsim schema`).
constexpr int kMaxOptimizeKnots = 12;
constexpr int kMaxOptimizeIslands = 64;
constexpr int kMaxOptimizePopulation = 1000;
constexpr int kMaxOptimizeGenerations = 10000;
constexpr int kMaxOptimizeRestarts = 50;
constexpr int kMaxOptimizeLocalRestarts = 200;
constexpr int kMaxKeptDirectionsLog2 = 12;  // directions_kept <= 2^12 (and <= 2^n)
constexpr int kMaxPolishEvaluations = 100000;
constexpr int kMaxOptimizeSeeds = 20;
constexpr int kMaxParetoPoints = 20;

// Inputs (physical ranges; the paper's cases lie well inside them).
constexpr double kMinDT_s = 1e-3;              // tail motion duration dT  [s]
constexpr double kMinWss = 0.01, kMaxWss = 0.99;  // acceleration share w_ss of dT
constexpr double kMaxAbsDthetaDeg = 3600.0;    // |dtheta| (ten turns)  [deg]
constexpr double kMaxAbsTheta0Deg = 360.0;     // |theta0|, and every spline knot  [deg]
constexpr int kMaxSplineKnots = 64;            // knots per joint of a spline trajectory (start and end included)
constexpr double kMinMassKg = 1e-3;            // quadruped and tail link masses  [kg]
constexpr double kMaxMassKg = 1e4;

// Run-end checks (RunSummary::at_rest and warnings).
constexpr double kAtRestPhidotDps = 0.1;        // |phi_dot| at the end below this: at rest  [deg/s]
constexpr double kAtRestSpeedMps = 1e-3;        // body speed at the end below this: at rest  [m/s]
// MuJoCo's step schedule (docs/mujoco-model.md "Step schedule"): after the tail's motion ends, the
// body counts as resting once every speed below stays under these for kRestHoldS; the run then
// steps at mujoco.rest_step_factor times timestep_s, and the check run stops there.
constexpr double kRestAngularRadps = 1e-4;  // quadruped body |angular velocity|  [rad/s]
constexpr double kRestSpeedMps = 1e-5;      // quadruped body |linear velocity|  [m/s]
constexpr double kRestJointRadps = 1e-3;    // every tail joint |theta_dot|  [rad/s]
constexpr double kRestHoldS = 0.02;         // [s]
constexpr double kMaxPaperSpuriousTurnDeg = 10.0;  // paper coupling: turn its momentum error alone causes  [deg]
constexpr double kMaxTrackingErrorDeg = 1.0;       // MuJoCo: max servo tracking error above this warns  [deg]
// A tail joint's peak speed above this warns (every model): 100 turns a second, beyond any tail
// motor, where a result describes a stroke no robot makes (the loader's limits on dtheta and dT
// allow 2 x 3600 deg / 1 ms = 7.2e6 deg/s).
constexpr double kMaxJointSpeedDps = 36000.0;  // [deg/s]
// MuJoCo contact fidelity (docs/mujoco-model.md "Contact fidelity"): share of the run's steps with
// no foot loaded, and the peak summed foot normal force in units of the weight m g; above these warns.
constexpr double kMaxAirborneFraction = 0.2;        // [1]
constexpr double kMaxPeakNormalForceOverMg = 30.0;  // [1]
// MuJoCo near fall (docs/mujoco-model.md "Tipping over"): a run that stands but whose body tilted
// beyond this share of mujoco.max_tilt_deg rocked on two feet; whether it falls depends on the
// contact and the step, so its phi_net is marked uncertain. Paper cases: at most 0.32 deg of 5;
// a robot the converged reference sees fall: down to 1.5 deg at the defaults.
constexpr double kNearFallTiltShare = 0.25;  // [1]

}  // namespace tailsim::limits
