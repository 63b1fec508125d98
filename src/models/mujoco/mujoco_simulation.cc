#include "models/mujoco/mujoco_simulation.h"

#include "results/columns.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <deque>
#include <limits>
#include <map>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <string>
#include <vector>

#include "controllers/tail_controller.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"
#include "models/mujoco/run_uncertainty.h"
#include "models/mujoco/step_schedule.h"
#include "common/sha256.h"
#include "common/work_limits.h"
#include "robot/friction_law.h"
#include "common/units.h"

namespace tailsim {

namespace {

constexpr double kRad2Deg = units::kDegPerRad;

// Indices into mjModel for the elements the simulation reads.
struct Layout {
  int quad_body = -1;
  int root_dofadr = -1;  // first rotational dof of the quadruped (body-frame angular velocity)
  int link1_body = -1;
  std::vector<int> tail_qposadr, tail_dofadr, tail_act;
  std::array<int, 4> foot_geom{};
};

Layout makeLayout(const mjModel* m, int n, bool translation) {
  Layout L;
  L.quad_body = bodyId(m, mjcf::kQuadrupedBody);
  const int root = jointId(m, mjcf::kRootJoint);
  L.root_dofadr = m->jnt_dofadr[root] + (translation ? 3 : 0);  // free: (v, w_local); ball: w_local
  L.link1_body = bodyId(m, mjcf::tailBodyName(1));
  for (int i = 1; i <= n; ++i) {
    const int j = jointId(m, mjcf::tailJointName(i));
    L.tail_qposadr.push_back(m->jnt_qposadr[j]);
    L.tail_dofadr.push_back(m->jnt_dofadr[j]);
    L.tail_act.push_back(actuatorId(m, mjcf::tailActuatorName(i)));
  }
  for (int k = 1; k <= 4; ++k) L.foot_geom[k - 1] = geomId(m, mjcf::footGeomName(k));
  return L;
}

// Column indices of the output table.
struct Columns {
  int t, x, y, phi, phidot, phiddot, mzt, mzf, izz, izz_phiddot, ftx, fty, ffx, ffy;
  std::vector<int> theta, thetadot, thetaddot, track_err;
  std::array<int, 4> fn{}, ft{};
};

Columns makeColumns(TimeSeries& ts, int n) {
  Columns c;
  c.t = ts.addColumn(col::kT);
  for (int i = 1; i <= n; ++i) c.theta.push_back(ts.addColumn(col::theta(i)));
  for (int i = 1; i <= n; ++i) c.thetadot.push_back(ts.addColumn(col::thetadot(i)));
  for (int i = 1; i <= n; ++i) c.thetaddot.push_back(ts.addColumn(col::thetaddot(i)));
  c.x = ts.addColumn(col::kX);
  c.y = ts.addColumn(col::kY);
  c.phi = ts.addColumn(col::kPhi);
  c.phidot = ts.addColumn(col::kPhidot);
  c.phiddot = ts.addColumn(col::kPhiddot);
  c.mzt = ts.addColumn(col::kMzT);
  c.mzf = ts.addColumn(col::kMzF);
  c.izz = ts.addColumn(col::kIzz);
  c.izz_phiddot = ts.addColumn(col::kIzzPhiddot);
  c.ftx = ts.addColumn(col::kFTx);
  c.fty = ts.addColumn(col::kFTy);
  c.ffx = ts.addColumn(col::kFFx);
  c.ffy = ts.addColumn(col::kFFy);
  for (int k = 1; k <= 4; ++k) {
    c.fn[k - 1] = ts.addColumn(col::footFn(k));
    c.ft[k - 1] = ts.addColumn(col::footFt(k));
  }
  for (int i = 1; i <= n; ++i) c.track_err.push_back(ts.addColumn(col::trackErr(i)));
  return c;
}

double yawOf(const mjData* d, int body) {
  const mjtNum* R = d->xmat + 9 * body;  // row-major, body -> world
  return std::atan2(R[3], R[0]);          // heading of the body x axis in the ground plane
}

double wrapPi(double a) { return std::remainder(a, 2.0 * M_PI); }

// z component (world) of a body-frame vector w of `body`.
double worldZ(const mjData* d, int body, const mjtNum* w) {
  const mjtNum* R = d->xmat + 9 * body;
  return R[6] * w[0] + R[7] * w[1] + R[8] * w[2];
}

// The loads of one MuJoCo step (the forces of the state the step started from, applied over the
// step): the columns that are impulse-averaged over each output interval (docs/mujoco-model.md
// "Force and moment columns").
enum LoadIndex { kPhiddot, kIzzPhiddot, kMzT, kFTx, kFTy, kMzF, kFFx, kFFy, kFn1, kFt1 = kFn1 + 4, kNumLoads = kFt1 + 4 };
using Loads = std::array<double, kNumLoads>;

int loadColumn(const Columns& c, int j) {
  switch (j) {
    case kPhiddot: return c.phiddot;
    case kIzzPhiddot: return c.izz_phiddot;
    case kMzT: return c.mzt;
    case kFTx: return c.ftx;
    case kFTy: return c.fty;
    case kMzF: return c.mzf;
    case kFFx: return c.ffx;
    case kFFy: return c.ffy;
    default: return j < kFt1 ? c.fn[j - kFn1] : c.ft[j - kFt1];
  }
}

// Izz of the whole robot about the system COM (Eq. 11, full 3-D inertia tensors, tilt included).
double systemIzz(const mjModel* m, const mjData* d, const Layout& L) {
  const mjtNum* com = d->subtree_com + 3 * L.quad_body;
  double izz = 0.0;
  for (int b = L.quad_body; b < m->nbody; ++b) {
    if (m->body_rootid[b] != L.quad_body) continue;
    const mjtNum* R = d->ximat + 9 * b;
    const mjtNum* I = m->body_inertia + 3 * b;
    izz += R[6] * R[6] * I[0] + R[7] * R[7] * I[1] + R[8] * R[8] * I[2];
    const double dx = d->xipos[3 * b] - com[0], dy = d->xipos[3 * b + 1] - com[1];
    izz += m->body_mass[b] * (dx * dx + dy * dy);
  }
  return izz;
}

// Kinematics, contacts and constraint forces in d belong to the state (qvel, qacc applied) at the
// step's start time (the step has just run, only d->qpos / d->qvel / d->time moved on).
Loads computeLoads(const mjModel* m, mjData* d, const Layout& L, const std::vector<mjtNum>& qvel,
                   const std::vector<mjtNum>& qacc, std::vector<mjtNum>& scratch) {
  Loads out{};
  const double phiddot = worldZ(d, L.quad_body, qacc.data() + L.root_dofadr);
  out[kPhiddot] = phiddot * kRad2Deg;

  out[kIzzPhiddot] = systemIzz(m, d, L) * phiddot;
  const mjtNum* com = d->subtree_com + 3 * L.quad_body;  // the system COM

  // Tail load on the body: minus the interaction force of the tail's first link with its parent.
  // cfrc_int is (torque, force) at subtree_com of the root body = the system COM, world axes, so
  // its z torque is already M_z,T about the system COM (Eq. 13). mj_rnePostConstraint reads
  // d->qvel and d->qacc: give it the velocities of the step's start and the accelerations the
  // integrator actually applied over the step.
  scratch.resize(2 * m->nv);
  std::copy(d->qvel, d->qvel + m->nv, scratch.begin());
  std::copy(d->qacc, d->qacc + m->nv, scratch.begin() + m->nv);
  std::copy(qvel.begin(), qvel.end(), d->qvel);
  std::copy(qacc.begin(), qacc.end(), d->qacc);
  mj_rnePostConstraint(m, d);
  std::copy(scratch.begin(), scratch.begin() + m->nv, d->qvel);
  std::copy(scratch.begin() + m->nv, scratch.end(), d->qacc);
  const mjtNum* fint = d->cfrc_int + 6 * L.link1_body;
  out[kMzT] = -fint[2];
  out[kFTx] = -fint[3];
  out[kFTy] = -fint[4];

  // Foot contact forces (world), their friction moment about the system COM.
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& con = d->contact[i];
    int k = -1;
    double sign = 1.0;  // mj_contactForce: force of geom1 on geom2 in the contact frame
    for (int f = 0; f < 4; ++f) {
      if (con.geom2 == L.foot_geom[f]) k = f;
      if (con.geom1 == L.foot_geom[f]) k = f, sign = -1.0;
    }
    if (k < 0) continue;
    mjtNum f6[6];
    mj_contactForce(m, d, i, f6);
    double F[3];
    for (int a = 0; a < 3; ++a)
      F[a] = sign * (f6[0] * con.frame[a] + f6[1] * con.frame[3 + a] + f6[2] * con.frame[6 + a]);
    out[kFn1 + k] += f6[0];
    out[kFt1 + k] += std::hypot(f6[1], f6[2]);
    const double rx = con.pos[0] - com[0], ry = con.pos[1] - com[1];
    out[kMzF] += rx * F[1] - ry * F[0];
    out[kFFx] += F[0];
    out[kFFy] += F[1];
  }
  return out;
}

// Fills one output row: the state at time t and the loads of the step that starts there (the
// load columns are replaced by their interval averages once the interval's steps have run).
void fillRow(const mjModel* m, const mjData* d, const Layout& L, const Columns& c, const TailController& ctrl,
             const std::vector<mjtNum>& qpos, const std::vector<mjtNum>& qvel, const std::vector<mjtNum>& qacc,
             const Loads& loads, double t_grid, double phi, std::vector<double>& row) {
  const int n = static_cast<int>(L.tail_qposadr.size());
  row[c.t] = t_grid;
  for (int i = 0; i < n; ++i) {
    row[c.theta[i]] = qpos[L.tail_qposadr[i]] * kRad2Deg;
    row[c.thetadot[i]] = qvel[L.tail_dofadr[i]] * kRad2Deg;
    row[c.thetaddot[i]] = qacc[L.tail_dofadr[i]] * kRad2Deg;  // actual, not the reference
    row[c.track_err[i]] = ctrl.lastError(i) * kRad2Deg;
  }
  row[c.x] = d->xpos[3 * L.quad_body];  // quadruped COM = body origin
  row[c.y] = d->xpos[3 * L.quad_body + 1];
  row[c.phi] = phi * kRad2Deg;
  row[c.phidot] = worldZ(d, L.quad_body, qvel.data() + L.root_dofadr) * kRad2Deg;
  row[c.izz] = systemIzz(m, d, L);
  for (int j = 0; j < kNumLoads; ++j) row[loadColumn(c, j)] = loads[j];
}

// Impulse averages of the load columns over the output intervals: row k owns the steps that start
// in [t_k - dt/2, t_k + dt/2) (row 0: [0, dt/2); the last row: up to the end of the run), and its
// value is the sum of (load * h) over those steps divided by their total time. A row that owns no
// step (sample_dt < timestep) keeps the loads of the step it falls in. Rows wait here until their
// interval has run, then go into the series whole.
class ImpulseAverager {
 public:
  ImpulseAverager(double sample_dt, double h, long rows, const Columns& c, TimeSeries& ts)
      : dt_(sample_dt), h_(h), rows_(rows), c_(c), ts_(ts) {}
  void addRow(long k, const std::vector<double>& row) { pending_.push_back({k, row}); }
  // The loads of the step of length h_step that starts at t_step.
  void addStep(double t_step, double h_step, const Loads& loads) {
    const long k = std::clamp(static_cast<long>(std::floor((t_step + 1e-6 * h_) / dt_ + 0.5)), 0L, rows_ - 1);
    if (k != bucket_) flushBucket();
    bucket_ = k;
    for (int j = 0; j < kNumLoads; ++j) sum_[j] += loads[j] * h_step;
    time_ += h_step;
  }
  // At the end of the run: the last interval, every row still waiting.
  void finish() {
    flushBucket();
    for (const auto& p : pending_) ts_.appendRow(p.second);
    pending_.clear();
  }

