// How far MuJoCo at a given contact-setting rule is from a converged MuJoCo reference, over the
// seeded random-robot corpus of tests/random_robots.h (docs/mujoco-model.md "Contact settings:
// the rule and its evidence"). Plain main, one thread; prints one Markdown row per rule:
//   nice build/tests/bench_trust [--cases N=120] [--seed S=31] [--rules "today;set:imp=100,ns=3;.."]
//                                [--ref-cache FILE] [--check16 K=10] [--csv FILE] [--jitter-check]
//                                [--corpus mixed|tippy] [--falls] [--ref-rule NAME]
// Reference of a rule: the rule's settings at timestep / 8 (servo w_n kept), impratio >= 100,
// noslip >= 3 (for "today": the old defaults' reference); every K-th case also at timestep / 16, to
// show the reference itself has converged. --ref-cache keeps the reference runs (keyed by seed,
// case and settings) so rules can be compared without re-running them. --ref-rule NAME: every rule
// against NAME's reference instead of its own (a candidate default against today's default's).
// Columns (cases where both the rule and its reference stand):
//  * err median / p90 / max: |phi_net - phi_net,ref| / max(|phi_net,ref|, 0.5 deg);
//  * vs today ref: the same against today's reference (what a rule's physics moves);
//  * vs per-foot: the same against the per-foot model with load transfer (rigid Coulomb friction);
//  * jitter p90: |phi_net(dT + 1 us) - phi_net(dT)| / max(|phi_net(dT)|, 0.5 deg), rule and reference;
//  * sign flips: phi_net and phi_net,ref of opposite signs, |phi_net,ref| >= 0.5 deg;
//  * airborne > 1 %: runs with no foot loaded in more than 1 % of the steps (summary extra
//    airborne_fraction), and the median share;
//  * peak Fn / m g: median and max of summary extra peak_normal_force_over_mg;
//  * falls: the rule fails (tips over, unstable) where the reference stands, and the other way round;
//  * steps, wall: median mj_step calls (pre-roll and the uncertainty's check run included) and
//    wall time per run;
//  * U bounds err: runs whose phi_net_uncertainty_deg >= |phi_net - phi_net,ref|; U median: the
//    uncertainty / max(|phi_net|, 0.5 deg); U flagged: runs warned as uncertain; err > 3 %
//    flagged: of the runs more than 3 % off the reference, those warned.
// --corpus tippy: the robots near tipping over (random_robots.h RandomCorpus::kTippy).
// --falls: instead of the rule table, the fall signal (docs/mujoco-model.md "Tipping over"):
// MuJoCo at the defaults (uncertainty on) and the per-foot model with load transfer against the
// reference of the defaults, as confusion tables, the count of cases where the reference falls
// and the default run prints a plain turn (no warning beginning kUncertainWarning), and the
// verdict (src/experiments/verdict.h) of per-foot and MuJoCo where they disagree on falling.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/verdict.h"
#include "models/perfoot/per_foot_model.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_settings.h"
#include "models/mujoco/mujoco_simulation.h"
#include "random_robots.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {

struct Run {
  bool ok = false;
  double phi_deg = NAN, airborne = NAN, peak = NAN, wall_s = NAN, u_deg = NAN, tilt_deg = NAN, check_deg = NAN;
  long steps = 0;
  bool fell = false;  // failed because the robot fell over (kMujocoFallText), not from instability
  RunSummary summary;
};

// Settings every rule starts from: MujocoSettings' defaults with the body at the robot's COM
// height (what the experiment loader does).
MujocoSettings baseSettings(const RobotParams& r) {
  MujocoSettings s;
  s.body_height_m = r.quadruped.com_height_m;
  return s;
}

// Today's (pre-rule) contact and integration settings, written out so that the "before" stays
// reproducible whatever MujocoSettings' defaults become.
void today(const RobotParams&, const TailTrajectory&, MujocoSettings& s) {
  s.timestep_s = 2e-4;
  s.servo_wn_dt = 0.2;
  s.integrator = MujocoIntegrator::kImplicit;
  s.cone = MujocoCone::kElliptic;
  s.impratio = 1.0;
  s.noslip_iterations = 0;
  s.condim = 3;
  s.solref = {0.002, 1.0};
  s.solimp = {0.95, 0.99, 0.001, 0.5, 2.0};
  s.foot_shape = MujocoFootShape::kSphere;
  s.foot_radius_m = 0.01;
  s.settle_s = 0.1;
  s.uncertainty = false;
  s.rest_step_factor = 1;
}

