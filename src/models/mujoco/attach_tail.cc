#include "models/mujoco/attach_tail.h"

#include <tinyxml2.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include "controllers/tail_controller.h"
#include "results/columns.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/run_uncertainty.h"
#include "settings/units.h"

namespace tailsim {
namespace {

using tinyxml2::XMLElement;

constexpr double kPi = 3.14159265358979323846;
constexpr double kTailRadius = 0.012;  // visual capsule radius [m]

std::string nums(std::initializer_list<double> v) {
  std::string s;
  char b[40];
  for (double x : v) {
    std::snprintf(b, sizeof b, "%.17g", x);
    s += (s.empty() ? "" : " ") + std::string(b);
  }
  return s;
}

XMLElement* findBody(XMLElement* e, const std::string& name) {
  for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    if (std::string(c->Name()) == "body" && c->Attribute("name") && name == c->Attribute("name")) return c;
    if (XMLElement* f = findBody(c, name)) return f;
  }
  return nullptr;
}

double angleDeg(double cosine) { return units::degrees(std::acos(std::max(-1.0, std::min(1.0, cosine)))); }

// The body's z axis in the world (column 2 of its row-major xmat).
std::array<double, 3> bodyZ(const mjData* d, int body) {
  const double* R = d->xmat + 9 * body;
  return {R[2], R[5], R[8]};
}

double tiltDeg(const mjData* d, int body) { return angleDeg(d->xmat[9 * body + 8]); }

double tiltFromDeg(const mjData* d, int body, const std::array<double, 3>& z0) {
  const std::array<double, 3> z = bodyZ(d, body);
  return angleDeg(z[0] * z0[0] + z[1] * z0[1] + z[2] * z0[2]);
}

}  // namespace

std::string attachTail(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                       const MujocoSettings& s) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(r.model.xml.c_str()) != tinyxml2::XML_SUCCESS) throw RobotImportError("attachTail: the model does not parse");
  XMLElement* root = doc.RootElement();
  while (XMLElement* k = root->FirstChildElement("keyframe")) root->DeleteChild(k);
  const std::string bodyName = mount.body.empty() ? r.root_body : mount.body;
  XMLElement* parent = findBody(root->FirstChildElement("worldbody"), bodyName);
  if (!parent) throw RobotImportError(r.model.source + ": tail mount: no body named '" + bodyName + "'");
  // Tail frame: the mount body's frame turned about z so that x points backward (yaw + 180 deg).
  const double a = 0.5 * (mount.yaw_rad + kPi);
  XMLElement* link = nullptr;
  XMLElement* at = parent;
  RobotParams p;
  p.tail = tail;
  const ServoGains gains = tailServoGains(p, s);
  for (std::size_t i = 0; i < tail.size(); ++i) {
    const TailLink& l = tail[i];
    link = doc.NewElement("body");
    at->InsertEndChild(link);
    link->SetAttribute("name", mjcf::tailBodyName(static_cast<int>(i + 1)).c_str());
    if (i == 0) {
      link->SetAttribute("pos", nums({mount.pos_m[0], mount.pos_m[1], mount.pos_m[2]}).c_str());
      link->SetAttribute("quat", nums({std::cos(a), 0.0, 0.0, std::sin(a)}).c_str());
    } else {
      link->SetAttribute("pos", nums({tail[i - 1].length_m, 0.0, 0.0}).c_str());
    }
    XMLElement* in = doc.NewElement("inertial");
    link->InsertEndChild(in);
    in->SetAttribute("pos", nums({l.com_offset_m, 0.0, 0.0}).c_str());
    in->SetAttribute("mass", nums({l.mass_kg}).c_str());
    const std::array<double, 3> I = tailLinkDiagInertia(l);
    in->SetAttribute("diaginertia", nums({I[0], I[1], I[2]}).c_str());
    XMLElement* j = doc.NewElement("joint");
    link->InsertEndChild(j);
    j->SetAttribute("name", mjcf::tailJointName(static_cast<int>(i + 1)).c_str());
    j->SetAttribute("type", "hinge");
    j->SetAttribute("axis", "0 0 1");
    j->SetAttribute("limited", "false");
    j->SetAttribute("damping", "0");
    j->SetAttribute("armature", "0");
    j->SetAttribute("frictionloss", "0");
    XMLElement* g = doc.NewElement("geom");
    link->InsertEndChild(g);
    g->SetAttribute("name", ("tail_geom" + std::to_string(i + 1)).c_str());
    g->SetAttribute("type", "capsule");
    g->SetAttribute("fromto", nums({0.0, 0.0, 0.0, l.length_m, 0.0, 0.0}).c_str());
    g->SetAttribute("size", nums({kTailRadius}).c_str());
    g->SetAttribute("contype", 0);
    g->SetAttribute("conaffinity", 0);
    g->SetAttribute("mass", 0);
    g->SetAttribute("group", 1);
    g->SetAttribute("rgba", "0.85 0.45 0.1 1");
    at = link;
  }
  if (r.legs_locked) {
    // Each leg joint held at its stood angle (solref 0.002 s, critically damped; MuJoCo raises the
    // time constant to 2 timesteps where it is shorter).
    XMLElement* eq = doc.NewElement("equality");
    root->InsertEndChild(eq);
    for (const auto& [name, target] : r.hold_target_rad) {
      (void)target;
      XMLElement* e = doc.NewElement("joint");
      eq->InsertEndChild(e);
      e->SetAttribute("name", ("tailsim_lock_" + name).c_str());
      e->SetAttribute("joint1", name.c_str());
      e->SetAttribute("polycoef", nums({r.settled_qpos.at(name).at(0), 0.0, 0.0, 0.0, 0.0}).c_str());
      e->SetAttribute("solref", "0.002 1");
    }
  }
  XMLElement* act = root->FirstChildElement("actuator");
  if (!act) {
    act = doc.NewElement("actuator");
    root->InsertEndChild(act);
  }
  for (std::size_t i = 0; i < tail.size(); ++i) {
    XMLElement* g = doc.NewElement("general");
    act->InsertEndChild(g);
    g->SetAttribute("name", mjcf::tailActuatorName(static_cast<int>(i + 1)).c_str());
    g->SetAttribute("joint", mjcf::tailJointName(static_cast<int>(i + 1)).c_str());
    g->SetAttribute("ctrllimited", "false");
    g->SetAttribute("forcelimited", "false");
    g->SetAttribute("gainprm", nums({gains.kp[i]}).c_str());
    g->SetAttribute("biasprm", nums({0.0, -gains.kp[i], -gains.kv[i]}).c_str());
    g->SetAttribute("biastype", "affine");
    g->SetAttribute("gaintype", "fixed");
  }
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