 private:
  void flushBucket() {
    if (bucket_ < 0) return;
    for (auto& [k, row] : pending_)
      if (k == bucket_ && time_ > 0.0)
        for (int j = 0; j < kNumLoads; ++j) row[loadColumn(c_, j)] = sum_[j] / time_;
    while (!pending_.empty() && pending_.front().first <= bucket_) {
      ts_.appendRow(pending_.front().second);
      pending_.pop_front();
    }
    sum_ = Loads{};
    time_ = 0.0;
  }
  double dt_, h_;
  long rows_;
  const Columns& c_;
  TimeSeries& ts_;
  std::deque<std::pair<long, std::vector<double>>> pending_;
  long bucket_ = -1;
  Loads sum_{};
  double time_ = 0.0;
};

// ADAMS law (Fig. 4): each foot's coefficient from its horizontal slip speed. Uses d->cvel of the
// last evaluated state (one step old).
void updateFootFriction(mjModel* m, const mjData* d, const Layout& L, const FrictionParams& fp) {
  for (int k = 0; k < 4; ++k) {
    mjtNum v6[6];
    mj_objectVelocity(m, d, mjOBJ_GEOM, L.foot_geom[k], v6, 0);  // (angular, linear), world axes
    const double slip = std::hypot(v6[3], v6[4]);
    m->geom_friction[3 * L.foot_geom[k]] = adamsFrictionCoefficient(slip, fp.v_s_mps, fp.v_d_mps, fp.mu_s, fp.mu_d);
  }
}

// Watches whether the quadruped still stands (docs/mujoco-model.md "Falling over"). Called once
// per step with the state the step started from (xmat, xpos, contacts and efc_force of time t):
// one comparison for the tilt, one for the height, a loop over the few foot contacts.
class StandingMonitor {
 public:
  StandingMonitor(const MujocoSettings& s, const Effects& e, int body)
      : body_(body),
        z_ref_(s.body_height_m),
        h_(s.timestep_s),
        enforce_(e.gravity && e.ground_contact),
        pyramid_rows_(s.cone == MujocoCone::kPyramidal),
        cos_limit_(s.max_tilt_deg > 0.0 ? std::cos(units::radians(s.max_tilt_deg)) : -2.0),
        off_limit_steps_(s.max_all_feet_off_s > 0.0 ? static_cast<long>(std::ceil(s.max_all_feet_off_s / h_ - 1e-9))
                                                    : -1),
        max_tilt_deg_(s.max_tilt_deg),
        max_off_s_(s.max_all_feet_off_s) {}