// Finer step with the servo's natural frequency kept.
void refine(MujocoSettings& s, double factor) {
  s.timestep_s /= factor;
  if (s.kp == 0.0) s.servo_wn_dt /= factor;
}

// A rule's converged reference: its own contact, a finer step, stiff friction and noslip.
void toReference(MujocoSettings& s, double factor) {
  refine(s, factor);
  s.uncertainty = false;
  s.impratio = std::max(s.impratio, 100.0);
  s.noslip_iterations = std::max(s.noslip_iterations, 3);
}

using Rule = std::function<void(const RobotParams&, const TailTrajectory&, MujocoSettings&)>;

// Named rules (name -> settings): "today" is the before, "default" MujocoSettings' defaults.
std::map<std::string, Rule> rules() {
  std::map<std::string, Rule> m;
  m["today"] = today;
  m["default"] = [](const RobotParams&, const TailTrajectory&, MujocoSettings&) {};  // MujocoSettings' defaults
  m["default_ns3"] = [](const RobotParams&, const TailTrajectory&, MujocoSettings& s) { s.noslip_iterations = 3; };
  m["default_h2"] = [](const RobotParams&, const TailTrajectory&, MujocoSettings& s) { refine(s, 2.0); };
  for (int f : {1, 2, 10})  // the defaults with another step once the body rests
    m["default_rest" + std::to_string(f)] = [f](const RobotParams&, const TailTrajectory&, MujocoSettings& s) {
      s.rest_step_factor = f;
    };
  m["imp100"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    s.impratio = 100.0;
  };
  m["imp100ns3"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    s.impratio = 100.0;
    s.noslip_iterations = 3;
  };
  m["h2"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    refine(s, 2.0);
  };
  m["h2imp100ns3"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    refine(s, 2.0);
    s.impratio = 100.0;
    s.noslip_iterations = 3;
  };
  m["softimp"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    s.impratio = 100.0;
    s.noslip_iterations = 3;
    s.solimp = {0.015, 0.9999, 0.031, 0.5, 2.0};
  };
  m["box"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    s.foot_shape = MujocoFootShape::kBox;
  };
  m["boxns3"] = [](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    today(r, t, s);
    s.foot_shape = MujocoFootShape::kBox;
    s.impratio = 100.0;
    s.noslip_iterations = 3;
  };
  return m;
}

