// What legs change (docs/your-robot.md): a user's MuJoCo robot with a generated 1..n-link tail,
// run articulated in MuJoCo (robot_import.h, attach_tail.h), against the three planar models run
// on the parameters derived from the same file: MuJoCo's rigid box, perfoot and analytic.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "models/mujoco/attach_tail.h"
#include "models/mujoco/robot_import.h"

namespace tailsim {

struct RobotTailChoice {
  double mass_fraction = 0.10;   // tail mass / robot mass
  double length_m = 0.0;         // <= 0: one body length, the derived l_F_m
  int links = 1;                 // identical links, the mass and length split evenly
  double thetadot_max_dps = 600; // Eq. 25 peak joint speed [deg/s]
  double stand_s = 2.0;          // standing with the tail before the stroke [s]
  double settle_after_s = 1.0;   // after the stroke [s]
};

struct ModelRow {
  std::string model;  // "mujoco (articulated)", "mujoco (rigid box)", "perfoot", "analytic"
  bool ok = true;
  bool not_run = false;  // a model that does not take this robot (3 feet: only the articulated run)
  double phi_net_deg = 0.0;
  // The MuJoCo rows' own estimate (phi_net_uncertainty_deg: NaN when their check run failed);
  // absent for the planar rows, which estimate none.
  std::optional<double> phi_net_uncertainty_deg;
  std::vector<std::string> warnings;  // and the error when !ok
};

struct RobotComparison {
  DerivedRobot robot;
  std::vector<TailLink> tail;
  ExperimentCase planar;         // the planar models' case (derived robot, tail, Eq. 25 stroke)
  ArticulatedRun articulated;
  std::vector<ModelRow> rows;
};

// The tail links of a choice for a derived robot.
std::vector<TailLink> tailFor(const DerivedRobot& r, const RobotTailChoice& c);

// Derives the robot, then runs the four models. Throws RobotImportError / MujocoError when the
// robot cannot be stood; a model that fails is a row with ok = false.
RobotComparison compareRobotModels(const RobotModelSpec& spec, const RobotTailChoice& choice);

// `tailsim robot FILE.yaml`: the planar robot of a YAML robot file or experiment (its first case),
// value by value with units. Throws ConfigError.
std::string describeYamlRobot(const std::string& path);

// A tailsim robot file (docs/experiment-format.md "Robot file") holding the derived parameters,
// mu_s = mu_d = the derived mu, and tails.1..6 from tailFor (the choice's mass and length split
// over n links): `tailsim robot FILE --write-robot OUT.yaml`, for experiments.
std::string derivedRobotFile(const DerivedRobot& r, const RobotTailChoice& c);
// Its first line starts with this: `tailsim robot --write-robot` replaces only a file that does.
inline constexpr const char* kDerivedRobotFileMarker = "# Written by `tailsim robot`";

// The comparison as a Markdown table plus each run's warnings; a MuJoCo row's phi_net with its
// "+- U" (docs/your-robot.md).
std::string describeComparison(const RobotComparison& c);

}  // namespace tailsim