  // Returns false (and why()) once the robot has fallen. t_s: time of the state, for the message;
  // h_step: the step taken from it (a whole multiple of timestep_s, counted as that many steps).
  bool update(const mjData* d, double t_s, double h_step) {
    const long units = std::max(1L, std::lround(h_step / h_));
    const double cz = d->xmat[9 * body_ + 8];  // cos(tilt) = body z axis . world z
    min_cos_ = std::min(min_cos_, cz);
    const double dz = d->xpos[3 * body_ + 2] - z_ref_;
    max_dz_ = std::max(max_dz_, std::abs(dz));
    bool loaded = false;
    for (int i = 0; i < d->ncon && !loaded; ++i) {
      const int a = d->contact[i].efc_address;  // only feet touch the floor
      if (a < 0) continue;
      loaded = d->efc_force[a] > 0.0;  // elliptic: the normal force; pyramidal: the first edge
      if (pyramid_rows_)  // pyramidal: the normal force is the sum of the (>= 0) edge forces
        for (int r = 1; r < 2 * (d->contact[i].dim - 1) && !loaded; ++r) loaded = d->efc_force[a + r] > 0.0;
    }
    off_steps_ = loaded ? 0 : off_steps_ + units;
    longest_off_steps_ = std::max(longest_off_steps_, off_steps_);
    if (t_s >= 0.0) {  // the run proper (the pre-roll has t < 0): airborne steps
      run_steps_ += units;
      if (!loaded) airborne_steps_ += units;
    }
    if (!enforce_ || !why_.empty()) return why_.empty();
    std::ostringstream os;
    os.precision(4);
    if (cz < cos_limit_) {
      os << "robot fell over at t = " << t_s << " s: body tilt " << tiltDeg(cz) << " deg (limit max_tilt_deg = "
         << max_tilt_deg_ << " deg)";
    } else if (off_limit_steps_ > 0 && off_steps_ >= off_limit_steps_) {
      os << "robot fell over at t = " << t_s << " s: no foot has touched the ground for " << off_steps_ * h_
         << " s (limit max_all_feet_off_s = " << max_off_s_ << " s), body tilt " << tiltDeg(cz) << " deg";
    } else {
      return true;
    }
    os << "; the analytic model reports this as tipping over (system COM outside the support rectangle)";
    why_ = os.str();
    return false;
  }
  const std::string& why() const { return why_; }
  // The figures a user judges the run by (summary extras).
  void report(std::map<std::string, double>& extra) const {
    extra["max_tilt_deg"] = tiltDeg(min_cos_);
    extra["max_height_change_m"] = max_dz_;
    extra["longest_all_feet_off_s"] = longest_off_steps_ * h_;
    extra["airborne_fraction"] = airborneFraction();
  }
  // Share of the run's steps (t >= 0, the pre-roll excluded; a step of k timestep_s counts k times)
  // in which no foot carried load.
  double airborneFraction() const {
    return run_steps_ > 0 ? static_cast<double>(airborne_steps_) / static_cast<double>(run_steps_) : 0.0;
  }
  bool enforced() const { return enforce_; }