// "set:key=value,..": today's rule with these changes; "dset:key=value,..": MujocoSettings'
// defaults with these changes (keys: h = timestep_s (servo w_n kept),
// imp = impratio, ns = noslip_iterations, tau, zeta = solref, dmin, dmax, width, mid, power =
// solimp, foot = sphere|capsule|box, r = foot_radius_m, settle = settle_s).
Rule parseRule(const std::string& spec) {
  const bool from_defaults = spec.rfind("dset:", 0) == 0;
  std::vector<std::pair<std::string, std::string>> kv;
  for (std::stringstream ss(spec.substr(spec.find(':') + 1)); ss.good();) {
    std::string item;
    std::getline(ss, item, ',');
    const size_t eq = item.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("rule item without '=': " + item);
    kv.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return [kv, from_defaults](const RobotParams& r, const TailTrajectory& t, MujocoSettings& s) {
    if (!from_defaults) today(r, t, s);
    for (const auto& [k, v] : kv) {
      const double x = std::atof(v.c_str());
      if (k == "h") refine(s, s.timestep_s / x);
      else if (k == "imp") s.impratio = x;
      else if (k == "ns") s.noslip_iterations = static_cast<int>(x);
      else if (k == "tau") s.solref[0] = x;
      else if (k == "zeta") s.solref[1] = x;
      else if (k == "dmin") s.solimp[0] = x;
      else if (k == "dmax") s.solimp[1] = x;
      else if (k == "width") s.solimp[2] = x;
      else if (k == "mid") s.solimp[3] = x;
      else if (k == "power") s.solimp[4] = x;
      else if (k == "r") s.foot_radius_m = x;
      else if (k == "settle") s.settle_s = x;
      else if (k == "foot") s.foot_shape = v == "box" ? MujocoFootShape::kBox : v == "capsule" ? MujocoFootShape::kCapsule : MujocoFootShape::kSphere;
      else throw std::invalid_argument("unknown rule key " + k);
    }
  };
}

TailTrajectory jittered(const TailTrajectory& t, double d_s) {
  TailTrajectory out;
  for (const auto& j : t.joints) {
    SplitCycleParams p = j.params();
    p.dT_s += d_s;
    out.joints.emplace_back(p);
  }
  return out;
}

Run runOnce(const RobotParams& r, const TailTrajectory& t, const MujocoSettings& s) {
  OutputSettings o;
  o.time_series = TimeSeriesOutput::kNone;
  Effects e;
  Run out;
  try {
    const RunResult res = simulateMujoco(r, t, s, e, o);
    out.ok = res.summary.ok;
    out.fell = !res.summary.ok && res.summary.error.find(kMujocoFallText) != std::string::npos;
    out.summary = res.summary;
    out.phi_deg = res.summary.phi_net_deg;
    out.wall_s = res.summary.wall_time_s;
    out.steps = res.summary.solver_steps + static_cast<long>(std::lround(s.settle_s / s.timestep_s));
    if (const auto u = res.summary.extra.find("uncertainty_solver_steps"); u != res.summary.extra.end())
      out.steps += static_cast<long>(u->second) + static_cast<long>(std::lround(s.settle_s / (2 * s.timestep_s)));
    auto x = [&](const char* k) {
      const auto it = res.summary.extra.find(k);
      return it == res.summary.extra.end() ? NAN : it->second;
    };
    out.airborne = x("airborne_fraction");
    out.peak = x("peak_normal_force_over_mg");
    out.u_deg = x("phi_net_uncertainty_deg");
    out.check_deg = x("phi_net_check_deg");
    out.tilt_deg = x("max_tilt_deg");
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "run threw: %s\n", ex.what());
  }
  return out;
}


std::string key(const MujocoSettings& s) {
  std::ostringstream os;
  os.precision(17);
  os << s.timestep_s << '/' << s.servo_wn_dt << '/' << s.impratio << '/' << s.noslip_iterations << '/' << s.solref[0]
     << '/' << s.solref[1] << '/' << s.solimp[0] << '/' << s.solimp[1] << '/' << s.solimp[2] << '/'
     << s.solimp[3] << '/' << s.solimp[4] << '/' << name(s.foot_shape) << '/' << s.foot_radius_m << '/'
     << s.foot_half_length_m << '/' << s.body_height_m << '/' << s.settle_s << '/' << name(s.cone) << '/'
     << name(s.integrator) << '/' << s.condim << '/' << s.kp << '/' << s.kv << '/' << s.iterations;
  return os.str();
}

// Reference runs, optionally kept in a file: one line "key ok phi airborne peak steps wall
// [max_tilt fell]" (the last two are absent in caches written before --falls).
class RefCache {
 public:
  explicit RefCache(std::string path) : path_(std::move(path)) {
    if (path_.empty()) return;
    std::ifstream in(path_);
    // Numbers through strtod, which reads the "nan" a failed run writes (operator>> does not).
    for (std::string line; std::getline(in, line);) {
      std::istringstream is(line);
      std::string k;
      std::vector<double> x;
      is >> k;
      for (std::string w; is >> w;) x.push_back(std::strtod(w.c_str(), nullptr));
      if (x.size() < 6) continue;
      Run r;
      r.ok = x[0] != 0.0;
      r.phi_deg = x[1], r.airborne = x[2], r.peak = x[3], r.steps = static_cast<long>(x[4]), r.wall_s = x[5];
      if (x.size() >= 8) r.tilt_deg = x[6], r.fell = x[7] != 0.0;
      else if (!r.ok) continue;  // an older line: whether the run fell is not known, run it again
      map_[k] = r;
    }
  }
  Run get(const std::string& k, const std::function<Run()>& make) {
    const auto it = map_.find(k);
    if (it != map_.end()) return it->second;
    const Run r = make();
    map_[k] = r;
    if (!path_.empty()) {
      std::ofstream out(path_, std::ios::app);
      out.precision(17);
      out << k << ' ' << r.ok << ' ' << r.phi_deg << ' ' << r.airborne << ' ' << r.peak << ' ' << r.steps << ' '
          << r.wall_s << ' ' << r.tilt_deg << ' ' << r.fell << '\n';
    }
    return r;
  }

