// The experiment loader's parts, one file each (docs/ARCHITECTURE.md): bounded YAML documents
// (yaml_file.cc), sweeps (sweep_grid.cc), robot files and built-in robots (robot_section.cc), a
// robot from its model file (robot_model_section.cc), the trajectory and pose (trajectory_reader.cc),
// the settings sections with checks across keys (case_sections.cc), one case (case_reader.cc).
// experiment_loader.cc expands the sweep grid and holds the entry points. Internal to the loader.
#pragma once

#include "experiments/experiment_config.h"
#include "experiments/yaml_reader.h"

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

namespace tailsim {
namespace loader {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Bounded YAML documents (yaml_file.cc)

// Offset of the first byte of `s` that is not part of valid UTF-8, or npos.
std::size_t invalidUtf8At(const std::string& s);
// The whole file, or a ConfigError naming it and the OS error.
std::string readFileBounded(const std::string& file);
// `text` as the YAML document of `file` (the name its errors carry), within the same bounds.
YAML::Node parseYamlText(const std::string* file, const std::string& text);
// The document of `*file`, read within kMaxYamlBytes and parsed within the same bounds.
YAML::Node parseYaml(const std::string* file);

// ---------------------------------------------------------------------------------------------
// Sweeps (sweep_grid.cc)

struct Sweep {
  std::string key;  // dotted key
  std::vector<SweepValue> values;
};

// One {sweep: [...]} or {range: [start, stop, step]} map at `key`, its values checked and listed.
Sweep parseSweep(const std::string* file, const YAML::Node& n, const std::string& key);
// Pass 1: every sweep in the document, in file order.
void collectSweeps(const std::string* file, const YAML::Node& n, const std::string& key, std::vector<Sweep>& out);

// ---------------------------------------------------------------------------------------------
// Robot files (robot_section.cc)

struct RobotFile {
  std::string file;  // absolute path
  RobotParams base;  // tail empty
  Origins origin;    // quadruped.*, friction.*, gravity_mps2
  std::map<int, std::vector<TailLink>> tails;  // tails.n: its n links (the same link, but for per-joint actuator keys)
  std::map<int, Origins> tail_origin;  // keys "tail link 1 <field>"
};

// A robot file read and validated: its quadruped, friction, gravity and every tails.<n>.
std::unique_ptr<RobotFile> readRobotFile(const std::string& abs);

// quadruped: the explicit numbers or the size form, into q (every key when `all`: a robot file).
void readQuadruped(const Reader& r, const Item& item, bool all, QuadrupedParams& q, Origins& origin);
// friction: mu_s and mu_d (required when `all`), the continuous law's thresholds when given.
void readFriction(const Reader& r, const Item& item, bool all, FrictionParams& fp, Origins& origin);
// One tail link {mass_kg, izz_kgm2, length_m, com_offset_m?}; origins under "tail link <i> ".
TailLink readLink(const Reader& r, const Item& item, int index, Origins& origin);
// tailsim::validate() of the robot, its message at the value that set the field.
void validateRobot(const RobotParams& p, const Origins& origin, const Loc& fallback);
// Masses within [kMinMassKg, kMaxMassKg] (docs/experiment-format.md "Limits"), at the value that set them.
void checkMasses(const RobotParams& p, const Origins& origin, const Loc& fallback);

// The friction keys of the continuous law (checked by requireContinuousThresholds).
extern const char* const kContinuousKeys[4];

// `p` made absolute (lexically normal).
std::string absolutePath(const std::string& p);
// `p` relative to the folder of base_file (or absolute).
std::string resolveRelative(const std::string& base_file, const std::string& p);
// A value without '/' and '.' names a built-in robot (`robot: paper`).
bool isBuiltinRobotName(const std::string& v);
// The file of built-in robot `name`, or a ConfigError at `at`.
std::string builtinRobotFile(const std::string& name, const Loc& at);

// ---------------------------------------------------------------------------------------------
// One load: the files it read and the robot files it parsed (each once)


struct Loader {
  std::vector<std::unique_ptr<std::string>> files;  // stable storage for Loc::file
  std::map<std::string, std::unique_ptr<RobotFile>> robots;

  const std::string* keep(const std::string& s) {
    files.push_back(std::make_unique<std::string>(s));
    return files.back().get();
  }
  const RobotFile& robot(const std::string& abs, const Loc& at) {
    auto f = robots.find(abs);
    if (f != robots.end()) return *f->second;
    std::error_code ec;
    if (!fs::is_regular_file(abs, ec)) fail(at, "robot file not found: " + abs);
    return *(robots[abs] = readRobotFile(abs));
  }
};

// ---------------------------------------------------------------------------------------------
// One case's parts

// robot: {mjcf: PATH, ...} into c.robot_model (robot_model_section.cc).
void readRobotModel(const Reader& r, const Item& item, const std::string& source, ExperimentCase& c);
// The trajectory section's keys (trajectory_reader.cc): split-cycle (the default family) and spline.
extern const std::vector<std::string> kSplitCycleKeys;
extern const std::vector<std::string> kSplineKeys;
// family: spline -- per joint a clamped cubic spline through equally spaced knots (trajectory_reader.cc).
std::vector<SplineParams> readSplineTrajectory(const Reader& r, const Item& item, const MapView& t, int n);
// family: split_cycle (Eqs. 20-23, or rule: eq25) for n joints (trajectory_reader.cc).
std::vector<SplitCycleParams> readTrajectory(const Reader& r, const Item& item, int n);
// pose: the joint angles, speeds and accelerations of kind: pose (trajectory_reader.cc).
PoseSpec readPose(const Reader& r, const Item& item, int n);
// The settings sections with checks across keys (case_sections.cc).
MujocoSettings readMujoco(const Reader& r, const Item& item);
OutputSettings readOutput(const Reader& r, const Item& item, double tail_end_s);
RenderSettings readRender(const Reader& r, const Item& item, double run_end_s);
// effects.friction: continuous needs the law's thresholds (case_sections.cc).
void requireContinuousThresholds(const Reader& r, const MapView& top, const ExperimentCase& c, const Origins& origin);
// A case whose work estimate exceeds a limit, refused at the key that set it (case_sections.cc).
void checkCaseWork(const Reader& r, const MapView& top, const ExperimentCase& c);
// Pass 2: one case, with the sweeps resolved by `r` (case_reader.cc).
ExperimentCase readCase(Loader& L, const Reader& r, const YAML::Node& doc, const std::string& source);

}  // namespace loader
}  // namespace tailsim