 private:
  static double tiltDeg(double c) { return std::acos(std::clamp(c, -1.0, 1.0)) * kRad2Deg; }
  int body_;
  double z_ref_, h_;
  bool enforce_, pyramid_rows_;
  double cos_limit_;
  long off_limit_steps_;
  double max_tilt_deg_, max_off_s_;
  double min_cos_ = 1.0, max_dz_ = 0.0;
  long off_steps_ = 0, longest_off_steps_ = 0;
  long run_steps_ = 0, airborne_steps_ = 0;
  std::string why_;
};

std::string instabilityMessage(const mjData* d, double t, const MujocoSettings& s, const ServoGains& g) {
  std::ostringstream os;
  os << "MuJoCo became unstable at t=" << t << " s (" << describeWarnings(d) << "): timestep_s=" << s.timestep_s
     << " too large for kp=" << *std::max_element(g.kp.begin(), g.kp.end())
     << " N m/rad (servo_wn_dt=" << s.servo_wn_dt << ") or contact solref=[" << s.solref[0] << ", " << s.solref[1]
     << "] with integrator=" << name(s.integrator);
  return os.str();
}

// What a pre-roll depends on besides the MJCF: every MuJoCo setting (settle_s, the controller's
// feed-forward options, the standing limits), the effects, the friction law's parameters (run-time
// foot friction) and the reference at t = 0 (held during the pre-roll; its speed and acceleration
// enter the feed-forward terms). Written field by field from the settings' own declarations.
class KeyWriter {
 public:
  void number(const settings::Field& f, double x, const settings::Limits&) { put(f, x); }
  void integer(const settings::Field& f, int x, const settings::Limits&, const settings::IntSet& = {}) { put(f, x); }
  void boolean(const settings::Field& f, bool x) { put(f, x ? 1.0 : 0.0); }
  template <class E>
  void choice(const settings::Field& f, E x, const settings::EnumNames<E>&) {
    put(f, static_cast<double>(static_cast<int>(x)));
  }
  void text(const settings::Field& f, const std::string& x, const settings::TextRule&) {
    put(f.key, x);
  }
  template <std::size_t N>
  void numbers(const settings::Field& f, const std::array<double, N>& x) {
    for (double v : x) put(f, v);
  }
  template <class T>
  void internal(const settings::Field& f, const T& x) {
    if constexpr (std::is_arithmetic_v<T>) put(f, static_cast<double>(x));
  }
  void put(const settings::Field& f, double x) { put(f.key, x); }
  void put(const char* key, double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%a", x);  // exact
    put(key, std::string(b));
  }
  void put(const char* key, const std::string& x) {
    out += key;
    out += "=" + x + ";";
  }
  std::string out;
};

std::string settleKey(const std::string& xml, const MujocoSettings& s, const Effects& e, const FrictionParams& fp,
                      const std::vector<JointState>& ref0) {
  KeyWriter w;
  w.out = xml + "\n";
  declareFields(w, s);
  declareFields(w, e);
  declareFields(w, fp);
  for (const JointState& j : ref0) {
    w.put("theta0", j.theta);
    w.put("theta0_dot", j.theta_dot);
    w.put("theta0_ddot", j.theta_ddot);
  }
  return sha256Hex(w.out);
}

// The MuJoCo state after a pre-roll: every mjData field the next mj_forward/mj_step reads as input
// (the rest is computed from these), and the run-time foot friction written into the model.
struct SettledState {
  std::vector<mjtNum> qpos, act, ctrl, qfrc_applied, xfrc_applied, mocap_pos, mocap_quat, userdata, qacc_warmstart,
      geom_friction;
  StandingMonitor standing;
};

template <class T>
std::vector<mjtNum> copyOf(const T* p, int n) {
  return std::vector<mjtNum>(p, p + n);
}

SettledState saveSettled(const mjModel* m, const mjData* d, const StandingMonitor& standing) {
  return {copyOf(d->qpos, m->nq),          copyOf(d->act, m->na),
          copyOf(d->ctrl, m->nu),          copyOf(d->qfrc_applied, m->nv),
          copyOf(d->xfrc_applied, 6 * m->nbody), copyOf(d->mocap_pos, 3 * m->nmocap),
          copyOf(d->mocap_quat, 4 * m->nmocap), copyOf(d->userdata, m->nuserdata),
          copyOf(d->qacc_warmstart, m->nv), copyOf(m->geom_friction, 3 * m->ngeom),
          standing};
}

void restoreSettled(const SettledState& st, mjModel* m, mjData* d, StandingMonitor& standing) {
  d->time = 0.0;
  std::copy(st.qpos.begin(), st.qpos.end(), d->qpos);
  std::fill(d->qvel, d->qvel + m->nv, 0.0);
  std::copy(st.act.begin(), st.act.end(), d->act);
  std::copy(st.ctrl.begin(), st.ctrl.end(), d->ctrl);
  std::copy(st.qfrc_applied.begin(), st.qfrc_applied.end(), d->qfrc_applied);
  std::copy(st.xfrc_applied.begin(), st.xfrc_applied.end(), d->xfrc_applied);
  std::copy(st.mocap_pos.begin(), st.mocap_pos.end(), d->mocap_pos);
  std::copy(st.mocap_quat.begin(), st.mocap_quat.end(), d->mocap_quat);
  std::copy(st.userdata.begin(), st.userdata.end(), d->userdata);
  std::copy(st.qacc_warmstart.begin(), st.qacc_warmstart.end(), d->qacc_warmstart);
  std::copy(st.geom_friction.begin(), st.geom_friction.end(), m->geom_friction);
  standing = st.standing;
}

}  // namespace

struct MujocoSettleCache::Impl {
  std::mutex mu;
  std::map<std::string, std::shared_ptr<const SettledState>> states;
  std::size_t max_entries = 0;
  long hits = 0, misses = 0, settle_steps = 0;

  std::shared_ptr<const SettledState> find(const std::string& key) {
    std::lock_guard<std::mutex> lock(mu);
    auto it = states.find(key);
    if (it == states.end()) return nullptr;
    ++hits;
    return it->second;
  }
  void miss(long steps) {
    std::lock_guard<std::mutex> lock(mu);
    ++misses;
    settle_steps += steps;
  }
  void keep(const std::string& key, SettledState st) {
    std::lock_guard<std::mutex> lock(mu);
    if (states.size() < max_entries) states.emplace(key, std::make_shared<const SettledState>(std::move(st)));
  }
};

MujocoSettleCache::MujocoSettleCache(std::size_t max_entries) : impl_(std::make_unique<Impl>()) {
  impl_->max_entries = max_entries;
}
MujocoSettleCache::~MujocoSettleCache() = default;
long MujocoSettleCache::hits() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->hits;
}
long MujocoSettleCache::misses() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->misses;
}
long MujocoSettleCache::settleSteps() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->settle_steps;
}

