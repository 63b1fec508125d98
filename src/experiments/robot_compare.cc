#include "experiments/robot_compare.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "experiments/experiment_loader.h"
#include "experiments/model_registry.h"
#include "experiments/robot_model_cases.h"
#include "experiments/yaml_file.h"
#include "common/units.h"

#include <yaml-cpp/yaml.h>

namespace tailsim {

namespace {
std::string f3(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}
// A run as a row of the comparison: the error first among the warnings.
ModelRow rowOf(const std::string& title, const RunSummary& r) {
  ModelRow row{title, r.ok, false, r.phi_net_deg, std::nullopt, r.warnings};
  if (const auto u = r.extra.find("phi_net_uncertainty_deg"); u != r.extra.end()) row.phi_net_uncertainty_deg = u->second;
  if (!r.ok) row.warnings.insert(row.warnings.begin(), r.error);
  return row;
}

// A row's phi_net: "6.123", a MuJoCo row with its estimate "6.123 +- 0.050", with a failed check run
// "6.123 +- n/a (check run failed)"; "(uncertain)" after it when a warning says so.
std::string phiCell(const ModelRow& r) {
  if (r.not_run) return "not run";
  if (!r.ok) return "failed";
  std::string t = f3(r.phi_net_deg);
  if (r.phi_net_uncertainty_deg)
    t += std::isfinite(*r.phi_net_uncertainty_deg) ? " +- " + f3(*r.phi_net_uncertainty_deg)
                                                   : std::string(" +- n/a (check run failed)");
  for (const std::string& w : r.warnings)
    if (w.rfind(kUncertainWarning, 0) == 0) return t + " (uncertain)";
  return t;
}

}  // namespace

std::vector<TailLink> tailFor(const DerivedRobot& r, const RobotTailChoice& c) {
  const double L = c.length_m > 0.0 ? c.length_m : r.quadruped.l_F_m;
  const int n = std::max(1, c.links);
  const double m = c.mass_fraction * r.quadruped.mass_kg / n, l = L / n;
  // Each link a uniform slender rod about its COM: m l^2 / 12.
  return std::vector<TailLink>(static_cast<std::size_t>(n), TailLink{m, m * l * l / 12.0, l, 0.5 * l});
}

RobotComparison compareRobotModels(const RobotModelSpec& spec, const RobotTailChoice& choice) {
  RobotComparison c;
  c.robot = deriveRobot(spec);
  c.tail = tailFor(c.robot, choice);
  const int n = static_cast<int>(c.tail.size());

  ExperimentCase& k = c.planar;
  k.experiment = "robot";
  k.name = "base";
  k.robot.quadruped = c.robot.quadruped;
  k.robot.tail = c.tail;
  k.robot.friction.mu_s = k.robot.friction.mu_d = c.robot.mu;
  k.robot.gravity_mps2 = c.robot.gravity_mps2;
  for (int i = 0; i < n; ++i)
    k.joints.push_back(equalPeakSpeedParams(n, units::radians(choice.thetadot_max_dps), 0.25));  // Eq. (25)
  k.mujoco.body_height_m = k.robot.quadruped.com_height_m;
  k.output.settle_s = choice.settle_after_s;

  const RunResult articulated = simulateArticulated(c.robot, spec.mount, c.tail, k.trajectory(), k.mujoco,
                                                    choice.stand_s, choice.settle_after_s, 0.0, "mujoco",
                                                    &c.articulated);
  ModelRow art = rowOf(c.robot.legs_locked ? "mujoco (articulated, legs locked)" : "mujoco (articulated)",
                       articulated.summary);
  const ArticulatedRun& a = c.articulated;
  if (a.trim.rounds > 0)
    art.warnings.push_back("legs' set-points trimmed for the tail's weight in " + std::to_string(a.trim.rounds) +
                           " rounds of " + f3(kTrimRoundS) + " s (moved up to " + f3(a.trim.max_offset_deg) +
                           " deg; tilt from the stance after trimming " + f3(a.trim.end_tilt_deg) + " deg)");
  art.warnings.push_back("tilt (absolute / from the stance): stance " + f3(a.stance_tilt_deg) + " deg; after standing " +
                         f3(choice.stand_s) + " s with the tail " + f3(a.stand_end_tilt_deg) + " / " +
                         f3(a.stand_end_rel_tilt_deg) + " deg (at most " + f3(a.stand_max_tilt_deg) + " / " +
                         f3(a.stand_max_rel_tilt_deg) + "); during the stroke at most " + f3(a.max_tilt_deg) + " / " +
                         f3(a.max_rel_tilt_deg) + " deg; " + std::to_string(a.feet_in_contact) + " feet on the floor");
  c.rows.push_back(art);
  if (c.robot.foot_count != 4) {  // the other models take 4 feet: one row says why they did not run
    ModelRow skipped;
    skipped.model = "mujoco (rigid box), perfoot, analytic";
    skipped.ok = false;
    skipped.not_run = true;
    skipped.warnings.push_back("not run: " + threeFeetNote(c.robot));
    c.rows.push_back(skipped);
    return c;
  }
  for (const char* name : {"mujoco", "perfoot", "analytic"}) {
    const ModelEntry* e = findModel(name);
    if (!e) continue;
    k.models = {name};
    const RunResult res = e->run(k, nullptr);
    c.rows.push_back(rowOf(std::string(name) == "mujoco" ? "mujoco (rigid box)" : name, res.summary));
  }
  return c;
}

std::string derivedRobotFile(const DerivedRobot& r, const RobotTailChoice& c) {
  auto g = [](double v) {  // the shortest text that reads back as v
    char b[40];
    for (int prec = 6; prec <= 17; ++prec) {
      std::snprintf(b, sizeof b, "%.*g", prec, v);
      if (std::strtod(b, nullptr) == v) break;
    }
    return std::string(b);
  };
  const QuadrupedParams& q = r.quadruped;
  std::string t = std::string(kDerivedRobotFileMarker) + " from " + r.model.source + "\n# stance: " + r.stance +
                  "\n# feet (FL, FR, RR, RL):";
  for (const std::string& f : r.feet) t += " " + f;
  t += "\n# tail base: body '" + r.mount_body + "' (d_Q2B_m); docs/your-robot.md\n";
  t += "quadruped:\n  mass_kg: " + g(q.mass_kg) + "\n  izz_kgm2: " + g(q.izz_kgm2) + "\n  d_Q2C_m: " + g(q.d_Q2C_m) +
       "\n  d_Q2B_m: " + g(q.d_Q2B_m) + "\n  l_F_m: " + g(q.l_F_m) + "\n  w_F_m: " + g(q.w_F_m) +
       "\n  com_height_m: " + g(q.com_height_m) + "\n";
  t += "friction: {mu_s: " + g(r.mu) + ", mu_d: " + g(r.mu) + "}\n";
  t += "gravity_mps2: " + g(r.gravity_mps2) + "\n";
  RobotTailChoice k = c;
  t += "# tails.n: the link of an n-link tail of " + g(100 * c.mass_fraction) + " % of the robot's mass, " +
       (c.length_m > 0 ? g(c.length_m) + " m" : std::string("one body length (l_F)")) + " in all\ntails:\n";
  for (int n = 1; n <= 6; ++n) {
    k.links = n;
    const TailLink l = tailFor(r, k).front();
    t += "  " + std::to_string(n) + ": {mass_kg: " + g(l.mass_kg) + ", izz_kgm2: " + g(l.izz_kgm2) +
         ", length_m: " + g(l.length_m) + "}\n";
  }
  return t;
}

std::string describeYamlRobot(const std::string& path) {
  const YAML::Node doc = loadBoundedYaml(path);
  RobotParams p;
  std::string source;
  if (doc.IsMap() && (doc["name"] || doc["experiments"])) {
    std::vector<Experiment> e = loadExperimentSuite(path);
    if (e.front().cases.front().robot_model) {  // a robot from its model file: derived, as `tailsim run` does
      resolveRobotModels(e.front());
      const ExperimentCase& c = e.front().cases.front();
      std::string out = describeDerivedRobot(*c.robot_derived) + "\ntail (case " + c.name + "):\n";
      for (std::size_t i = 0; i < c.robot.tail.size(); ++i) {
        char line[160];
        const TailLink& l = c.robot.tail[i];
        std::snprintf(line, sizeof line, "  link %zu: mass_kg %.9g, izz_kgm2 %.9g, length_m %.9g, com_offset_m %.9g\n",
                      i + 1, l.mass_kg, l.izz_kgm2, l.length_m, l.com_offset_m);
        out += line;
      }
      return out;
    }
    const ExperimentCase& c = e.front().cases.front();
    p = c.robot;
    source = "robot file " + c.robot_file + " with the overrides of experiment " + e.front().name + " (case " + c.name + ")";
  } else {
    const RobotFileData r = loadRobotFile(path);
    p = r.base;
    source = "robot file " + r.file;
  }
  const QuadrupedParams& q = p.quadruped;
  const struct {
    const char* key;
    double v;
    const char* unit;
  } rows[] = {{"quadruped.mass_kg", q.mass_kg, "kg"},
              {"quadruped.izz_kgm2", q.izz_kgm2, "kg m^2"},
              {"quadruped.d_Q2C_m", q.d_Q2C_m, "m"},
              {"quadruped.d_Q2B_m", q.d_Q2B_m, "m"},
              {"quadruped.l_F_m", q.l_F_m, "m"},
              {"quadruped.w_F_m", q.w_F_m, "m"},
              {"quadruped.com_height_m", q.com_height_m, "m"},
              {"friction.mu_s", p.friction.mu_s, "-"},
              {"friction.mu_d", p.friction.mu_d, "-"},
              {"gravity_mps2", p.gravity_mps2, "m/s^2"}};
  std::string out = "robot: " + source + "\n\n";
  for (const auto& r : rows) {
    char line[128];
    std::snprintf(line, sizeof line, "%-24s %-14.9g %s\n", r.key, r.v, r.unit);
    out += line;
  }
  return out + "\n(a quadruped given by size_m has these values derived from its box: docs/experiment-format.md)\n";
}

std::string describeComparison(const RobotComparison& c) {
  std::ostringstream o;
  const TailLink& l = c.tail.front();
  o << "tail: " << c.tail.size() << " link(s) of " << f3(l.mass_kg) << " kg, " << f3(l.length_m)
    << " m; Eq. 25 stroke, mu = " << f3(c.robot.mu) << "\n\n";
  o << "| model | phi_net [deg] | warnings |\n|---|---|---|\n";
  for (const ModelRow& r : c.rows) {
    std::string w;
    for (const std::string& x : r.warnings) w += (w.empty() ? "" : "; ") + x;
    o << "| " << r.model << " | " << phiCell(r) << " | " << w << " |\n";
  }
  return o.str();
}

}  // namespace tailsim
