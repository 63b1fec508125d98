// What holds the per-foot model and MuJoCo apart: one MuJoCo effect isolated per
// variant, over every case of Figs. 6, 7, 9, 11-14 (configs/paper), measured as the change of the
// gap |phi_net,perfoot - phi_net,MuJoCo| / |phi_net,MuJoCo| (median / max over the cases with
// |phi_net,MuJoCo| >= 1 deg). docs/per-foot-model.md "What holds the per-foot model and MuJoCo apart".
//   build/tests/bench_gap_attribution [--law stiction|adams] [--only REGEX] [--variants a,b,..]
//                                     [--csv FILE] [--suite SUITE.yaml] [--dump DIR]
// Variants (each a pair: per-foot run vs MuJoCo run, same friction law):
//   base       perfoot load transfer (h = com_height_m)    vs MuJoCo default
//   qs         perfoot quasi-static loads                  vs MuJoCo default
//   measured   perfoot driven by MuJoCo's own foot<k>_Fn_N (impulse averages, 1 ms) vs MuJoCo default
//   h<N>       perfoot lt vs MuJoCo timestep / N (servo w_n kept), e.g. h2, h4, h8
//   stiff<N>   perfoot lt vs MuJoCo solref[0] / N at timestep / N (stiff2: solref 0.001 at 1e-4 s)
//   impratio   perfoot lt vs MuJoCo impratio 100
//   torsion<T> perfoot lt vs MuJoCo condim 4 with torsional friction T mm (moment / normal force), e.g. torsion1
//   condim6    perfoot lt vs MuJoCo condim 6 (torsional and rolling friction 0: must equal base)
//   capsule    perfoot lt vs MuJoCo capsule feet (mujoco.foot_shape, default foot_radius_m / foot_half_length_m)
//   box        perfoot lt vs MuJoCo box feet (cubes of half-size foot_radius_m, 4 corner contacts)
//   softimp    perfoot lt vs MuJoCo impratio 100, noslip 3, solimp 0.015 0.9999 0.031
//   low        perfoot lt and MuJoCo with the body (COM) 0.05 m high instead of 0.15 m
//   servo      perfoot lt vs MuJoCo with a 2x stiffer tail servo (servo_wn_dt 0.4)
//   noff       perfoot lt vs MuJoCo without the inverse-dynamics feed-forward
//   nofric     both without friction (the multibody and the integrator alone)
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "models/perfoot/per_foot_model.h"
#include "experiments/experiment_loader.h"
#include "models/mujoco/mujoco_simulation.h"
#include "common/atomic_file.h"
#include "results/csv.h"
#include "results/columns.h"

using namespace tailsim;