namespace {

// The articulated run at s.timestep_s (the model's own, or the check run's twice that): the tail's
// servo gains from s, the model's option timestep replaced by s.timestep_s.
ArticulatedRun runArticulatedAt(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                                const TailTrajectory& trajectory, const MujocoSettings& s, double stand_s,
                                double settle_after_s, double sample_dt_s) {
  ArticulatedRun out;
  MujocoMessages messages;
  ModelPtr mp = loadModelFromXml(attachTail(r, mount, tail, s));
  mjModel* m = mp.get();
  m->opt.timestep = s.timestep_s;
  DataPtr dp = makeData(m);
  mjData* d = dp.get();
  const int n = static_cast<int>(tail.size());
  for (const auto& [name, q] : r.settled_qpos) {
    const int j = jointId(m, name);
    for (std::size_t k = 0; k < q.size(); ++k) d->qpos[m->jnt_qposadr[j] + k] = q[k];
  }
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const char* jn = mj_id2name(m, mjOBJ_JOINT, m->actuator_trnid[2 * a]);
    const auto t = jn ? r.hold_target_rad.find(jn) : r.hold_target_rad.end();
    if (t != r.hold_target_rad.end()) d->ctrl[a] = t->second;
  }
  std::vector<int> qadr, vadr, act, pdq, pdv;
  std::vector<double> pdTarget;
  for (int i = 1; i <= n; ++i) {
    const int j = jointId(m, mjcf::tailJointName(i));
    qadr.push_back(m->jnt_qposadr[j]);
    vadr.push_back(m->jnt_dofadr[j]);
    act.push_back(actuatorId(m, mjcf::tailActuatorName(i)));
  }
  for (const std::string& name : r.pd_joints) {
    const int j = jointId(m, name);
    pdq.push_back(m->jnt_qposadr[j]);
    pdv.push_back(m->jnt_dofadr[j]);
    pdTarget.push_back(r.hold_target_rad.at(name));
  }
  std::vector<JointState> ref0;
  trajectory.evaluate(0.0, ref0);
  for (int i = 0; i < n; ++i) d->qpos[qadr[i]] = ref0[i].theta;
  TailController ctrl(m, trajectory, qadr, vadr, act, {s.velocity_feedforward, s.inverse_dynamics_feedforward});
  mj_forward(m, d);
  const int body = bodyId(m, r.root_body);
  const std::array<double, 3> stanceZ = bodyZ(d, body);
  out.stance_tilt_deg = tiltDeg(d, body);
  if (r.mu_given) {
    for (const auto& [bodyName, k] : r.foot_geoms) m->geom_friction[3 * (m->body_geomadr[bodyId(m, bodyName)] + k)] = r.mu;
    m->geom_friction[3 * geomId(m, r.model.floor_geom)] = r.mu;
  }
  auto step = [&](double t_ref) {
    mj_step1(m, d);
    for (std::size_t k = 0; k < pdq.size(); ++k)
      d->qfrc_applied[pdv[k]] = kStancePdKp * (pdTarget[k] - d->qpos[pdq[k]]) - kStancePdKv * d->qvel[pdv[k]];
    ctrl.apply(m, d, t_ref, false);
    mj_step2(m, d);
    ++out.steps;
  };
  const double dt = m->opt.timestep;
  const long standSteps = std::lround(stand_s / dt);
  for (long k = 0; k < standSteps && out.ok; ++k) {
    step(0.0);
    out.stand_max_tilt_deg = std::max(out.stand_max_tilt_deg, tiltDeg(d, body));
    out.stand_max_rel_tilt_deg = std::max(out.stand_max_rel_tilt_deg, tiltFromDeg(d, body, stanceZ));
    if (warningCount(d)) out.ok = false, out.error = "MuJoCo warnings while standing: " + describeWarnings(d);
  }
  out.stand_s = stand_s;
  out.stand_end_tilt_deg = tiltDeg(d, body);
  out.stand_end_rel_tilt_deg = tiltFromDeg(d, body, stanceZ);
  for (const auto& [bodyName, k] : r.foot_geoms) {
    const int g = m->body_geomadr[bodyId(m, bodyName)] + k;
    bool touching = false;
    for (int i = 0; i < d->ncon; ++i) touching = touching || d->contact[i].geom1 == g || d->contact[i].geom2 == g;
    out.feet_in_contact += touching;
  }
  auto yaw = [&] { return std::atan2(d->xmat[9 * body + 3], d->xmat[9 * body]); };
  const double yaw0 = yaw();
  double phi = 0.0, prev = yaw0;
  const double t_end = trajectory.endTime() + settle_after_s;
  const long runSteps = std::lround(t_end / dt);
  // Rows on the output grid (the sample nearest each grid time: the step that reaches it).
  std::vector<int> colTheta, colThetadot, colTrack;
  int colT = -1, colX = -1, colY = -1, colPhi = -1, colPhidot = -1;
  if (sample_dt_s > 0.0) {
    colT = out.series.addColumn(col::kT);
    for (int i = 1; i <= n; ++i) colTheta.push_back(out.series.addColumn(col::theta(i)));
    for (int i = 1; i <= n; ++i) colThetadot.push_back(out.series.addColumn(col::thetadot(i)));
    colX = out.series.addColumn(col::kX);
    colY = out.series.addColumn(col::kY);
    colPhi = out.series.addColumn(col::kPhi);
    colPhidot = out.series.addColumn(col::kPhidot);
    for (int i = 1; i <= n; ++i) colTrack.push_back(out.series.addColumn(col::trackErr(i)));
  }
  const double* root = d->xpos + 3 * body;
  const double x0 = root[0], y0 = root[1];
  long nextRow = 0;
  std::vector<double> row(out.series.numColumns());
  std::vector<JointState> ref;
  auto record = [&](double t) {
    if (sample_dt_s <= 0.0) return;
    while (nextRow * sample_dt_s <= t + 0.5 * dt && nextRow * sample_dt_s <= t_end + 1e-9 * sample_dt_s) {
      trajectory.evaluate(t, ref);
      row[colT] = nextRow * sample_dt_s;
      for (int i = 0; i < n; ++i) {
        row[colTheta[i]] = units::degrees(d->qpos[qadr[i]]);
        row[colThetadot[i]] = units::degrees(d->qvel[vadr[i]]);
        row[colTrack[i]] = units::degrees(d->qpos[qadr[i]] - ref[i].theta);
      }
      row[colX] = root[0] - x0;
      row[colY] = root[1] - y0;
      row[colPhi] = units::degrees(phi);
      row[colPhidot] = units::degrees(d->cvel[6 * body + 2]);  // world-frame angular velocity z (com-based)
      out.series.appendRow(row);
      ++nextRow;
    }
  };
  record(0.0);
  for (long k = 0; k < runSteps && out.ok; ++k) {
    step((k + 1) * dt);
    const double y = yaw();
    phi += std::remainder(y - prev, 2 * kPi);
    prev = y;
    record((k + 1) * dt);
    out.max_tilt_deg = std::max(out.max_tilt_deg, tiltDeg(d, body));
    out.max_rel_tilt_deg = std::max(out.max_rel_tilt_deg, tiltFromDeg(d, body, stanceZ));
    if (warningCount(d)) out.ok = false, out.error = "MuJoCo warnings during the stroke: " + describeWarnings(d);
  }
  out.run_s = t_end;
  out.phi_net_deg = units::degrees(phi);
  {
    const double* v = d->cvel + 6 * body;  // [angular; linear] at the subtree COM, world frame
    out.at_rest = units::degrees(std::abs(v[2])) < 0.1 && std::hypot(v[3], v[4]) < 1e-3;
  }
  if (out.stand_max_rel_tilt_deg >= kStandingTiltLimitDeg)
    out.warnings.push_back("the body tilted up to " + std::to_string(out.stand_max_rel_tilt_deg) + " deg from its stance (" +
                           std::to_string(out.stand_max_tilt_deg) + " deg absolute) while standing with the tail");
  if (!messages.text().empty()) out.warnings.push_back(messages.text());
  return out;
}