namespace {

// The run's length and rows, checked before any work (std::invalid_argument).
struct MujocoPlan {
  double duration = 0;  // simulated seconds after the pre-roll
  long rows = 0;        // output rows
};

MujocoPlan planMujocoRun(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
                         const OutputSettings& output) {
  const int n = robot.numLinks();
  if (static_cast<int>(trajectory.joints.size()) != n)
    throw std::invalid_argument("trajectory has " + std::to_string(trajectory.joints.size()) +
                                " joints but the tail has " + std::to_string(n) + " links");
  if (!(output.sample_dt_s > 0.0)) throw std::invalid_argument("output.sample_dt_s must be > 0");
  const double duration = output.runEnd(trajectory.endTime());
  if (!(duration >= 0.0) || !std::isfinite(duration)) throw std::invalid_argument("bad simulation duration");
  // Work bounds, checked as doubles before they become counts (no float-to-integer overflow).
  const double rows = output.rows(duration);
  if (!(rows <= limits::kMaxRowsPerRun))
    throw std::invalid_argument("the run (" + std::to_string(duration) + " s / output.sample_dt_s " +
                                std::to_string(output.sample_dt_s) + " s) would write more than " +
                                std::to_string(static_cast<long>(limits::kMaxRowsPerRun)) + " rows");
  const double total_steps = (settings.settle_s + duration) / settings.timestep_s;
  if (!(total_steps <= limits::kMaxMujocoSteps))
    throw std::invalid_argument("MuJoCo would take " + std::to_string(total_steps) + " steps ((settle_s " +
                                std::to_string(settings.settle_s) + " s + " + std::to_string(duration) +
                                " s) / timestep_s " + std::to_string(settings.timestep_s) + " s), more than " +
                                std::to_string(static_cast<long>(limits::kMaxMujocoSteps)));
  return {duration, static_cast<long>(rows)};
}

// One MuJoCo run, in named stages in the manner of mj_forward: build (the constructor: MJCF,
// model, data, columns, start pose), settle (the pre-roll or its cached end state), stepLoop (the
// steps, with the output rows sampled on the grid as it passes, sampleRows), judge (the summary
// and the warnings of a doubtful result). The stages share the run's state below.
class MujocoRun {
 public:
  // How a run ends besides its settings: `stop_at_rest`, once the body rests after the tail's
  // motion (the check run: only phi_net is wanted).
  struct Options {
    bool stop_at_rest = false;
  };

  MujocoRun(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
            const Effects& effects, const OutputSettings& output, const MujocoPlan& plan, const Options& options)
      : robot_(robot),
        settings_(settings),
        effects_(effects),
        output_(output),
        plan_(plan),
        options_(options),
        n_(robot.numLinks()),
        xml_(generateMjcf(robot, settings, effects)),  // validates robot + settings
        model_(loadModelFromXml(xml_)),
        m_(model_.get()),
        data_(makeData(m_)),
        d_(data_.get()),
        L_(makeLayout(m_, n_, effects.translation)),
        gains_(tailServoGains(robot, settings)),
        continuous_(effects.friction == FrictionLaw::kContinuous && effects.ground_contact),
        rk4_(settings.integrator == MujocoIntegrator::kRK4),
        sum_(result_.summary),
        ts_(result_.series),
        cols_(makeColumns(ts_, n_)),
        row_(ts_.numColumns(), 0.0),
        ctrl_(m_, trajectory, L_.tail_qposadr, L_.tail_dofadr, L_.tail_act,
              {settings.velocity_feedforward, settings.inverse_dynamics_feedforward}),
        qvel_s_(m_->nv),
        qacc_s_(m_->nv),
        standing_(settings, effects, L_.quad_body),
        weight_N_(mj_getTotalmass(m_) * robot.gravity_mps2) {
    sum_.model = "mujoco";
    // Initial state: home keyframe, tail at theta(0), then settle on the feet.
    mj_resetDataKeyframe(m_, d_, mj_name2id(m_, mjOBJ_KEY, mjcf::kHomeKey));
    trajectory.evaluate(0.0, ref0_);
    for (int i = 0; i < n_; ++i) d_->qpos[L_.tail_qposadr[i]] = ref0_[i].theta;
    mj_forward(m_, d_);
  }

  // Pre-roll (or its cached end state): the quadruped settles on its feet, the tail held at
  // theta(0). False: the run failed while settling.
  bool settle(MujocoSettleCache* settle_cache) {
    const std::string key =
        settle_cache ? settleKey(xml_, settings_, effects_, robot_.friction, ref0_) : std::string();
    const std::shared_ptr<const SettledState> cached = settle_cache ? settle_cache->impl().find(key) : nullptr;
    if (cached) {
      restoreSettled(*cached, m_, d_, standing_);
    } else {
      long settle_steps = 0;
      while (d_->time < settings_.settle_s - 0.5 * settings_.timestep_s && sum_.ok) {
        const double t_state = d_->time - settings_.settle_s;
        step(0.0, false, nullptr);
        ++settle_steps;
        if (warningCount(d_) > 0)
          fail(instabilityMessage(d_, d_->time - settings_.settle_s, settings_, gains_) + " (settling)");
        else if (!standing_.update(d_, t_state, settings_.timestep_s))
          fail(standing_.why() + " (while settling with the tail held at theta(0))");
      }
      if (settle_cache) settle_cache->impl().miss(settle_steps);
      if (!sum_.ok) return false;
      d_->time = 0.0;
      for (int v = 0; v < m_->nv; ++v) d_->qvel[v] = 0.0;
      if (settle_cache && messages_.text().empty()) settle_cache->impl().keep(key, saveSettled(m_, d_, standing_));
    }
    mj_forward(m_, d_);
    return true;
  }

