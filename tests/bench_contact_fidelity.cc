// MuJoCo contact fidelity (docs/mujoco-model.md "Contact fidelity"): for each
// candidate contact setting, how far MuJoCo's soft convex contact is from rigid Coulomb friction
// at four point feet. Prints one Markdown table row per candidate:
//   build/tests/bench_contact_fidelity [NAME..]   (about 30 s a candidate on one core)
// NAME..: only the default and the candidates whose name contains one of them, e.g. "feet".
// Columns:
//  * airborne, peak Fn/mg: summary extras `airborne_fraction`, `peak_normal_force_over_mg` of the
//    Fig. 7 case (configs/default.yaml: 1 link, d_Q2B 0.125 m, -90 deg in 0.25 s) and of Fig. 6a
//    (configs/paper/fig06a_model_comparison_1dof.yaml: the same stroke at d_Q2B 0.1405 m);
//  * creep: the body standing with the tail held still, a steady pure moment (xfrc_applied on the
//    quadruped body) of 0.9x the per-foot breakaway moment for 1 s; the fastest foot's mean speed
//    over t = 0.2 .. 1 s [um/s] (rigid Coulomb friction: 0);
//  * M_break ratio / F_break ratio: a pure moment (a pure force along x at the body COM) ramped
//    from 0 at 20 % of its prediction per second; breakaway = the first step a foot slips faster than 1 mm/s;
//    ratio to the per-foot limit-surface prediction (loadFactor of the four discs mu N_i, with
//    MuJoCo's own settled N_i and foot positions);
//  * phi_net(h) and its relative change at h/2 (servo_wn_dt halved too: the same servo);
//  * gap: |phi_net(MuJoCo) - phi_net(per-foot, stiction, quasi-static loads)| / |phi_net(per-foot)| on Fig. 7.
// Not a benchmark of speed; a plain main() (linked like the other bench_* files).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "models/perfoot/per_foot_model.h"
#include "experiments/experiment_loader.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;