namespace {

bool inGap(const std::string& name) {
  for (const char* p : {"fig06a", "fig06b", "fig07", "fig09", "fig11", "fig12", "fig13", "fig14"})
    if (name.rfind(p, 0) == 0) return true;
  return false;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// MuJoCo's recorded foot loads as a per-foot model input.
PrescribedNormalLoads loadsOf(const TimeSeries& ts) {
  PrescribedNormalLoads L;
  const std::vector<double>& t = ts.values(col::kT);
  L.t_s = t;
  L.N.resize(t.size());
  for (int k = 1; k <= 4; ++k) {
    const std::vector<double>& fn = ts.values(col::footFn(k));
    for (size_t j = 0; j < t.size(); ++j) L.N[j][k - 1] = std::isfinite(fn[j]) ? std::max(0.0, fn[j]) : 0.0;
  }
  return L;
}

struct Pair {
  double perfoot = NAN, mujoco = NAN;
};

}  // namespace

int main(int argc, char** argv) {
  std::string suite = TAILSIM_SOURCE_DIR "/configs/paper/all.yaml", only = ".*", law_name = "stiction";
  std::string variants = "base,qs,measured,h2,stiff2,impratio,low,servo,noff,nofric";
  const char* csv = nullptr;
  std::string dump;  // --dump DIR: the default MuJoCo run and the measured-load per-foot run of each case as CSV
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--suite")) suite = argv[i + 1];
    else if (!std::strcmp(argv[i], "--only")) only = argv[i + 1];
    else if (!std::strcmp(argv[i], "--variants")) variants = argv[i + 1];
    else if (!std::strcmp(argv[i], "--law")) law_name = argv[i + 1];
    else if (!std::strcmp(argv[i], "--csv")) csv = argv[i + 1];
    else if (!std::strcmp(argv[i], "--dump")) dump = argv[i + 1];
    else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  const FrictionLaw law = law_name == "adams" ? FrictionLaw::kContinuous : FrictionLaw::kStiction;
  std::vector<std::string> names;
  {
    std::stringstream ss(variants);
    for (std::string v; std::getline(ss, v, ',');) names.push_back(v);
  }
  const std::regex re(only);
  std::vector<ExperimentCase> cases;
  for (const Experiment& e : loadExperimentSuite(suite))
    if (inGap(e.name))
      for (const ExperimentCase& c : e.cases)
        if (std::regex_search(c.experiment + "/" + c.name, re)) cases.push_back(c);

  std::map<std::string, std::vector<Pair>> res;
  std::vector<std::string> case_names;
  std::vector<std::map<std::string, double>> extras;  // per case: tracking etc. of the default MuJoCo run
  for (const ExperimentCase& c0 : cases) {
    case_names.push_back(c0.experiment + "/" + c0.name);
    const TailTrajectory tr = c0.trajectory();
    Effects e = c0.effects;
    e.friction = law;
    OutputSettings out = c0.output;
    out.time_series = TimeSeriesOutput::kFull;
    out.sample_dt_s = 1e-3;
    PerFootSettings lt = c0.perfoot;
    lt.normal_loads = NormalLoadModel::kLoadTransfer;
    auto phiOf = [&](const RunResult& r, const char* what, const std::string& v) {
      if (!r.summary.ok)
        std::fprintf(stderr, "%s %s %s: %s\n", case_names.back().c_str(), v.c_str(), what, r.summary.error.c_str());
      return r.summary.ok ? r.summary.phi_net_deg : NAN;
    };
    RunResult mj0 = simulateMujoco(c0.robot, tr, c0.mujoco, e, out);
    const double p_lt = phiOf(simulatePerFoot(c0.robot, tr, lt, e, out), "perfoot", "base");
    extras.push_back(mj0.summary.extra);
    for (const std::string& v : names) {
      Pair p;
      MujocoSettings ms = c0.mujoco;
      RobotParams robot = c0.robot;
      Effects ev = e;
      bool own_mujoco = true, own_perfoot = false;
      PerFootSettings ps = lt;
      if (v == "base" || v == "qs" || v == "measured") {
        own_mujoco = false;
        p.mujoco = phiOf(mj0, "mujoco", v);
        if (v == "base") p.perfoot = p_lt;
        if (v == "qs") {
          ps.normal_loads = NormalLoadModel::kQuasiStatic;
          own_perfoot = true;
        }
        if (v == "measured" && mj0.summary.ok) {
          const RunResult r = simulatePerFoot(robot, tr, ps, ev, out, loadsOf(mj0.series));
          p.perfoot = phiOf(r, "perfoot", v);
          if (!dump.empty()) {
            std::string tag = case_names.back();
            for (char& ch : tag)
              if (ch == '/' || ch == ',' || ch == '=') ch = '_';
            writeCsvAtomic(dump + "/" + tag + "_mujoco.csv", mj0.series);
            writeCsvAtomic(dump + "/" + tag + "_perfoot_measured.csv", r.series);
          }
        }
      } else if ((v.rfind("h", 0) == 0 && v.size() > 1 && std::isdigit(v[1])) || v.rfind("stiff", 0) == 0) {
        const bool stiff = v[0] == 's';
        const double f = std::stod(v.substr(stiff ? 5 : 1));
        ms.timestep_s /= f;
        ms.servo_wn_dt /= f;
        if (stiff) ms.solref[0] /= f;
      } else if (v.rfind("torsion", 0) == 0) {
        ms.condim = 4;
        ms.torsional_friction_m = 1e-3 * std::stod(v.substr(7));
      } else if (v == "condim6") {
        ms.condim = 6;
      } else if (v == "capsule") {
        ms.foot_shape = MujocoFootShape::kCapsule;
      } else if (v == "box") {
        ms.foot_shape = MujocoFootShape::kBox;
      } else if (v == "impratio") {
        ms.impratio = 100;
      } else if (v == "softimp") {
        ms.impratio = 100;
        ms.noslip_iterations = 3;
        ms.solimp = {0.015, 0.9999, 0.031, 0.5, 2.0};
      } else if (v == "low") {
        robot.quadruped.com_height_m = 0.05;
        ms.body_height_m = 0.05;
        own_perfoot = true;
      } else if (v == "servo") {
        ms.servo_wn_dt *= 2.0;
      } else if (v == "noff") {
        ms.inverse_dynamics_feedforward = false;
      } else if (v == "nofric") {
        ev.friction = FrictionLaw::kNone;
        own_perfoot = true;
      } else {
        std::fprintf(stderr, "unknown variant %s\n", v.c_str());
        return 2;
      }
      if (own_mujoco) p.mujoco = phiOf(simulateMujoco(robot, tr, ms, ev, c0.output), "mujoco", v);
      if (own_perfoot) p.perfoot = phiOf(simulatePerFoot(robot, tr, ps, ev, c0.output), "perfoot", v);
      else if (std::isnan(p.perfoot) && v != "measured") p.perfoot = p_lt;
      res[v].push_back(p);
    }
    std::fflush(stderr);
  }

  // Gap of each variant: all cases, |phi_MuJoCo(base)| >= 1 deg, and the signed mean (perfoot - MuJoCo) / |MuJoCo|.
  std::printf("law %s, %zu cases; gap = |perfoot - MuJoCo| / |MuJoCo|; set: |phi_net,MuJoCo default| >= 1 deg\n",
              law_name.c_str(), cases.size());
  std::printf("%-10s %6s %10s %10s %12s %10s\n", "variant", "cases", "median", "max", "signed med.", "worst case");
  const std::vector<Pair>& base = res.count("base") ? res["base"] : res.begin()->second;
  for (const std::string& v : names) {
    std::vector<double> g, sg;
    double worst = -1;
    size_t wi = 0;
    for (size_t i = 0; i < res[v].size(); ++i) {
      const Pair& p = res[v][i];
      if (!(std::abs(base[i].mujoco) >= 1.0) || !std::isfinite(p.perfoot) || !std::isfinite(p.mujoco) || p.mujoco == 0)
        continue;
      const double r = std::abs(p.perfoot - p.mujoco) / std::abs(p.mujoco);
      g.push_back(r);
      sg.push_back((p.perfoot - p.mujoco) / std::abs(p.mujoco));
      if (r > worst) worst = r, wi = i;
    }
    std::printf("%-10s %6zu %9.2f%% %9.2f%% %11.2f%% %s\n", v.c_str(), g.size(), 100 * median(g),
                g.empty() ? NAN : 100 * *std::max_element(g.begin(), g.end()), 100 * median(sg),
                g.empty() ? "" : case_names[wi].c_str());
  }
  if (csv) {
    std::ofstream f(csv);
    f << "case";
    for (const std::string& v : names) f << ",perfoot_" << v << ",mujoco_" << v;
    f << ",tracking_rms_deg_j1,tracking_max_deg_j1,airborne_fraction\n";
    for (size_t i = 0; i < case_names.size(); ++i) {
      f << '"' << case_names[i] << '"';
      for (const std::string& v : names) f << "," << res[v][i].perfoot << "," << res[v][i].mujoco;
      auto x = [&](const char* k) { return extras[i].count(k) ? extras[i].at(k) : NAN; };
      f << "," << x("tracking_rms_deg_j1") << "," << x("tracking_max_deg_j1") << "," << x("airborne_fraction") << "\n";
    }
  }
  return 0;
}