  // The run from t = 0 to its end. Row k is the state at the start of the first step with
  // t >= t_k (exact when the timestep divides sample_dt; otherwise up to one timestep late,
  // labelled t_k).
  void stepLoop(const MujocoSampleObserver& observer, const MujocoTrajectoryHook& hook) {
    const double h = settings_.timestep_s;
    const double eps = 1e-6 * h;
    const double duration = plan_.duration;
    long k = 0;
    std::vector<mjtNum> qpos_t(m_->nq), qvel_t(m_->nv), qacc_t(m_->nv);
    ImpulseAverager averager(output_.sample_dt_s, h, plan_.rows, cols_, ts_);
    // The servo's w_n is known where the gains come from it (kp = 0); its damper is implicit only
    // with the implicit integrator; a direct solref (<= 0) has no time constant to keep.
    const double servo_wn = settings_.kp == 0.0 ? settings_.servo_wn_dt / h : HUGE_VAL;
    StepSchedule schedule(h, settings_.rest_step_factor, ctrl_.trajectory().endTime(), duration,
                          output_.sample_dt_s, settings_.solref[0] > 0.0 ? settings_.solref[0] : 0.0, servo_wn,
                          settings_.integrator == MujocoIntegrator::kImplicit && !hook);
    phi_ = yaw_prev_ = phi0_ = yawOf(d_, L_.quad_body);
    const auto wall0 = std::chrono::steady_clock::now();
    // Runs to the end of the simulated time even when the output grid ends earlier (a spacing that
    // does not divide the duration): the summary is the state at the end, not the last row.
    while (k < plan_.rows || d_->time < duration - eps) {
      const double t = d_->time;
      const double h_step = m_->opt.timestep;
      const bool sample = k < plan_.rows && t >= k * output_.sample_dt_s - eps;
      const bool averaged = t < duration - eps;  // the step lies inside the run: its impulse counts
      if (sample) {
        if (observer) observer(k * output_.sample_dt_s, m_, d_);
        if (hook) {
          mj_kinematics(m_, d_);  // xmat of this state (the yaw so far is one step old)
          const double phi_now = phi_ + wrapPi(yawOf(d_, L_.quad_body) - yaw_prev_);
          TailTrajectory next = ctrl_.trajectory();
          if (hook(k * output_.sample_dt_s, phi_now - phi0_, m_, d_, next)) ctrl_.setTrajectory(std::move(next));
        }
        std::copy(d_->qpos, d_->qpos + m_->nq, qpos_t.begin());
        std::copy(d_->qvel, d_->qvel + m_->nv, qvel_t.begin());
      }
      if (rk4_ && sample) {
        // RK4 overwrites the intermediate fields: evaluate the sample state first.
        if (continuous_) updateFootFriction(m_, d_, L_, robot_.friction);
        mj_forward(m_, d_);
        ctrl_.apply(m_, d_, t, true);
        const double yaw = yawOf(d_, L_.quad_body);
        phi_ += wrapPi(yaw - yaw_prev_);
        yaw_prev_ = yaw;
        std::copy(d_->qacc, d_->qacc + m_->nv, qacc_t.begin());
        loads_ = computeLoads(m_, d_, L_, qvel_t, qacc_t, scratch_);
        sampleRows(k, t, eps, qpos_t, qvel_t, qacc_t, averager);
        mj_step(m_, d_);
      } else if (rk4_) {
        step(t, true, &loads_);
      } else {
        std::copy(d_->qvel, d_->qvel + m_->nv, qvel_s_.begin());
        step(t, true, nullptr, h_step / h);
      }
      ++steps_;
      if (steps_ > settings_.max_steps) {
        fail("step budget of " + std::to_string(settings_.max_steps) +
             " MuJoCo steps exhausted at t=" + std::to_string(t) + " s (docs/experiment-format.md \"Limits\")");
        break;
      }
      if (warningCount(d_) > 0 || !std::isfinite(d_->qacc[L_.root_dofadr]) || !std::isfinite(ctrl_.lastError(0))) {
        fail(instabilityMessage(d_, t, settings_, gains_));
        break;
      }
      if (!standing_.update(d_, t, h_step)) {
        fellOver(t);
        break;
      }
      if (!rk4_) {  // unwrapped every step, so a coarse output grid cannot alias a fast spin
        const double yaw = yawOf(d_, L_.quad_body);  // xmat of time t
        phi_ += wrapPi(yaw - yaw_prev_);
        yaw_prev_ = yaw;
        // The acceleration the integrator applied (implicit: (M - h D)^-1 f, not d->qacc's explicit one).
        for (int v = 0; v < m_->nv; ++v) qacc_s_[v] = (d_->qvel[v] - qvel_s_[v]) / h_step;
        loads_ = computeLoads(m_, d_, L_, qvel_s_, qacc_s_, scratch_);
      }
      if (sample && !rk4_) sampleRows(k, t, eps, qpos_t, qvel_s_, qacc_s_, averager);
      if (averaged) {
        averager.addStep(t, h_step, loads_);
        peak_normal_N_ =
            std::max(peak_normal_N_, loads_[kFn1] + loads_[kFn1 + 1] + loads_[kFn1 + 2] + loads_[kFn1 + 3]);
      }
      m_->opt.timestep = schedule.next(d_->time, speedsAtRest(m_, d_));
      if (options_.stop_at_rest && schedule.rested(d_->time)) break;
    }
    averager.finish();
    sum_.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    sum_.solver_steps = steps_;
  }

  // The summary of the run that ended, and the warnings of a result that is computed but doubtful.
  // Stages: the final figures, then the warnings in the order they are printed.
  RunResult judge() {
    const TrackingStats st = ctrl_.stats();
    finalFigures(st);
    if (standing_.enforced() && sum_.ok) warnContactFidelity();
    if (standing_.enforced() && sum_.ok && settings_.max_tilt_deg > 0.0 &&
        sum_.extra["max_tilt_deg"] > limits::kNearFallTiltShare * settings_.max_tilt_deg)
      warnNearFall();
    judgeAtRest();
    warnTracking(st);
    if (!sum_.ok) sum_.phi_net_deg = std::numeric_limits<double>::quiet_NaN();
    return result_;
  }