 private:
  std::string path_;
  std::map<std::string, Run> map_;
};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double x = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(x);
  return i + 1 < v.size() ? v[i] + (x - i) * (v[i + 1] - v[i]) : v.back();
}

double rel(double a, double ref) { return std::abs(a - ref) / std::max(std::abs(ref), 0.5); }

// The fall signal (--falls): how each case ends in the per-foot model (load transfer), MuJoCo at the
// defaults and the defaults' reference, as confusion tables and the list of the cases that matter.
enum class End { kFalls, kWarns, kPlain, kFails };  // MuJoCo; the planar model: kFalls = tips, kPlain = stands

bool uncertainWarned(const RunSummary& s) {
  for (const std::string& w : s.warnings)
    if (w.rfind(kUncertainWarning, 0) == 0) return true;
  return false;
}

End mujocoEnd(const Run& r) {
  if (!r.ok) return r.fell ? End::kFalls : End::kFails;
  return uncertainWarned(r.summary) ? End::kWarns : End::kPlain;
}

// Why a default run was marked uncertain: the near-fall tilt, the check run, or the size of U.
std::string warnReason(const RunSummary& s) {
  std::string out;
  for (const std::string& w : s.warnings) {
    if (w.rfind(kUncertainWarning, 0) != 0) continue;
    const char* why = w.find("nearly fell") != std::string::npos  ? "near fall"
                      : w.find("check run") != std::string::npos ? (w.find(kMujocoFallText) != std::string::npos ? "check run fell" : "check run failed")
                                                                 : "U > share";
    out += std::string(out.empty() ? "" : "+") + why;
  }
  return out;
}

RunSummary perFootSummary(const RobotParams& r, const TailTrajectory& t) {
  OutputSettings o;
  o.time_series = TimeSeriesOutput::kNone;
  PerFootSettings p;
  p.normal_loads = NormalLoadModel::kLoadTransfer;
  try {
    RunSummary s = simulatePerFoot(r, t, p, Effects{}, o).summary;
    s.model = "perfoot";
    return s;
  } catch (const std::exception& e) {
    RunSummary s;
    s.model = "perfoot";
    s.ok = false;
    s.error = e.what();
    return s;
  }
}

// The per-foot model with load transfer (rigid Coulomb friction at four point feet), for scale.
double perFootPhi(const RobotParams& r, const TailTrajectory& t) {
  const RunSummary s = perFootSummary(r, t);
  return s.ok ? s.phi_net_deg : NAN;
}

// A run with the tilt check off (max_tilt_deg 0, no check run): does it rock back or topple? Its
// largest tilt and the tilt at its last output row [deg]; ok false when it failed all the same
// (no foot loaded for max_all_feet_off_s).
struct FreeRun {
  bool ok = false;
  double max_tilt_deg = NAN, final_tilt_deg = NAN;
};

FreeRun freeRun(const RandomRobotCase& c, MujocoSettings s) {
  s.max_tilt_deg = 0.0;
  s.uncertainty = false;
  FreeRun out;
  int body = -1;
  double cz = NAN;
  const MujocoSampleObserver last = [&](double, const mjModel* m, const mjData* d) {
    if (body < 0) body = mj_name2id(m, mjOBJ_BODY, mjcf::kQuadrupedBody);
    cz = d->xmat[9 * body + 8];
  };
  try {
    const RunResult r = simulateMujoco(c.robot, c.trajectory, s, Effects{}, OutputSettings{}, last);
    out.ok = r.summary.ok;
    out.max_tilt_deg = r.summary.extra.at("max_tilt_deg");
    out.final_tilt_deg = std::acos(std::clamp(cz, -1.0, 1.0)) * 180.0 / M_PI;
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "free run threw: %s\n", ex.what());
  }
  return out;
}