// The settings at the model's own timestep.
MujocoSettings atModelTimestep(const DerivedRobot& r, const MujocoSettings& s_in) {
  MujocoSettings s = s_in;
  s.timestep_s = loadModelFromXml(r.model.xml)->opt.timestep;
  return s;
}

}  // namespace

ArticulatedRun runArticulated(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                              const TailTrajectory& trajectory, const MujocoSettings& s, double stand_s,
                              double settle_after_s, double sample_dt_s) {
  return runArticulatedAt(r, mount, tail, trajectory, atModelTimestep(r, s), stand_s, settle_after_s, sample_dt_s);
}

RunResult articulatedRunResult(const ArticulatedRun& a, const std::string& model) {
  RunResult r;
  RunSummary& s = r.summary;
  s.model = model;
  s.ok = a.ok;
  s.error = a.error;
  s.phi_net_deg = a.phi_net_deg;
  s.t_stop_s = a.run_s;
  s.solver_steps = a.steps;
  s.at_rest = a.at_rest;
  s.warnings = a.warnings;
  s.extra["stance_tilt_deg"] = a.stance_tilt_deg;
  s.extra["stand_end_tilt_from_stance_deg"] = a.stand_end_rel_tilt_deg;
  s.extra["stand_max_tilt_from_stance_deg"] = a.stand_max_rel_tilt_deg;
  s.extra["stroke_max_tilt_from_stance_deg"] = a.max_rel_tilt_deg;
  s.extra["feet_in_contact"] = a.feet_in_contact;
  r.series = a.series;
  return r;
}

RunResult simulateArticulated(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                              const TailTrajectory& trajectory, const MujocoSettings& s_in, double stand_s,
                              double settle_after_s, double sample_dt_s, const std::string& model,
                              ArticulatedRun* run) {
  const auto wall0 = std::chrono::steady_clock::now();
  const MujocoSettings s = atModelTimestep(r, s_in);
  ArticulatedRun a = runArticulatedAt(r, mount, tail, trajectory, s, stand_s, settle_after_s, sample_dt_s);
  RunResult res = articulatedRunResult(a, model);
  if (s.uncertainty && a.ok) {
    const MujocoSettings coarse = checkRunSettings(s);
    RunSummary check;
    try {
      check = articulatedRunResult(runArticulatedAt(r, mount, tail, trajectory, coarse, stand_s, settle_after_s, 0.0),
                                   model).summary;
    } catch (const std::exception& e) {
      check.ok = false;
      check.error = e.what();
    }
    applyCheckRun(res.summary, check, coarse.timestep_s,
                  s.uncertainty_warn_share, "lower the timestep of the model's <option> (the model file's own step)");
  }
  res.summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (run) *run = std::move(a);
  return res;
}

}  // namespace tailsim
