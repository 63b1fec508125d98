#include "models/mujoco/attach_tail.h"

#include <tinyxml2.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>

#include "controllers/tail_controller.h"
#include "results/columns.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/run_uncertainty.h"
#include "models/mujoco/step_schedule.h"
#include "common/units.h"

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

namespace {

// Stage: the tail's bodies under `parent`: tail_link1..n with their inertials, hinges about z and
// visual capsules; the first at the mount, turned so that x points backward (yaw + 180 deg).
void addTailLinks(tinyxml2::XMLDocument& doc, XMLElement* parent, const TailMount& mount, const std::vector<TailLink>& tail) {
  const double a = 0.5 * (mount.yaw_rad + kPi);
  XMLElement* at = parent;
  for (std::size_t i = 0; i < tail.size(); ++i) {
    const TailLink& l = tail[i];
    XMLElement* link = doc.NewElement("body");
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
}

// Stage: each leg joint held at its stood angle by a joint equality (solref 0.002 s, critically
// damped; MuJoCo raises the time constant to 2 timesteps where it is shorter).
void lockLegs(tinyxml2::XMLDocument& doc, XMLElement* root, const DerivedRobot& r) {
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

// Stage: one PD servo per tail joint (tail_motor<i>: a <general> actuator, affine bias) with gains.
void addTailServos(tinyxml2::XMLDocument& doc, XMLElement* root, std::size_t links, const ServoGains& gains) {
  XMLElement* act = root->FirstChildElement("actuator");
  if (!act) {
    act = doc.NewElement("actuator");
    root->InsertEndChild(act);
  }
  for (std::size_t i = 0; i < links; ++i) {
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
}

}  // namespace

// Stages: parse the robot's model, drop its keyframes, the tail's links under the mount body, the
// legs' locks (legs: locked), the tail's servos.
std::string attachTail(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                       const MujocoSettings& s) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(r.model.xml.c_str()) != tinyxml2::XML_SUCCESS) throw RobotImportError("attachTail: the model does not parse");
  XMLElement* root = doc.RootElement();
  while (XMLElement* k = root->FirstChildElement("keyframe")) root->DeleteChild(k);
  const std::string bodyName = mount.body.empty() ? r.root_body : mount.body;
  XMLElement* parent = findBody(root->FirstChildElement("worldbody"), bodyName);
  if (!parent) throw RobotImportError(r.model.source + ": tail mount: no body named '" + bodyName + "'");
  addTailLinks(doc, parent, mount, tail);
  if (r.legs_locked) lockLegs(doc, root, r);
  RobotParams p;
  p.tail = tail;
  addTailServos(doc, root, tail.size(), tailServoGains(p, s));
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

namespace {

// The articulated model in its stance, with the indices every stage needs.
struct ArticulatedSim {
  ModelPtr model;
  DataPtr data;
  mjModel* m = nullptr;
  mjData* d = nullptr;
  int n = 0;                              // tail links
  int body = -1;                          // the root body
  std::vector<int> qadr, vadr, act;       // the tail's joints and actuators
  std::vector<int> pdq, pdv;              // joints held by tailsim's PD
  std::vector<double> pdTarget;           // their set-points [rad]
  std::vector<double> pdLimit;            // their torque limits (HUGE_VAL: none) [N m]
  std::vector<double> pdStance;           // their angles in the settled stance [rad]
  std::vector<int> servoAct, servoQ;      // leg joints held by the model's position actuators
  std::vector<double> servoStance;        // their angles in the settled stance [rad]
  std::vector<double> servoHold, pdHold;  // the set-points the robot stood with (the stance's angles) [rad]
  std::array<double, 3> stanceZ{};        // the root body's z axis in the settled stance
};

// Stage: the model with the tail at s.timestep_s, in the settled stance, legs held at their stance
// angles, the tail at theta(0), friction from the user's mu.
void buildArticulated(ArticulatedSim& a, const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                      const TailTrajectory& trajectory, const MujocoSettings& s) {
  a.model = loadModelFromXml(attachTail(r, mount, tail, s));
  mjModel* m = a.m = a.model.get();
  m->opt.timestep = s.timestep_s;
  a.data = makeData(m);
  mjData* d = a.d = a.data.get();
  a.n = static_cast<int>(tail.size());
  for (const auto& [name, q] : r.settled_qpos) {
    const int j = jointId(m, name);
    for (std::size_t k = 0; k < q.size(); ++k) d->qpos[m->jnt_qposadr[j] + k] = q[k];
  }
  for (int u = 0; u < m->nu; ++u) {
    if (!isPositionServo(m, u)) continue;  // a motor's ctrl is a torque, not a set-point: it stays 0
    const char* jn = mj_id2name(m, mjOBJ_JOINT, m->actuator_trnid[2 * u]);
    const auto t = jn ? r.hold_target_rad.find(jn) : r.hold_target_rad.end();
    if (t == r.hold_target_rad.end()) continue;
    d->ctrl[u] = servoCtrlFor(m, u, t->second);
    a.servoAct.push_back(u);
    a.servoQ.push_back(m->jnt_qposadr[m->actuator_trnid[2 * u]]);
    a.servoStance.push_back(r.settled_qpos.at(jn).at(0));
    a.servoHold.push_back(t->second);
  }
  for (int i = 1; i <= a.n; ++i) {
    const int j = jointId(m, mjcf::tailJointName(i));
    a.qadr.push_back(m->jnt_qposadr[j]);
    a.vadr.push_back(m->jnt_dofadr[j]);
    a.act.push_back(actuatorId(m, mjcf::tailActuatorName(i)));
  }
  std::vector<int> pdJoints;
  for (const std::string& name : r.pd_joints) {
    const int j = jointId(m, name);
    pdJoints.push_back(j);
    a.pdq.push_back(m->jnt_qposadr[j]);
    a.pdv.push_back(m->jnt_dofadr[j]);
    a.pdTarget.push_back(r.hold_target_rad.at(name));
    const auto lim = r.pd_torque_limit_Nm.find(name);
    a.pdLimit.push_back(lim == r.pd_torque_limit_Nm.end() ? HUGE_VAL : lim->second);
    a.pdStance.push_back(r.settled_qpos.at(name).at(0));
    a.pdHold.push_back(a.pdTarget.back());
  }
  addStancePdDamping(m, pdJoints);
  std::vector<JointState> ref0;
  trajectory.evaluate(0.0, ref0);
  for (int i = 0; i < a.n; ++i) d->qpos[a.qadr[i]] = ref0[i].theta;
  mj_forward(m, d);
  a.body = bodyId(m, r.root_body);
  a.stanceZ = bodyZ(d, a.body);
  if (r.mu_given) {
    for (const auto& [bodyName, k] : r.foot_geoms) m->geom_friction[3 * (m->body_geomadr[bodyId(m, bodyName)] + k)] = r.mu;
    m->geom_friction[3 * geomId(m, r.model.floor_geom)] = r.mu;
  }
}

double legServoWnH(const ArticulatedSim& a);

// A fall: the body tilted more than kFallTiltFromStanceDeg from its stance. Sets the run's error
// (phase: while what) and returns true. Where a leg servo is too stiff for the step (w_n h > 1, the
// rest schedule's guard), the explicit spring may have thrown the body over: the message says so.
bool fell(const ArticulatedSim& a, double tilt_deg, const char* phase, std::string& error) {
  if (tilt_deg <= kFallTiltFromStanceDeg) return false;
  error = "the robot fell over: its body tilted " + std::to_string(tilt_deg) + " deg from its stance (limit " +
          std::to_string(kFallTiltFromStanceDeg) + " deg) " + phase;
  if (const double wh = legServoWnH(a); wh > 1.0) {
    char b[320];
    std::snprintf(b, sizeof b,
                  "; its stiffest leg servo has w_n h = %.3g > 1 at the model's timestep (%g s), so the step, not the "
                  "robot's balance, may be what threw it: run it again with a smaller <option timestep>",
                  wh, a.m->opt.timestep);
    error += b;
  }
  return true;
}

// One step: the legs' PD spring (for joints no actuator holds), the tail's controller at t_ref.
void stepArticulated(ArticulatedSim& a, TailController& ctrl, double t_ref, long& steps) {
  mj_step1(a.m, a.d);
  for (std::size_t k = 0; k < a.pdq.size(); ++k)
    a.d->qfrc_applied[a.pdv[k]] = stancePdTorque(a.pdTarget[k], a.d->qpos[a.pdq[k]], a.pdLimit[k]);  // its damper: dof_damping
  ctrl.apply(a.m, a.d, t_ref, false);
  mj_step2(a.m, a.d);
  ++steps;
}

// Stage: the legs' set-points trimmed for the tail's weight. A position servo holding a static load
// tau sags by tau / kp. Each round stands kTrimRoundS, then moves every held joint's set-point (the
// model's actuator's ctrl, or tailsim's PD target) by kTrimGain times that joint's remaining error
// from its settled-stance angle. With the feet on the floor the legs form closed chains, so a full
// step (gain 1) overshoots and diverges on ANYmal C; half a step converges on Go1 and ANYmal C.
// The body's tilt from the stance decides: the rounds end when it is below kTrimTiltTolDeg, when a
// round improved it by less than 10 %, or after kTrimRounds; a round that made it worse is undone
// (state and set-points as before it; its steps still count as work). An actuator's ctrlrange
// clamps its set-point. With legs locked by equality constraints there is nothing to trim. The
// ctrl change is how a robot's own controller (gravity compensation, or an integrator) holds a pose
// under a new load.
StanceTrim trimStance(ArticulatedSim& a, TailController& ctrl, bool legs_locked, long& steps, std::string& error) {
  StanceTrim t;
  if (legs_locked || (a.servoAct.empty() && a.pdq.empty())) return t;
  const long roundSteps = std::max(1L, std::lround(kTrimRoundS / a.m->opt.timestep));
  auto jointError = [&] {
    double e = 0.0;
    for (std::size_t k = 0; k < a.servoQ.size(); ++k) e = std::max(e, std::abs(a.servoStance[k] - a.d->qpos[a.servoQ[k]]));
    for (std::size_t k = 0; k < a.pdq.size(); ++k) e = std::max(e, std::abs(a.pdStance[k] - a.d->qpos[a.pdq[k]]));
    return e;
  };
  double prevTilt = 1e300;
  DataPtr before = makeData(a.m);  // the state before the last change of the set-points
  std::vector<double> prevPd = a.pdTarget;
  while (t.rounds < kTrimRounds) {
    for (long k = 0; k < roundSteps; ++k) {
      stepArticulated(a, ctrl, 0.0, steps);
      t.max_rel_tilt_deg = std::max(t.max_rel_tilt_deg, tiltFromDeg(a.d, a.body, a.stanceZ));
      if (fell(a, t.max_rel_tilt_deg, "while its legs were trimmed for the tail's weight", error)) return t;
      if (warningCount(a.d)) {
        error = "MuJoCo warnings while trimming the legs' set-points for the tail: " + describeWarnings(a.d);
        return t;
      }
    }
    ++t.rounds;
    t.trim_s += roundSteps * a.m->opt.timestep;
    const double tilt = tiltFromDeg(a.d, a.body, a.stanceZ);
    if (tilt > prevTilt) {  // the last change made it worse: the round is undone
      mj_copyData(a.d, a.m, before.get());
      a.pdTarget = prevPd;
      t.trim_s -= roundSteps * a.m->opt.timestep;
      break;
    }
    t.end_tilt_deg = tilt;
    if (tilt < kTrimTiltTolDeg || tilt > 0.9 * prevTilt) break;
    prevTilt = tilt;
    mj_copyData(before.get(), a.m, a.d);
    prevPd = a.pdTarget;
    for (std::size_t k = 0; k < a.servoAct.size(); ++k) {
      const int u = a.servoAct[k];
      double c = a.d->ctrl[u] + kTrimGain * servoCtrlPerRad(a.m, u) * (a.servoStance[k] - a.d->qpos[a.servoQ[k]]);
      if (a.m->actuator_ctrllimited[u]) c = std::clamp(c, a.m->actuator_ctrlrange[2 * u], a.m->actuator_ctrlrange[2 * u + 1]);
      a.d->ctrl[u] = c;
    }
    for (std::size_t k = 0; k < a.pdq.size(); ++k) a.pdTarget[k] += kTrimGain * (a.pdStance[k] - a.d->qpos[a.pdq[k]]);
  }
  for (std::size_t k = 0; k < a.servoAct.size(); ++k)
    t.max_offset_deg =
        std::max(t.max_offset_deg, units::degrees(std::abs(a.d->ctrl[a.servoAct[k]] - servoCtrlFor(a.m, a.servoAct[k], a.servoHold[k])) /
                                                  std::abs(servoCtrlPerRad(a.m, a.servoAct[k]))));
  for (std::size_t k = 0; k < a.pdq.size(); ++k)
    t.max_offset_deg = std::max(t.max_offset_deg, units::degrees(std::abs(a.pdTarget[k] - a.pdHold[k])));
  t.residual_deg = units::degrees(jointError());
  return t;
}

// Stage: stand stand_s with the tail held at theta(0): the tilt figures and the feet in contact at the end.
void standWithTail(ArticulatedSim& a, TailController& ctrl, const DerivedRobot& r, double stand_s, ArticulatedRun& out) {
  const mjModel* m = a.m;
  const mjData* d = a.d;
  const long standSteps = std::lround(stand_s / m->opt.timestep);
  for (long k = 0; k < standSteps && out.ok; ++k) {
    stepArticulated(a, ctrl, 0.0, out.steps);
    out.stand_max_tilt_deg = std::max(out.stand_max_tilt_deg, tiltDeg(d, a.body));
    out.stand_max_rel_tilt_deg = std::max(out.stand_max_rel_tilt_deg, tiltFromDeg(d, a.body, a.stanceZ));
    if (warningCount(d)) out.ok = false, out.error = "MuJoCo warnings while standing: " + describeWarnings(d);
    if (out.ok && fell(a, out.stand_max_rel_tilt_deg, "while standing with the tail", out.error)) out.ok = false;
  }
  out.stand_s = stand_s;
  out.stand_end_tilt_deg = tiltDeg(d, a.body);
  out.stand_end_rel_tilt_deg = tiltFromDeg(d, a.body, a.stanceZ);
  for (const auto& [bodyName, k] : r.foot_geoms) {
    const int g = m->body_geomadr[bodyId(m, bodyName)] + k;
    bool touching = false;
    for (int i = 0; i < d->ncon; ++i) touching = touching || d->contact[i].geom1 == g || d->contact[i].geom2 == g;
    out.feet_in_contact += touching;
  }
}

// The rows of the articulated run's time series (ArticulatedRun::series) on the output grid: the
// sample nearest each grid time is the step that reaches it.
class StrokeRecorder {
 public:
  StrokeRecorder(const ArticulatedSim& a, const TailTrajectory& trajectory, TimeSeries& series, double sample_dt_s,
                 double t_end)
      : a_(a), trajectory_(trajectory), series_(series), sample_dt_s_(sample_dt_s), t_end_(t_end),
        dt_(a.m->opt.timestep), x0_(a.d->xpos[3 * a.body]), y0_(a.d->xpos[3 * a.body + 1]) {
    if (sample_dt_s_ <= 0.0) return;
    colT_ = series_.addColumn(col::kT);
    for (int i = 1; i <= a_.n; ++i) colTheta_.push_back(series_.addColumn(col::theta(i)));
    for (int i = 1; i <= a_.n; ++i) colThetadot_.push_back(series_.addColumn(col::thetadot(i)));
    colX_ = series_.addColumn(col::kX);
    colY_ = series_.addColumn(col::kY);
    colPhi_ = series_.addColumn(col::kPhi);
    colPhidot_ = series_.addColumn(col::kPhidot);
    for (int i = 1; i <= a_.n; ++i) colTrack_.push_back(series_.addColumn(col::trackErr(i)));
    row_.resize(series_.numColumns());
  }

  // The rows up to time t of the stroke, phi the heading change so far [rad].
  void record(double t, double phi) {
    if (sample_dt_s_ <= 0.0) return;
    const mjData* d = a_.d;
    const double* root = d->xpos + 3 * a_.body;
    while (nextRow_ * sample_dt_s_ <= t + 0.5 * dt_ && nextRow_ * sample_dt_s_ <= t_end_ + 1e-9 * sample_dt_s_) {
      trajectory_.evaluate(t, ref_);
      row_[colT_] = nextRow_ * sample_dt_s_;
      for (int i = 0; i < a_.n; ++i) {
        row_[colTheta_[i]] = units::degrees(d->qpos[a_.qadr[i]]);
        row_[colThetadot_[i]] = units::degrees(d->qvel[a_.vadr[i]]);
        row_[colTrack_[i]] = units::degrees(d->qpos[a_.qadr[i]] - ref_[i].theta);
      }
      row_[colX_] = root[0] - x0_;
      row_[colY_] = root[1] - y0_;
      row_[colPhi_] = units::degrees(phi);
      row_[colPhidot_] = units::degrees(d->cvel[6 * a_.body + 2]);  // world-frame angular velocity z (com-based)
      series_.appendRow(row_);
      ++nextRow_;
    }
  }

 private:
  const ArticulatedSim& a_;
  const TailTrajectory& trajectory_;
  TimeSeries& series_;
  double sample_dt_s_, t_end_, dt_, x0_, y0_;
  std::vector<int> colTheta_, colThetadot_, colTrack_;
  int colT_ = -1, colX_ = -1, colY_ = -1, colPhi_ = -1, colPhidot_ = -1;
  long nextRow_ = 0;
  std::vector<double> row_;
  std::vector<JointState> ref_;
};

// The servos' largest natural frequency [rad/s]: the tail's (servo_wn_dt / h; unknown, so infinite,
// when kp is given) and each held leg joint's, sqrt(kp / M_ii) with its joint-space stiffness (a
// position actuator's -biasprm[1] gear^2, or tailsim's kStancePdKp) and the diagonal of the mass
// matrix at the state (armature included).
double stiffestServoWn(const ArticulatedSim& a, const MujocoSettings& s) {
  const double tail = s.kp == 0.0 ? s.servo_wn_dt / s.timestep_s : HUGE_VAL;
  return std::max(tail, legServoWnH(a) / a.m->opt.timestep);
}

// The stiffest held leg joint's w_n h at the model's step (its joint-space stiffness: a position
// actuator's -biasprm[1] gear^2, or tailsim's kStancePdKp; M_ii at the state, armature included).
double legServoWnH(const ArticulatedSim& a) {
  const mjModel* m = a.m;
  double wn = 0.0;
  auto joint = [&](int dof, double kp) { wn = std::max(wn, std::sqrt(kp / a.d->qM[m->dof_Madr[dof]])); };
  for (const int u : a.servoAct) {
    const double gear = m->actuator_gear[6 * u];
    joint(m->jnt_dofadr[m->actuator_trnid[2 * u]], -m->actuator_biasprm[mjNBIAS * u + 1] * gear * gear);
  }
  for (const int v : a.pdv) joint(v, kStancePdKp);
  return wn * m->opt.timestep;
}

// The stroke's rest step schedule (step_schedule.h) by the rigid box's guards, read from the model:
// its own integrator (implicit only), its shortest solref, the stiffest servo. row_dt_s: the rows'
// spacing inside the run (0: none).
StepSchedule restSchedule(const ArticulatedSim& a, const MujocoSettings& s, double tail_end_s, double end_s,
                          double row_dt_s) {
  return StepSchedule(a.m->opt.timestep, s.rest_step_factor, tail_end_s, end_s, row_dt_s, shortestSolrefS(a.m),
                      stiffestServoWn(a, s), a.m->opt.integrator == mjINT_IMPLICIT);
}

// Stage: the stroke and settle_after_s after it: phi_net (the root body's heading change, unwrapped
// step by step), the tilt during it, the rows, and whether the body is at rest at the end. Once the
// body rests after the stroke the steps are rest_step_factor times longer (restSchedule); with
// `stop_at_rest` (the check run: only phi_net is wanted) the run ends there.
void runStroke(ArticulatedSim& a, TailController& ctrl, const TailTrajectory& trajectory, const MujocoSettings& s,
               double settle_after_s, double sample_dt_s, bool stop_at_rest, ArticulatedRun& out) {
  const mjData* d = a.d;
  const int body = a.body;
  const double dt = a.m->opt.timestep;
  auto yaw = [&] { return std::atan2(d->xmat[9 * body + 3], d->xmat[9 * body]); };
  double phi = 0.0, prev = yaw();
  const double t_end = trajectory.endTime() + settle_after_s;
  const long runSteps = std::lround(t_end / dt);
  StrokeRecorder rec(a, trajectory, out.series, sample_dt_s, t_end);
  const double row_dt = sample_dt_s > 0.0 && sample_dt_s < t_end ? sample_dt_s : 0.0;  // rows inside the run
  StepSchedule schedule = restSchedule(a, s, trajectory.endTime(), runSteps * dt, row_dt);
  rec.record(0.0, phi);
  long k = 0;  // the run's time in steps of dt (a coarse step is rest_step_factor of them)
  while (k < runSteps && out.ok) {
    k += std::lround(a.m->opt.timestep / dt);
    stepArticulated(a, ctrl, k * dt, out.steps);
    const double y = yaw();
    phi += std::remainder(y - prev, 2 * kPi);
    prev = y;
    rec.record(k * dt, phi);
    out.max_tilt_deg = std::max(out.max_tilt_deg, tiltDeg(d, body));
    out.max_rel_tilt_deg = std::max(out.max_rel_tilt_deg, tiltFromDeg(d, body, a.stanceZ));
    if (warningCount(d)) out.ok = false, out.error = "MuJoCo warnings during the stroke: " + describeWarnings(d);
    if (out.ok && fell(a, out.max_rel_tilt_deg, "during the stroke", out.error)) out.ok = false;
    a.m->opt.timestep = schedule.next(k * dt, speedsAtRest(a.m, a.d));
    if (stop_at_rest && schedule.rested(k * dt)) break;
  }
  a.m->opt.timestep = dt;
  out.run_s = stop_at_rest ? k * dt : t_end;
  out.phi_net_deg = units::degrees(phi);
  const double* v = d->cvel + 6 * body;  // [angular; linear] at the subtree COM, world frame
  out.at_rest = units::degrees(std::abs(v[2])) < 0.1 && std::hypot(v[3], v[4]) < 1e-3;
}

// Stage: the run's verdict: not standing on 3 feet at the stroke's start is a failed run (phi_net
// NaN, as a fall); warnings: a tilt from the stance while standing with the tail, a near fall.
void judgeArticulated(ArticulatedRun& out) {
  if (out.ok && out.feet_in_contact < 3) {
    out.ok = false;
    out.error = "the robot does not stand: " + std::to_string(out.feet_in_contact) +
                " of its feet touch the floor after standing with the tail";
  }
  if (!out.ok) out.phi_net_deg = std::numeric_limits<double>::quiet_NaN();
  if (out.ok && out.max_rel_tilt_deg > kNearFallTiltFromStanceDeg)
    out.warnings.push_back(std::string(kUncertainWarning) + ": the robot nearly fell (body tilt up to " +
                           std::to_string(out.max_rel_tilt_deg) + " deg from its stance during the stroke, more than " +
                           std::to_string(kNearFallTiltFromStanceDeg) + " deg): whether it falls depends on the "
                           "contact and the step");
  if (out.stand_max_rel_tilt_deg >= kStandingTiltLimitDeg)
    out.warnings.push_back("the body tilted up to " + std::to_string(out.stand_max_rel_tilt_deg) + " deg from its stance (" +
                           std::to_string(out.stand_max_tilt_deg) + " deg absolute) while standing with the tail");
}

// The articulated run at s.timestep_s (the model's own, or the check run's twice that): the tail's
// servo gains from s, the model's option timestep replaced by s.timestep_s. Stages: build, trim the
// legs for the tail's weight, stand stand_s, the stroke and settle_after_s (sampled; with
// stop_at_rest only until the body rests after the stroke), judge.
ArticulatedRun runArticulatedAt(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                                const TailTrajectory& trajectory, const MujocoSettings& s, double stand_s,
                                double settle_after_s, double sample_dt_s, bool stop_at_rest = false) {
  ArticulatedRun out;
  MujocoMessages messages;
  ArticulatedSim a;
  buildArticulated(a, r, mount, tail, trajectory, s);
  TailController ctrl(a.m, trajectory, a.qadr, a.vadr, a.act, {s.velocity_feedforward, s.inverse_dynamics_feedforward});
  out.stance_tilt_deg = tiltDeg(a.d, a.body);
  out.trim = trimStance(a, ctrl, r.legs_locked, out.steps, out.error);
  out.ok = out.error.empty();
  standWithTail(a, ctrl, r, stand_s, out);
  runStroke(a, ctrl, trajectory, s, settle_after_s, sample_dt_s, stop_at_rest, out);
  judgeArticulated(out);
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
  s.extra["stance_trim_rounds"] = a.trim.rounds;
  s.extra["stance_trim_max_offset_deg"] = a.trim.max_offset_deg;
  s.extra["stance_trim_residual_deg"] = a.trim.residual_deg;
  s.extra["stance_trim_end_tilt_from_stance_deg"] = a.trim.end_tilt_deg;
  s.extra["stance_trim_max_tilt_from_stance_deg"] = a.trim.max_rel_tilt_deg;
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
      // Only its phi_net is wanted: it ends once the body rests after the stroke.
      const ArticulatedRun c = runArticulatedAt(r, mount, tail, trajectory, coarse, stand_s, settle_after_s, 0.0, true);
      check = articulatedRunResult(c, model).summary;
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
