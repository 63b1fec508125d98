#include "experiments/robot_model_cases.h"

#include <map>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "experiments/robot_compare.h"
#include "models/mujoco/attach_tail.h"
#include "models/mujoco/robot_import.h"

namespace tailsim {

namespace {

// What a derivation depends on: the spec, every field.
std::string specKey(const RobotModelSpec& s) {
  nlohmann::json j = {{"file", s.file},   {"keyframe", s.keyframe}, {"joints", s.joint_angles_rad},
                      {"feet", s.feet},   {"mu", s.mu},             {"mount_body", s.mount.body},
                      {"mount_pos", s.mount.pos_m}, {"mount_yaw", s.mount.yaw_rad}, {"settle_s", s.settle_s},
                      {"legs", s.legs}};
  return j.dump();
}

// "file:line:col: key: " of the key an error is about, or of the nearest key above it that the file sets.
std::string where(const ExperimentCase& c, std::string key) {
  for (;;) {
    const auto it = c.robot_model_at.find(key);
    if (it != c.robot_model_at.end()) return it->second;
    const std::size_t dot = key.rfind('.');
    if (dot == std::string::npos) break;
    key.erase(dot);
  }
  const auto it = c.robot_model_at.find("robot");
  return it != c.robot_model_at.end() ? it->second : c.source_file + ": robot: ";
}

}  // namespace

void resolveRobotModels(Experiment& e) {
  std::map<std::string, std::shared_ptr<const DerivedRobot>> derived;
  for (ExperimentCase& c : e.cases) {
    if (!c.robot_model || c.robot_derived) continue;
    const std::string key = specKey(*c.robot_model);
    std::shared_ptr<const DerivedRobot>& d = derived[key];
    if (!d) {
      try {
        d = std::make_shared<const DerivedRobot>(deriveRobot(*c.robot_model));
      } catch (const RobotImportError& x) {
        throw ConfigError(where(c, x.key()) + x.what());
      } catch (const std::exception& x) {  // MuJoCo refused the file
        throw ConfigError(where(c, "robot.mjcf") + x.what());
      }
    }
    if (d->foot_count != 4)
      for (const std::string& model : c.models)
        if (model != "mujoco")
          throw ConfigError(where(c, "robot.mjcf") + "models: " + model + " cannot run this robot: " + threeFeetNote(*d) +
                            " (models: [mujoco])");
    c.robot.quadruped = d->quadruped;
    c.robot.friction.mu_s = c.robot.friction.mu_d = d->mu;
    c.robot.gravity_mps2 = d->gravity_mps2;
    if (c.robot_model_links > 0) {
      RobotTailChoice t;
      t.links = c.robot_model_links;
      c.robot.tail = tailFor(*d, t);
    }
    c.mujoco.body_height_m = c.robot.quadruped.com_height_m;
    try {
      validate(c.robot);
    } catch (const std::invalid_argument& x) {
      const std::string msg = x.what();
      const bool mount = msg.rfind("quadruped.d_Q2B_m", 0) == 0;
      throw ConfigError(where(c, mount ? "tail.mount.pos_m" : "robot.mjcf") + "the robot derived from " +
                        c.robot_model->file + ": " + msg +
                        (mount ? " (the tail base is in front of the COM: check tail.mount)" : ""));
    }
    c.robot_derived = d;
  }
}

void resolveRobotModels(std::vector<Experiment>& suite) {
  for (Experiment& e : suite) resolveRobotModels(e);
}

void refuseRobotModels(const std::vector<Experiment>& suite, const std::string& command) {
  for (const Experiment& e : suite)
    for (const ExperimentCase& c : e.cases)
      if (c.robot_model)
        throw ConfigError(where(c, "robot.mjcf") + "`tailsim " + command +
                          "` does not take a robot from its model file (its MuJoCo run is the articulated robot, on "
                          "the model's own settings): run the experiment with `tailsim run`");
}

std::string articulatedMjcf(const ExperimentCase& c) {
  if (!c.robot_derived) throw std::invalid_argument("articulatedMjcf: the robot was not derived");
  MujocoSettings s = c.mujoco;
  s.timestep_s = loadModelFromXml(c.robot_derived->model.xml)->opt.timestep;  // as runArticulated
  return attachTail(*c.robot_derived, c.robot_model->mount, c.robot.tail, s);
}

}  // namespace tailsim