namespace {

struct Candidate {
  const char* name;
  std::function<void(MujocoSettings&)> apply;
};

ExperimentCase firstCase(const std::string& path) {
  return loadExperiment(path).cases.at(0);
}

// The standing robot (tail held at 0) under an external load on the quadruped body that grows as
// load(t) (a pure moment about z, or a pure force along x at the body COM).
struct StandTest {
  double fastest_foot_mps = 0.0;  // creep: mean speed of the fastest foot over [t0, t1]
  double break_load = NAN;        // ramp: load when a foot first slips faster than 1 mm/s
  double predicted = NAN;         // per-foot limit surface prediction for this load direction
  double sum_mu_N_r = NAN;        // sum mu N_i |r_i| about the body COM (pure moment bound)
};

StandTest standTest(const ExperimentCase& c, const MujocoSettings& s, bool moment, double ramp_per_s,
                    double steady_factor, double duration_s) {
  const std::string xml = generateMjcf(c.robot, s, c.effects);
  ModelPtr model = loadModelFromXml(xml);
  mjModel* m = model.get();
  DataPtr data = makeData(m);
  mjData* d = data.get();
  mj_resetDataKeyframe(m, d, mj_name2id(m, mjOBJ_KEY, mjcf::kHomeKey));
  const int body = bodyId(m, mjcf::kQuadrupedBody);
  int foot[4];
  for (int k = 0; k < 4; ++k) foot[k] = geomId(m, mjcf::footGeomName(k + 1));
  for (int a = 0; a < m->nu; ++a) d->ctrl[a] = 0.0;  // tail held straight (theta = 0)
  // Settle 0.3 s.
  while (d->time < 0.3) mj_step(m, d);
  // Settled normal loads and foot positions (relative to the body COM).
  const double mu = footFrictionCoefficient(c.robot, s, c.effects);
  FootDiscs discs;
  StandTest out;
  out.sum_mu_N_r = 0.0;
  const double* com = d->xipos + 3 * body;
  for (int i = 0; i < d->ncon; ++i) {
    for (int k = 0; k < 4; ++k) {
      if (d->contact[i].geom1 != foot[k] && d->contact[i].geom2 != foot[k]) continue;
      mjtNum f6[6];
      mj_contactForce(m, d, i, f6);
      discs.c[k] += mu * f6[0];
    }
  }
  for (int k = 0; k < 4; ++k) {
    discs.r[k] = Vec2(d->geom_xpos[3 * foot[k]] - com[0], d->geom_xpos[3 * foot[k] + 1] - com[1]);
    out.sum_mu_N_r += discs.c[k] * discs.r[k].norm();
  }
  Wrench2 unit;
  if (moment) unit.M = 1.0;
  else unit.F = Vec2(1.0, 0.0);
  out.predicted = 1.0 / loadFactor(discs, unit).s;

  // Load: steady (steady_factor * predicted) or ramped (ramp_per_s * predicted * t).
  const double t0 = d->time;
  double p0[4][2], pmid[4][2];
  for (int k = 0; k < 4; ++k) p0[k][0] = d->geom_xpos[3 * foot[k]], p0[k][1] = d->geom_xpos[3 * foot[k] + 1];
  bool mid_taken = false;
  const double t_mid = 0.2;
  while (d->time - t0 < duration_s) {
    const double t = d->time - t0;
    const double load = out.predicted * (steady_factor > 0.0 ? steady_factor : ramp_per_s * t);
    for (int j = 0; j < 6; ++j) d->xfrc_applied[6 * body + j] = 0.0;
    if (moment) d->xfrc_applied[6 * body + 5] = load;
    else d->xfrc_applied[6 * body + 0] = load;
    mj_step(m, d);
    if (!mid_taken && t >= t_mid) {
      for (int k = 0; k < 4; ++k)
        pmid[k][0] = d->geom_xpos[3 * foot[k]], pmid[k][1] = d->geom_xpos[3 * foot[k] + 1];
      mid_taken = true;
    }
    if (steady_factor <= 0.0 && std::isnan(out.break_load)) {
      for (int k = 0; k < 4; ++k) {
        mjtNum v6[6];
        mj_objectVelocity(m, d, mjOBJ_GEOM, foot[k], v6, 0);
        if (std::hypot(v6[3], v6[4]) > 1e-3) out.break_load = load;
      }
      if (!std::isnan(out.break_load)) break;
    }
  }
  if (steady_factor > 0.0) {
    const double span = d->time - t0 - t_mid;
    for (int k = 0; k < 4; ++k) {
      const double dx = d->geom_xpos[3 * foot[k]] - pmid[k][0], dy = d->geom_xpos[3 * foot[k] + 1] - pmid[k][1];
      out.fastest_foot_mps = std::max(out.fastest_foot_mps, std::hypot(dx, dy) / span);
    }
  }
  (void)p0;
  return out;
}

double extra(const RunResult& r, const char* key) {
  auto it = r.summary.extra.find(key);
  return it == r.summary.extra.end() ? NAN : it->second;
}

}  // namespace