// `reference(k)`: case k's reference run; `ref_settings`: its settings.
void fallsReport(const std::vector<RandomRobotCase>& cases, const std::function<Run(int)>& reference,
                 const std::function<MujocoSettings(const RobotParams&)>& ref_settings, std::ofstream& csv) {
  const int N = static_cast<int>(cases.size());
  // [reference: falls, stands, fails][default: falls, warns, plain, fails]; [reference][per-foot: tips, stands, fails]
  int mj[3][4] = {}, pf[3][3] = {};
  std::vector<std::string> notes;
  std::vector<double> tilt_stand, tilt_fall;  // default runs that stand: max tilt, by the reference's end
  std::map<std::string, int> reasons;  // verdict of per-foot vs MuJoCo default where they disagree on falling
  if (csv.is_open())
    csv << "case,ref_end,ref_phi_deg,ref_max_tilt_deg,default_end,default_phi_deg,default_max_tilt_deg,default_u_deg,"
           "default_check_phi_deg,default_warning,default_error,perfoot_end,perfoot_phi_deg,perfoot_error,verdict,description\n";
  const char* kMj[] = {"falls", "warns", "plain", "fails"};
  for (int k = 0; k < N; ++k) {
    const RandomRobotCase& c = cases[k];
    const Run f = reference(k);
    const Run d = runOnce(c.robot, c.trajectory, baseSettings(c.robot));
    RunSummary p = perFootSummary(c.robot, c.trajectory);
    RunSummary m = d.summary;
    m.model = "mujoco";
    const int fi = !f.ok ? (f.fell ? 0 : 2) : 1;
    const End de = mujocoEnd(d);
    const int pi = p.ok ? 1 : p.error.find(kPlanarTipText) != std::string::npos ? 0 : 2;
    ++mj[fi][static_cast<int>(de)];
    ++pf[fi][pi];
    if (de != End::kFalls && de != End::kFails) (fi == 0 ? tilt_fall : tilt_stand).push_back(d.tilt_deg);
    const std::string verdict = caseVerdict({p, m});
    if ((pi == 0) != (de == End::kFalls) && pi != 2 && de != End::kFails) {
      const bool lt = verdict.find("dynamic load transfer") != std::string::npos;
      const bool sm = verdict.find("support margin") != std::string::npos;
      ++reasons[std::string(pi == 0 ? "per-foot tips, MuJoCo stands" : "MuJoCo falls, per-foot stands") + ": " +
                (lt ? "dynamic load transfer" : sm ? "support margin" : "no reason")];
    }
    const char* fname = fi == 0 ? "falls" : fi == 1 ? "stands" : "fails";
    const char* pname = pi == 0 ? "tips" : pi == 1 ? "stands" : "fails";
    if ((fi == 0 && de != End::kFalls) || (fi == 1 && de == End::kFalls)) {
      // How far each tilts with the tilt check off: a fall goes on past the tip-over angle (the
      // system COM over the side feet, atan(w_F / 2 / h)), a rock comes back.
      const FreeRun df = freeRun(c, baseSettings(c.robot)), ff = freeRun(c, ref_settings(c.robot));
      const double tip_deg = std::atan(0.5 * c.robot.quadruped.w_F_m / c.robot.quadruped.com_height_m) * 180.0 / M_PI;
      char b[400];
      std::snprintf(b, sizeof b,
                    "case %d: reference %s (tilt %.2f deg; free: max %.1f, end %.1f deg%s), default %s (phi %.2f deg, "
                    "tilt %.2f deg%s%s; free: max %.1f, end %.1f deg%s), side tip-over angle %.1f deg, per-foot %s: ",
                    k, fname, f.tilt_deg, ff.max_tilt_deg, ff.final_tilt_deg, ff.ok ? "" : ", fails",
                    kMj[static_cast<int>(de)], d.phi_deg, d.tilt_deg, de == End::kWarns ? ", " : "",
                    de == End::kWarns ? warnReason(d.summary).c_str() : "", df.max_tilt_deg, df.final_tilt_deg,
                    df.ok ? "" : ", fails", tip_deg, pname);
      notes.push_back(b + describe(c));
    }
    if (csv.is_open())
      csv << k << ',' << fname << ',' << f.phi_deg << ',' << f.tilt_deg << ',' << kMj[static_cast<int>(de)] << ','
          << d.phi_deg << ',' << d.tilt_deg << ',' << d.u_deg << ',' << d.check_deg << ",\"" << warnReason(d.summary)
          << "\",\"" << d.summary.error << "\"," << pname << ',' << p.phi_net_deg << ",\"" << p.error << "\",\"" << verdict << "\",\"" << describe(c) << "\"\n";
    std::fprintf(stderr, "case %d/%d: reference %s, default %s, per-foot %s\n", k + 1, N, fname,
                 kMj[static_cast<int>(de)], pname);
  }
  const char* kRef[] = {"reference falls", "reference stands", "reference fails (unstable)"};
  std::printf("MuJoCo at the defaults (uncertainty on) against the reference (the defaults at timestep / 8, impratio "
              "100, noslip 3); warns = a warning beginning \"%s\" (near fall, check run failed, or U beyond "
              "uncertainty_warn_share)\n\n",
              kUncertainWarning);
  std::printf("| | default falls | default warns | default plain turn | default fails (unstable) |\n|---|---|---|---|---|\n");
  for (int i = 0; i < 3; ++i)
    std::printf("| %s | %d | %d | %d | %d |\n", kRef[i], mj[i][0], mj[i][1], mj[i][2], mj[i][3]);
  std::printf("\n**Reference falls, default prints a plain turn: %d** (of %d cases)\n\n", mj[0][2], N);
  std::printf("| | per-foot tips | per-foot stands | per-foot fails |\n|---|---|---|---|\n");
  for (int i = 0; i < 3; ++i) std::printf("| %s | %d | %d | %d |\n", kRef[i], pf[i][0], pf[i][1], pf[i][2]);
  std::printf("\nlargest tilt of the default runs that stand: where the reference stands median %.2f, p90 %.2f, max "
              "%.2f deg (n %zu); where it falls min %.2f, median %.2f, max %.2f deg (n %zu)\n\n",
              quantile(tilt_stand, 0.5), quantile(tilt_stand, 0.9), quantile(tilt_stand, 1.0), tilt_stand.size(),
              quantile(tilt_fall, 0.0), quantile(tilt_fall, 0.5), quantile(tilt_fall, 1.0), tilt_fall.size());
  std::printf("verdict (per-foot and MuJoCo at the defaults) where they disagree on falling:\n");
  for (const auto& [r, n] : reasons) std::printf("  %s: %d\n", r.c_str(), n);
  std::printf("\ncases where the reference and the default disagree on falling:\n");
  for (const std::string& n : notes) std::printf("  %s\n", n.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  int N = 120, check16 = 10;
  bool jitter_check = false, falls = false;
  RandomCorpus corpus = RandomCorpus::kMixed;  // --jitter-check: the jitter run has its own check run (check_jitter_phi_deg)
  unsigned seed = 31;
  std::string rule_list = "today", cache_path, csv_path, ref_rule;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--cases") N = std::atoi(next().c_str());
    else if (a == "--seed") seed = static_cast<unsigned>(std::atoll(next().c_str()));
    else if (a == "--rules") rule_list = next();
    else if (a == "--ref-cache") cache_path = next();
    else if (a == "--check16") check16 = std::atoi(next().c_str());
    else if (a == "--csv") csv_path = next();
    else if (a == "--ref-rule") ref_rule = next();
    else if (a == "--jitter-check") jitter_check = true;
    else if (a == "--falls") falls = true;
    else if (a == "--corpus") {
      const std::string v = next();
      if (v != "mixed" && v != "tippy") {
        std::fprintf(stderr, "--corpus is mixed or tippy, not %s\n", v.c_str());
        return 2;
      }
      corpus = v == "tippy" ? RandomCorpus::kTippy : RandomCorpus::kMixed;
    }
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  std::map<std::string, Rule> all = rules();
  std::vector<std::string> names;
  for (std::stringstream ss(rule_list); ss.good();) {
    std::string n;
    std::getline(ss, n, ';');
    if (n.rfind("set:", 0) == 0 || n.rfind("dset:", 0) == 0) all[n] = parseRule(n);
    if (!all.count(n)) {
      std::fprintf(stderr, "unknown rule %s; known:", n.c_str());
      for (const auto& [k, v] : all) std::fprintf(stderr, " %s", k.c_str());
      std::fprintf(stderr, "\n");
      return 2;
    }
    names.push_back(n);
  }
  if (!ref_rule.empty() && !all.count(ref_rule)) {
    std::fprintf(stderr, "unknown --ref-rule %s\n", ref_rule.c_str());
    return 2;
  }
  RefCache cache(cache_path);
  std::ofstream csv;
  if (!csv_path.empty()) csv.open(csv_path);
  if (csv.is_open() && !falls) {
    csv << "rule,case,ok,phi_deg,phi_jitter_deg,ref_ok,ref_phi_deg,ref_jitter_deg,today_ref_phi_deg,ref16_phi_deg,perfoot_phi_deg,airborne,"
           "peak_over_mg,steps,wall_s,u_deg,max_tilt_deg,check_phi_deg,check_jitter_phi_deg,"
           "description\n";
  }

  std::vector<RandomRobotCase> cases;
  std::vector<double> perfoot;
  for (int k = 0; k < N; ++k) {
    cases.push_back(randomRobotCase(seed, k, corpus));
    perfoot.push_back(perFootPhi(cases.back().robot, cases.back().trajectory));
  }
  auto tag = [&](int k) {
    return std::string(corpus == RandomCorpus::kTippy ? "tippy:" : "") + std::to_string(seed) + ':' + std::to_string(k) + ':';
  };
  // A rule's reference runs (cached): its settings refined by `factor`, impratio >= 100, noslip >= 3.
  auto refRun = [&](const Rule& rule, int k, double factor, double jitter_s) {
    const RandomRobotCase& c = cases[k];
    MujocoSettings s = baseSettings(c.robot);
    rule(c.robot, c.trajectory, s);
    toReference(s, factor);
    const std::string kk = tag(k) + (jitter_s != 0.0 ? "refj:" : "ref:") + key(s);
    return cache.get(kk, [&] { return runOnce(c.robot, jittered(c.trajectory, jitter_s), s); });
  };

  if (falls) {
    std::printf("corpus: %d cases (seed %u, %s)\n\n", N, seed, corpus == RandomCorpus::kTippy ? "tippy" : "mixed");
    fallsReport(
        cases, [&](int k) { return refRun(all.at("default"), k, 8.0, 0.0); },
        [](const RobotParams& r) {
          MujocoSettings s = baseSettings(r);
          toReference(s, 8.0);
          return s;
        },
        csv);
    return 0;
  }
  std::printf("corpus: %d cases (seed %u); reference: the rule's settings at timestep / 8 (servo w_n kept), impratio "
              ">= 100, noslip >= 3; 'today ref': today's rule's reference (the same for every rule)\n\n",
              N, seed);
  std::printf("| rule | compared | err median | err p90 | err max | vs today ref median | vs today ref p90 | "
              "vs per-foot median | vs per-foot p90 | jitter p90 | ref jitter p90 | ref h/8 vs h/16 median / p90 (n) | sign flips | airborne > 1 %% | "
              "airborne median | peak Fn/mg median | peak Fn/mg max | falls only here / only in ref | steps median | "
              "wall median [ms] | U bounds err | U median | U flagged | err > 3 %% flagged |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& nm : names) {
    const Rule& rule = all.at(nm);
    std::vector<double> err, errT, errP, jit, rjit, conv, air, peak, steps, wall;
    int flips = 0, air1 = 0, falls_here = 0, falls_ref = 0, compared = 0;
    int u_have = 0, u_bound = 0, u_flag = 0, big = 0, big_flag = 0;
    std::vector<double> u_rel;
    for (int k = 0; k < N; ++k) {
      const RandomRobotCase& c = cases[k];
      MujocoSettings s = baseSettings(c.robot);
      rule(c.robot, c.trajectory, s);
      const Run r = runOnce(c.robot, c.trajectory, s);
      MujocoSettings sj = s;
      sj.uncertainty = jitter_check && s.uncertainty;  // the jitter run needs phi_net only
      const Run j = runOnce(c.robot, jittered(c.trajectory, 1e-6), sj);
      const Rule& ref_of = ref_rule.empty() ? rule : all.at(ref_rule);
      const Run f = refRun(ref_of, k, 8.0, 0.0);
      const Run fj = refRun(ref_of, k, 8.0, 1e-6);
      const Run ft = refRun(all.at("today"), k, 8.0, 0.0);
      Run f16;
      if (check16 > 0 && k % check16 == 0) f16 = refRun(ref_of, k, 16.0, 0.0);
      steps.push_back(r.steps);
      wall.push_back(r.wall_s);
      if (csv.is_open())
        csv << '"' << nm << "\"," << k << ',' << r.ok << ',' << r.phi_deg << ',' << j.phi_deg << ',' << f.ok << ','
            << f.phi_deg << ',' << fj.phi_deg << ',' << ft.phi_deg << ',' << f16.phi_deg << ',' << perfoot[k] << ',' << r.airborne << ','
            << r.peak << ',' << r.steps << ',' << r.wall_s << ',' << r.u_deg << ',' << r.tilt_deg << ',' << r.check_deg << ',' << j.check_deg << ",\"" << describe(c) << "\"\n";
      if (r.ok && !f.ok) ++falls_ref;
      if (!r.ok && f.ok) ++falls_here;
      if (!r.ok || !f.ok) continue;
      ++compared;
      err.push_back(rel(r.phi_deg, f.phi_deg));
      if (ft.ok) errT.push_back(rel(r.phi_deg, ft.phi_deg));
      if (!std::isnan(perfoot[k])) errP.push_back(rel(r.phi_deg, perfoot[k]));
      if (j.ok) jit.push_back(rel(j.phi_deg, r.phi_deg));
      if (fj.ok) rjit.push_back(rel(fj.phi_deg, f.phi_deg));
      if (f16.ok) conv.push_back(rel(f.phi_deg, f16.phi_deg));
      if (std::abs(f.phi_deg) >= 0.5 && r.phi_deg * f.phi_deg < 0) ++flips;
      if (std::isfinite(r.u_deg)) {
        const double scale = std::max(std::abs(r.phi_deg), 0.5);
        const bool flagged = r.u_deg > s.uncertainty_warn_share * scale;
        ++u_have;
        if (std::abs(r.phi_deg - f.phi_deg) <= r.u_deg) ++u_bound;
        u_flag += flagged;
        u_rel.push_back(r.u_deg / scale);
        if (err.back() > 0.03) ++big, big_flag += flagged;
      }
      air.push_back(r.airborne);
      if (r.airborne > 0.01) ++air1;
      peak.push_back(r.peak);
    }
    std::printf("| %s | %d | %.2f %% | %.2f %% | %.1f %% | %.2f %% | %.2f %% | %.2f %% | %.2f %% | %.2f %% | %.2f %% | %.2f %% / %.2f %% (%zu) "
                "| %d | %d | %.1f %% | %.2f | %.1f | %d / %d | %.0f | %.1f | %d / %d (%.1f %%) | %.2f %% | %d | %d / %d |\n",
                nm.c_str(), compared, 100 * quantile(err, 0.5), 100 * quantile(err, 0.9), 100 * quantile(err, 1.0),
                100 * quantile(errT, 0.5), 100 * quantile(errT, 0.9), 100 * quantile(errP, 0.5), 100 * quantile(errP, 0.9),
                100 * quantile(jit, 0.9),
                100 * quantile(rjit, 0.9), 100 * quantile(conv, 0.5), 100 * quantile(conv, 0.9), conv.size(), flips,
                air1, 100 * quantile(air, 0.5), quantile(peak, 0.5), quantile(peak, 1.0), falls_here, falls_ref,
                quantile(steps, 0.5), 1e3 * quantile(wall, 0.5), u_bound, u_have,
                u_have ? 100.0 * u_bound / u_have : NAN, 100 * quantile(u_rel, 0.5), u_flag, big_flag, big);
    std::fflush(stdout);
  }
  return 0;
}
