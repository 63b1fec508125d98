// Cases whose robot is given by its MuJoCo model file (`robot: {mjcf: PATH, ...}`,
// docs/your-robot.md "Experiments"): the loader reads and checks the keys without MuJoCo; this
// derives the robot, once per experiment and distinct model spec, before any case runs.
#pragma once

#include <string>
#include <vector>

#include "experiments/experiment_loader.h"

namespace tailsim {

// For every case with robot_model and no robot_derived: stands the robot (deriveRobot), then sets
// robot.quadruped, the friction (mu_s = mu_d = the derived mu), gravity, a `tail: {links: n}` tail
// (n links sharing 10 % of the robot's mass and one body length l_F, tailFor), the MuJoCo body
// height and robot_derived. Cases of one experiment with the same spec share one derivation.
// Throws ConfigError naming the experiment file, line and key (robot.mjcf, robot.stance,
// robot.feet, tail.mount.body, ...) when the model cannot be loaded or stood.
void resolveRobotModels(std::vector<Experiment>& suite);
void resolveRobotModels(Experiment& e);

// Commands that change the MuJoCo settings or need the rigid box (trust, accuracy, mjcf) refuse a
// robot from its model file: ConfigError at its robot.mjcf, naming the command.
void refuseRobotModels(const std::vector<Experiment>& suite, const std::string& command);

// The MJCF the articulated run simulates (the robot with the tail attached), for the result folder.
std::string articulatedMjcf(const ExperimentCase& c);

}  // namespace tailsim