int main(int argc, char** argv) {
  const ExperimentCase fig7 = firstCase(TAILSIM_SOURCE_DIR "/configs/default.yaml");
  const ExperimentCase fig6 = firstCase(TAILSIM_SOURCE_DIR "/configs/paper/fig06a_model_comparison_1dof.yaml");
  const double perfoot7 =
      simulatePerFoot(fig7.robot, fig7.trajectory(), fig7.perfoot, fig7.effects, fig7.output).summary.phi_net_deg;
  std::printf("Fig. 7 per-foot model (stiction, %s loads): phi_net %.3f deg\n\n",
              fig7.perfoot.normal_loads == NormalLoadModel::kQuasiStatic ? "quasi-static" : "load-transfer",
              perfoot7);

  const std::vector<Candidate> candidates = {
      {"default (elliptic, impratio 1, condim 3, noslip 0, solref 0.002)", [](MujocoSettings&) {}},
      {"pyramidal cone", [](MujocoSettings& s) { s.cone = MujocoCone::kPyramidal; }},
      {"impratio 100", [](MujocoSettings& s) { s.impratio = 100.0; }},
      {"impratio 100, condim 6", [](MujocoSettings& s) { s.impratio = 100.0, s.condim = 6; }},
      {"Menagerie: impratio 100, condim 6, solimp 0.015 0.9999 0.031",
       [](MujocoSettings& s) { s.impratio = 100.0, s.condim = 6, s.solimp = {0.015, 0.9999, 0.031, 0.5, 2.0}; }},
      {"noslip 1", [](MujocoSettings& s) { s.noslip_iterations = 1; }},
      {"noslip 2", [](MujocoSettings& s) { s.noslip_iterations = 2; }},
      {"noslip 3", [](MujocoSettings& s) { s.noslip_iterations = 3; }},
      {"solref 0.005", [](MujocoSettings& s) { s.solref[0] = 0.005; }},
      {"solref 0.01", [](MujocoSettings& s) { s.solref[0] = 0.01; }},
      {"impratio 100, noslip 3", [](MujocoSettings& s) { s.impratio = 100.0, s.noslip_iterations = 3; }},
      {"solimp 0.015 0.9999 0.031 (only)", [](MujocoSettings& s) { s.solimp = {0.015, 0.9999, 0.031, 0.5, 2.0}; }},
      {"impratio 100, noslip 3, solimp 0.015 0.9999 0.031",
       [](MujocoSettings& s) { s.impratio = 100.0, s.noslip_iterations = 3, s.solimp = {0.015, 0.9999, 0.031, 0.5, 2.0}; }},
      {"solref 0.001", [](MujocoSettings& s) { s.solref[0] = 0.001; }},
      {"capsule feet (r 0.01, half-length 0.01 along x)", [](MujocoSettings& s) { s.foot_shape = MujocoFootShape::kCapsule; }},
      {"box feet (cube, half-size 0.01)", [](MujocoSettings& s) { s.foot_shape = MujocoFootShape::kBox; }},
  };
  std::printf(
      "| candidate | Fig. 7 airborne | Fig. 7 peak Fn/mg | Fig. 6a airborne | Fig. 6a peak Fn/mg | creep at 0.9 M_break "
      "[um/s] | M_break / per-foot | F_break / per-foot | Fig. 7 phi_net [deg] | change at h/2 | Fig. 6a phi_net [deg] | "
      "gap to per-foot (Fig. 7) | Fig. 7 max height change [mm] |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Candidate& cand : candidates) {
    // Arguments: run only the default and the candidates whose name contains one of them.
    bool wanted = argc < 2 || &cand == &candidates.front();
    for (int i = 1; i < argc; ++i) wanted = wanted || std::strstr(cand.name, argv[i]) != nullptr;
    if (!wanted) continue;
    MujocoSettings s = fig7.mujoco;
    cand.apply(s);
    const RunResult r7 = simulateMujoco(fig7.robot, fig7.trajectory(), s, fig7.effects, fig7.output);
    MujocoSettings half = s;
    half.timestep_s *= 0.5;
    half.servo_wn_dt *= 0.5;
    const RunResult r7h = simulateMujoco(fig7.robot, fig7.trajectory(), half, fig7.effects, fig7.output);
    MujocoSettings s6 = fig6.mujoco;
    cand.apply(s6);
    const RunResult r6 = simulateMujoco(fig6.robot, fig6.trajectory(), s6, fig6.effects, fig6.output);
    const StandTest creep = standTest(fig7, s, true, 0.0, 0.9, 1.0);
    const StandTest mramp = standTest(fig7, s, true, 0.2, 0.0, 7.0);   // 20 % of the prediction per s
    const StandTest framp = standTest(fig7, s, false, 0.2, 0.0, 7.0);
    const double p7 = r7.summary.phi_net_deg, p7h = r7h.summary.phi_net_deg;
    std::printf("| %s | %.1f %% | %.2f | %.1f %% | %.2f | %.3g | %.3f | %.3f | %.3f | %+.2f %% | %.3f | %.1f %% | %.2f |%s\n",
                cand.name, 100 * extra(r7, "airborne_fraction"), extra(r7, "peak_normal_force_over_mg"),
                100 * extra(r6, "airborne_fraction"), extra(r6, "peak_normal_force_over_mg"),
                1e6 * creep.fastest_foot_mps, mramp.break_load / mramp.predicted, framp.break_load / framp.predicted,
                p7, 100 * (p7h - p7) / std::abs(p7), r6.summary.phi_net_deg, 100 * std::abs(p7 - perfoot7) / std::abs(perfoot7), 1e3 * extra(r7, "max_height_change_m"),
                r7.summary.ok && r6.summary.ok ? "" : " (a run failed)");
    std::fflush(stdout);
    if (&cand == &candidates.front())
      std::fprintf(stderr, "prediction: M_break %.4f N m (sum mu N_i r_i about the body COM %.4f), F_break %.4f N\n",
                   mramp.predicted, mramp.sum_mu_N_r, framp.predicted);
  }
  return 0;
}