  // Stage: phi_net, the final position, t_stop (the last row where |phi_dot| reaches the stop
  // threshold), the tail's tracking, the standing and contact figures.
  void finalFigures(const TrackingStats& st) {
    mj_kinematics(m_, d_);  // xmat of the final state
    phi_ += wrapPi(yawOf(d_, L_.quad_body) - yaw_prev_);
    sum_.phi_net_deg = (phi_ - phi0_) * kRad2Deg;
    sum_.extra["final_x_m"] = d_->xpos[3 * L_.quad_body];  // as the x_m, y_m columns: the quadruped COM
    sum_.extra["final_y_m"] = d_->xpos[3 * L_.quad_body + 1];
    const std::vector<double>& tcol = ts_.values(cols_.t);
    const std::vector<double>& pd = ts_.values(cols_.phidot);
    const double thr = settings_.stop_phidot_radps * kRad2Deg;
    sum_.t_stop_s = 0.0;
    for (size_t r = pd.size(); r-- > 0;) {
      if (std::abs(pd[r]) >= thr) {
        sum_.t_stop_s = r + 1 < pd.size() ? tcol[r + 1] : tcol[r];
        break;
      }
    }
    for (int i = 0; i < n_; ++i) {
      sum_.extra["tracking_max_deg_j" + std::to_string(i + 1)] = st.max_abs_rad[i] * kRad2Deg;
      sum_.extra["tracking_rms_deg_j" + std::to_string(i + 1)] = st.rms_rad[i] * kRad2Deg;
    }
    sum_.extra["mujoco_warnings"] = warningCount(d_);
    sum_.extra["kp_j1"] = gains_.kp[0];
    standing_.report(sum_.extra);
    reportContact();
  }

  // Stage: contact fidelity (docs/mujoco-model.md "Contact fidelity"): feet that leave the ground
  // while the body slides, and impulsive normal forces, mean MuJoCo's soft contact, not Coulomb
  // friction, shaped the result.
  void warnContactFidelity() {
    const double airborne = sum_.extra["airborne_fraction"], peak = sum_.extra["peak_normal_force_over_mg"];
    std::ostringstream os;
    os.precision(3);
    if (airborne > limits::kMaxAirborneFraction)
      os << "all four feet carry no load in " << 100.0 * airborne << " % of the steps (limit "
         << 100.0 * limits::kMaxAirborneFraction << " %): MuJoCo's soft contact chatters while the body slides";
    if (peak > limits::kMaxPeakNormalForceOverMg)
      os << (os.str().empty() ? "" : "; ") << "the summed foot normal force peaks at " << peak
         << " m g (limit " << limits::kMaxPeakNormalForceOverMg << " m g): impulsive contact";
    if (!os.str().empty()) {
      os << "; phi_net depends on the contact softness (mujoco.solref), see docs/mujoco-model.md \"Contact fidelity\"";
      sum_.warnings.push_back(os.str());
    }
  }

  // Stage: near fall: the body rocked onto two feet and came back; a converged run may see it fall.
  void warnNearFall() {
    std::ostringstream os;
    os.precision(3);
    os << kUncertainWarning << ": the robot nearly fell (body tilt up to " << sum_.extra["max_tilt_deg"]
       << " deg, more than " << 100.0 * limits::kNearFallTiltShare << " % of max_tilt_deg = " << settings_.max_tilt_deg
       << " deg): it rocked on two feet, and whether it falls depends on the contact and the step "
       << "(docs/mujoco-model.md \"Tipping over\")";
    sum_.warnings.push_back(os.str());
  }

  // Stage: at rest at the end: yaw rate and the body's horizontal speed below the documented thresholds.
  void judgeAtRest() {
    mjtNum v6[6];
    mj_objectVelocity(m_, d_, mjOBJ_BODY, L_.quad_body, v6, 0);  // (angular, linear), world axes
    const double phidot_dps = std::abs(v6[2]) * kRad2Deg, speed = std::hypot(v6[3], v6[4]);
    sum_.extra["final_phidot_dps"] = v6[2] * kRad2Deg;
    sum_.extra["final_speed_mps"] = speed;
    sum_.at_rest = phidot_dps < limits::kAtRestPhidotDps && speed < limits::kAtRestSpeedMps;
    if (!sum_.at_rest && sum_.ok) {
      std::ostringstream os;
      os.precision(4);
      os << "the body is still moving when the run ends at t = " << plan_.duration << " s (|phi_dot| " << phidot_dps
         << " deg/s, speed " << speed << " m/s; at rest means below " << limits::kAtRestPhidotDps << " deg/s and "
         << limits::kAtRestSpeedMps << " m/s): phi_net is not final, raise output.settle_s or duration_s";
      sum_.warnings.push_back(os.str());
    }
  }

  // Stage: the servo follows the reference only as well as the step allows (a coarse timestep_s
  // lowers the gains: kp ~ (servo_wn_dt / timestep_s)^2): a large tracking error means a different motion.
  void warnTracking(const TrackingStats& st) {
    double worst = 0.0;
    int worst_j = 0;
    for (int i = 0; i < n_; ++i)
      if (st.max_abs_rad[i] * kRad2Deg > worst) worst = st.max_abs_rad[i] * kRad2Deg, worst_j = i + 1;
    if (worst > limits::kMaxTrackingErrorDeg && sum_.ok) {
      std::ostringstream os;
      os.precision(3);
      os << "the tail servo is off its reference by up to " << worst << " deg (joint " << worst_j << "; limit "
         << limits::kMaxTrackingErrorDeg << " deg): the simulated tail motion differs from the trajectory, "
         << "lower mujoco.timestep_s (" << settings_.timestep_s << " s)";
      sum_.warnings.push_back(os.str());
    }
  }

  // The result of a run that failed while settling.
  RunResult failed() {
    sum_.phi_net_deg = std::numeric_limits<double>::quiet_NaN();
    standing_.report(sum_.extra);
    reportContact();
    sum_.extra["mujoco_warnings"] = warningCount(d_);
    return result_;
  }

 private:
  // One step. RK4 with `rk4_loads`: also the loads of the state the step starts from (RK4 overwrites
  // the intermediate fields, so they are taken before it; the step's impulse is then h times them).
  // `weight`: this step's length in timestep_s (the step schedule), for the tracking RMS over time.
  void step(double t_ref, bool record, Loads* rk4_loads, double weight = 1.0) {
    if (continuous_) updateFootFriction(m_, d_, L_, robot_.friction);
    if (rk4_) {
      mj_forward(m_, d_);  // M, bias at this state for the feed-forward; ctrl is held over the RK4 step
      ctrl_.apply(m_, d_, t_ref, record, weight);
      if (rk4_loads) {
        std::copy(d_->qvel, d_->qvel + m_->nv, qvel_s_.begin());
        std::copy(d_->qacc, d_->qacc + m_->nv, qacc_s_.begin());
        *rk4_loads = computeLoads(m_, d_, L_, qvel_s_, qacc_s_, scratch_);
      }
      mj_step(m_, d_);
    } else {
      mj_step1(m_, d_);
      ctrl_.apply(m_, d_, t_ref, record, weight);
      mj_step2(m_, d_);
    }
  }

