// tailsim robot FILE [--keyframe K] [--joint NAME=DEG ...] [--feet A,B,C,D] [--mount-body B]
//                    [--mount-pos X,Y,Z] [--mount-yaw-deg Y] [--mu MU]
//                    [--compare [--tail-mass-frac F] [--tail-length-m L] [--links N] [--stroke-dps W]]
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "app/commands.h"
#include "experiments/robot_compare.h"
#include "common/atomic_file.h"
#include "models/mujoco/robot_import.h"
#include "common/units.h"

namespace tailsim {
namespace {

struct RobotOptions {
  std::string file, keyframe, mount_body;
  std::vector<std::string> joints, feet;
  std::vector<double> mount_pos;
  double mount_yaw_deg = 0.0, mu = -1.0, settle_s = 1.0;
  bool compare = false;
  std::string write_robot;
  std::string legs = "servos";
  RobotTailChoice tail;
};

// The subcommand's options, into o.
void addRobotOptions(CLI::App* cmd, RobotOptions& o) {
  cmd->add_option("file", o.file,
                  "the robot's MJCF (or URDF) file, its scene file, or a YAML robot file or experiment")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--keyframe", o.keyframe, "stance: this keyframe (default: the model's `home`)");
  cmd->add_option("--joint", o.joints, "stance: NAME=DEG, a joint angle in degrees (repeat)");
  cmd->add_option("--feet", o.feet, "the foot geoms (default: those touching the floor after standing)")
      ->delimiter(',');
  cmd->add_option("--mount-body", o.mount_body, "tail mount body (default: the root body)");
  cmd->add_option("--mount-pos", o.mount_pos, "tail base X,Y,Z in the mount body's frame [m]")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--mount-yaw-deg", o.mount_yaw_deg, "forward = the mount body's x turned by this about z [deg]");
  cmd->add_option("--mu", o.mu, "foot friction (default: from the foot contacts)");
  cmd->add_option("--legs", o.legs,
                  "--compare: the articulated robot's legs: servos (the model's actuators) or locked (joint equalities)")
      ->check(CLI::IsMember({"servos", "locked"}))
      ->capture_default_str();
  cmd->add_option("--settle-s", o.settle_s, "standing time before measuring [s]")
      ->check(CLI::Validator([](std::string& v) {  // CLI::Range lets nan through
        const double x = std::strtod(v.c_str(), nullptr);
        return x >= 0.1 && x <= 10.0 ? std::string() : std::string("from 0.1 to 10 s");
      }, "[0.1, 10]"));
  cmd->add_flag("--compare", o.compare,
                "also run the four models with a tail: MuJoCo articulated, MuJoCo rigid box, perfoot, analytic");
  cmd->add_option("--write-robot", o.write_robot,
                  "write a tailsim robot file of the derived values (tails.1..6 from the --tail-* options) for experiments");
  cmd->add_option("--tail-mass-frac", o.tail.mass_fraction, "--compare: tail mass / robot mass")
      ->check(CLI::Range(0.001, 1.0))
      ->capture_default_str();
  cmd->add_option("--tail-length-m", o.tail.length_m, "--compare: tail length (default: l_F, one body length) [m]");
  cmd->add_option("--links", o.tail.links, "--compare: tail links")->check(CLI::Range(1, 6))->capture_default_str();
  cmd->add_option("--stroke-dps", o.tail.thetadot_max_dps, "--compare: Eq. 25 peak joint speed [deg/s]")
      ->check(CLI::Range(1.0, 1e5))
      ->capture_default_str();
}

// The robot-model keys the options give (as an experiment's robot: {mjcf: ...} would).
RobotModelSpec robotSpec(const RobotOptions& o) {
  RobotModelSpec spec;
  spec.file = o.file;
  spec.keyframe = o.keyframe;
  for (const std::string& j : o.joints) {
    const std::size_t eq = j.find('=');
    double deg = 0.0;
    char extra = 0;
    if (eq == std::string::npos || eq == 0 || std::sscanf(j.c_str() + eq + 1, "%lf%c", &deg, &extra) != 1 ||
        !std::isfinite(deg))
      throw RobotImportError("--joint " + j + ": expected NAME=DEG (e.g. LF_HFE=23)");
    spec.joint_angles_rad[j.substr(0, eq)] = units::radians(deg);
  }
  spec.feet = o.feet;
  spec.mu = o.mu;
  spec.settle_s = o.settle_s;
  spec.legs = o.legs;
  spec.mount.body = o.mount_body;
  if (o.mount_pos.size() == 3) spec.mount.pos_m = {o.mount_pos[0], o.mount_pos[1], o.mount_pos[2]};
  spec.mount.yaw_rad = units::radians(o.mount_yaw_deg);
  return spec;
}

// A YAML robot file or experiment described; else the model stood (and compared with --compare),
// its derived values printed (and written with --write-robot).
void runRobot(const RobotOptions& o) {
  const std::string ext = o.file.size() >= 5 ? o.file.substr(o.file.rfind('.') == std::string::npos ? 0 : o.file.rfind('.')) : "";
  if (ext == ".yaml" || ext == ".yml") {
    std::fputs(describeYamlRobot(o.file).c_str(), stdout);
    return;
  }
  const RobotModelSpec spec = robotSpec(o);
  if (o.compare) {
    const RobotComparison c = compareRobotModels(spec, o.tail);
    std::fputs(describeDerivedRobot(c.robot).c_str(), stdout);
    std::fputs(("\n" + describeComparison(c)).c_str(), stdout);
    if (!o.write_robot.empty() && !writeUserFile(o.write_robot, derivedRobotFile(c.robot, o.tail), kDerivedRobotFileMarker))
      std::printf("wrote %s\n", o.write_robot.c_str());
  } else {
    const DerivedRobot r = deriveRobot(spec);
    std::fputs(describeDerivedRobot(r).c_str(), stdout);
    if (!o.write_robot.empty()) {
      if (!writeUserFile(o.write_robot, derivedRobotFile(r, o.tail), kDerivedRobotFileMarker))
        std::printf("wrote %s\n", o.write_robot.c_str());
    }
  }
}

}  // namespace

void addRobotCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<RobotOptions>();
  CLI::App* cmd = app.add_subcommand(
      "robot", "stand a MuJoCo model (MJCF or URDF) and print the planar models' parameters derived from it");
  addRobotOptions(cmd, *o);
  cmd->callback([o, &exit_code] {
    try {
      runRobot(*o);
      exit_code = 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      exit_code = 1;
    }
  });
}

}  // namespace tailsim
