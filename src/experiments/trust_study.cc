#include "common/number_text.h"
#include "experiments/trust_study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>

#include "experiments/model_registry.h"
#include "experiments/verdict.h"
#include "models/mujoco/mujoco_simulation.h"

namespace tailsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(const char* f, double x) { return std::isfinite(x) ? formatNumber(f, x) : "n/a"; }

// One variant of the case's MuJoCo settings or stroke.
struct Variant {
  std::string group, setting;
  std::function<void(ExperimentCase&)> apply;
};

// Finer or coarser step with the servo's natural frequency kept (as the uncertainty's check run).
void scaleStep(MujocoSettings& m, double factor) {
  m.timestep_s *= factor;
  if (m.kp == 0.0) m.servo_wn_dt *= factor;
}

std::vector<Variant> variants(const ExperimentCase& c) {
  const MujocoSettings& m = c.mujoco;
  std::vector<Variant> v;
  for (double f : {2.0, 0.5, 0.25})
    v.push_back({"timestep", "timestep_s = " + fmt("%.3g", m.timestep_s * f) + " s",
                 [f](ExperimentCase& x) { scaleStep(x.mujoco, f); }});
  for (double f : {0.5, 2.0})
    v.push_back({"contact", "solref time constant = " + fmt("%.3g", m.solref[0] * f) + " s",
                 [f](ExperimentCase& x) { x.mujoco.solref[0] *= f; }});
  for (double f : {0.5, 2.0})
    v.push_back({"contact", "solimp width = " + fmt("%.3g", m.solimp[2] * f) + " m",
                 [f](ExperimentCase& x) { x.mujoco.solimp[2] *= f; }});
  v.push_back({"contact", "impratio = 1", [](ExperimentCase& x) { x.mujoco.impratio = 1.0; }});
  v.push_back({"contact", "noslip_iterations = 3", [](ExperimentCase& x) { x.mujoco.noslip_iterations = 3; }});
  if (!c.joints.empty())
    for (double d : {1e-6, -1e-6, 1e-5})
      v.push_back({"jitter", "stroke dT " + fmt("%+.0f", d * 1e6) + " us", [d](ExperimentCase& x) {
                     for (SplitCycleParams& j : x.joints) j.dT_s += d;
                   }});
  v.push_back({"reference",
               "timestep_s = " + fmt("%.3g", m.timestep_s / 8) + " s, impratio = " +
                   fmt("%.3g", std::max(m.impratio, 100.0)) + ", noslip_iterations = " +
                   std::to_string(std::max(m.noslip_iterations, 3)),
               [](ExperimentCase& x) {
                 scaleStep(x.mujoco, 1.0 / 8);
                 x.mujoco.impratio = std::max(x.mujoco.impratio, 100.0);
                 x.mujoco.noslip_iterations = std::max(x.mujoco.noslip_iterations, 3);
               }});
  return v;
}

TrustRow rowOf(const std::string& group, const std::string& setting, const RunSummary& s) {
  TrustRow r;
  r.group = group;
  r.setting = setting;
  r.model = s.model;
  r.ok = s.ok;
  r.failure = s.error;
  r.phi_net_deg = s.ok ? s.phi_net_deg : kNaN;
  r.wall_s = s.wall_time_s;
  r.steps = s.solver_steps;
  if (const auto c = s.extra.find("uncertainty_solver_steps"); c != s.extra.end())
    r.check_steps = static_cast<long>(c->second);
  const auto u = s.extra.find("phi_net_uncertainty_deg");
  r.uncertainty_deg = u != s.extra.end() ? u->second : kNaN;
  return r;
}

RunSummary runMujocoCase(const ExperimentCase& c) {
  OutputSettings out = c.output;
  out.time_series = TimeSeriesOutput::kNone;
  try {
    return simulateMujoco(c.robot, c.trajectory(), c.mujoco, c.effects, out).summary;
  } catch (const std::exception& e) {
    RunSummary s;
    s.model = "mujoco";
    s.ok = false;
    s.error = e.what();
    return s;
  }
}

}  // namespace

const TrustRow* TrustStudy::row(const std::string& group) const {
  for (const TrustRow& r : rows)
    if (r.group == group) return &r;
  return nullptr;
}

std::vector<TrustStudy> runTrustStudy(const Experiment& e, const TrustOptions& options) {
  std::vector<const ExperimentCase*> cases;
  for (const ExperimentCase& c : e.cases)
    if (c.kind == CaseKind::kSimulate && (options.only_case.empty() || c.name == options.only_case)) cases.push_back(&c);
  if (cases.empty())
    throw ConfigError(e.source_file + ": " +
                      (options.only_case.empty() ? std::string("no simulate case to study")
                                                 : "no simulate case is named " + options.only_case));
  std::vector<TrustStudy> out;
  for (const ExperimentCase* cp : cases) {
    TrustStudy st;
    st.case_name = cp->name;
    ExperimentCase base = *cp;
    base.mujoco.uncertainty = true;
    const RunSummary def = runMujocoCase(base);
    st.rows.push_back(rowOf("default", "the case's settings (with its uncertainty check at 2 timestep_s)", def));
    std::vector<RunSummary> models{def};
    for (const Variant& v : variants(*cp)) {
      ExperimentCase x = *cp;
      x.mujoco.uncertainty = false;
      v.apply(x);
      st.rows.push_back(rowOf(v.group, v.setting, runMujocoCase(x)));
    }
    // The planar models (cheap): the case's own settings.
    for (const char* name : {"analytic", "perfoot"}) {
      const ModelEntry* m = findModel(name);
      if (!m) continue;
      const RunSummary s = m->run(*cp, nullptr).summary;
      st.rows.push_back(rowOf("planar", std::string(name) + " model at the case's settings", s));
      models.push_back(s);
    }
    st.verdict = caseVerdict(models);
    out.push_back(std::move(st));
  }
  return out;
}

}  // namespace tailsim