  // The rows of the grid times the step starting at t reaches (the state sampled before it).
  void sampleRows(long& k, double t, double eps, const std::vector<mjtNum>& qpos, const std::vector<mjtNum>& qvel,
                  const std::vector<mjtNum>& qacc, ImpulseAverager& averager) {
    while (k < plan_.rows && t >= k * output_.sample_dt_s - eps) {
      fillRow(m_, d_, L_, cols_, ctrl_, qpos, qvel, qacc, loads_, k * output_.sample_dt_s, phi_, row_);
      averager.addRow(k, row_);
      ++k;
    }
  }

  // The body tipped past max_tilt_deg at t. A diverging integration (timestep too large for the
  // servo gains) also throws the body over, usually a few steps before MuJoCo's own warning. Look
  // 0.05 s further: if MuJoCo then warns, the cause is the step, not the robot's balance.
  void fellOver(double t) {
    m_->opt.timestep = settings_.timestep_s;
    const long look = std::max(1L, std::lround(0.05 / settings_.timestep_s));
    bool unstable = false;
    double t_bad = t;
    for (long i = 0; i < look && !unstable; ++i) {
      mj_step(m_, d_);  // (MuJoCo resets d, time included, when it finds a bad acceleration)
      t_bad += settings_.timestep_s;
      unstable = warningCount(d_) > 0 || !std::isfinite(d_->qacc[L_.root_dofadr]);
    }
    std::ostringstream tilt;
    tilt << " (the body had tilted past max_tilt_deg at t=" << t << " s as it diverged)";
    fail(unstable ? instabilityMessage(d_, t_bad, settings_, gains_) + tilt.str() : standing_.why());
  }

  void fail(const std::string& why) {
    sum_.ok = false;
    sum_.error = why + (messages_.text().empty() ? "" : " [" + messages_.text() + "]");
  }

  // Peak of the summed foot normal force over the run's steps (each step's force, not the 1 ms
  // averages), in units of the robot's weight m g (m = every body, g = robot.gravity_mps2).
  void reportContact() {
    sum_.extra["peak_normal_force_over_mg"] = weight_N_ > 0.0 ? peak_normal_N_ / weight_N_ : 0.0;
  }

  const RobotParams& robot_;
  const MujocoSettings& settings_;
  const Effects& effects_;
  const OutputSettings& output_;
  const MujocoPlan plan_;
  const Options options_;
  const int n_;
  const std::string xml_;
  const MujocoMessages messages_;  // MuJoCo's warnings go into this run's error text, not MUJOCO_LOG.TXT
  ModelPtr model_;
  mjModel* m_;
  DataPtr data_;
  mjData* d_;
  const Layout L_;
  const ServoGains gains_;
  const bool continuous_, rk4_;
  RunResult result_;
  RunSummary& sum_;
  TimeSeries& ts_;
  const Columns cols_;
  std::vector<double> row_;
  std::vector<JointState> ref0_;  // the joints at t = 0
  TailController ctrl_;
  std::vector<mjtNum> qvel_s_, qacc_s_, scratch_;
  Loads loads_{};
  StandingMonitor standing_;
  const double weight_N_;
  double peak_normal_N_ = 0.0;
  double phi_ = 0.0, yaw_prev_ = 0.0, phi0_ = 0.0;  // the unwrapped yaw, the last yaw read, the yaw at t = 0
  long steps_ = 0;
};

// One MuJoCo run at `settings`, without the uncertainty estimate: the stages of a MujocoRun.
RunResult runMujoco(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
                    const Effects& effects, const OutputSettings& output, const MujocoSampleObserver& observer,
                    MujocoSettleCache* settle_cache, const MujocoTrajectoryHook& hook,
                    const MujocoRun::Options& options) {
  const MujocoPlan plan = planMujocoRun(robot, trajectory, settings, output);
  MujocoRun run(robot, trajectory, settings, effects, output, plan, options);
  if (!run.settle(settle_cache)) return run.failed();
  run.stepLoop(observer, hook);
  return run.judge();
}

// The run's error estimate from a second run at twice the step (run_uncertainty.h): its own
// pre-roll at 2 h (not the run's settle cache, whose hit and miss counts are the runs'), so that a
// robot at the edge of standing meets the coarser step from the start; it stops once the body
// rests after the tail's motion (from there phi_net no longer moves); no time series; its wall
// time is added to the run's.
void addUncertainty(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
                    const Effects& effects, const OutputSettings& output, RunResult& fine) {
  const MujocoSettings coarse = checkRunSettings(settings);
  OutputSettings quiet = output;
  quiet.time_series = TimeSeriesOutput::kNone;
  const auto wall0 = std::chrono::steady_clock::now();
  const RunResult check = runMujoco(robot, trajectory, coarse, effects, quiet, nullptr, nullptr, nullptr,
                                    MujocoRun::Options{true});
  fine.summary.wall_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  applyCheckRun(fine.summary, check.summary, coarse.timestep_s, settings.uncertainty_warn_share,
                "lower mujoco.timestep_s or see `tailsim trust`");
}

}  // namespace

RunResult simulateMujoco(const RobotParams& robot, const TailTrajectory& trajectory, const MujocoSettings& settings,
                         const Effects& effects, const OutputSettings& output, const MujocoSampleObserver& observer,
                         MujocoSettleCache* settle_cache, const MujocoTrajectoryHook& hook) {
  RunResult r = runMujoco(robot, trajectory, settings, effects, output, observer, settle_cache, hook,
                          MujocoRun::Options{});
  // A run steered by a hook decides its reference as it goes: a second run would steer differently.
  if (settings.uncertainty && r.summary.ok && !hook)
    addUncertainty(robot, trajectory, settings, effects, output, r);
  return r;
}

}  // namespace tailsim
