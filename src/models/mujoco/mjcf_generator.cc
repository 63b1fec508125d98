#include "models/mujoco/mjcf_generator.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <utility>

#include "common/atomic_file.h"

namespace tailsim {

namespace mjcf {
std::string footGeomName(int k) {
  static const char* kSuffix[] = {"FL", "FR", "RR", "RL"};
  if (k < 1 || k > 4) throw std::invalid_argument("foot index must be 1..4");
  return "foot" + std::to_string(k) + "_" + kSuffix[k - 1];
}
std::string tailBodyName(int i) { return "tail_link" + std::to_string(i); }
std::string tailJointName(int i) { return "tail_joint" + std::to_string(i); }
std::string tailActuatorName(int i) { return "tail_motor" + std::to_string(i); }
}  // namespace mjcf

namespace {

constexpr double kBoxHeight = 0.1;       // inertia box of the quadruped (only for Ixx, Iyy)  [m]
constexpr double kTailGeomRadius = 0.012;  // visual capsule radius of the tail  [m]

// Attribute text for numbers: 15 significant digits (parameters read back to ~1e-15).
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.15g", v == 0.0 ? 0.0 : v);  // no "-0"
  return buf;
}
std::string nums(std::initializer_list<double> vs) {
  std::string s;
  for (double v : vs) {
    if (!s.empty()) s += ' ';
    s += num(v);
  }
  return s;
}

tinyxml2::XMLElement* child(tinyxml2::XMLElement* parent, const char* tag) {
  tinyxml2::XMLElement* e = parent->GetDocument()->NewElement(tag);
  parent->InsertEndChild(e);
  return e;
}

void requireOneOf(const std::string& v, std::initializer_list<const char*> allowed, const char* key) {
  for (const char* a : allowed)
    if (v == a) return;
  std::string list;
  for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
  throw std::invalid_argument(std::string("mujoco.") + key + " must be one of {" + list + "}, got '" + v + "'");
}

void validateSettings(const MujocoSettings& s) {
  if (!(s.timestep_s > 0.0) || !std::isfinite(s.timestep_s))
    throw std::invalid_argument("mujoco.timestep_s must be > 0");
  requireOneOf(name(s.integrator), {"Euler", "RK4", "implicit"}, "integrator");
  requireOneOf(name(s.solver), {"PGS", "CG", "Newton"}, "solver");
  requireOneOf(name(s.cone), {"pyramidal", "elliptic"}, "cone");
  requireOneOf(name(s.foot_shape), {"sphere", "capsule", "box"}, "foot_shape");
  if (s.foot_shape == MujocoFootShape::kCapsule && !(s.foot_half_length_m > 0.0))
    throw std::invalid_argument("mujoco.foot_half_length_m must be > 0 for capsule feet");
  if (s.condim != 1 && s.condim != 3 && s.condim != 4 && s.condim != 6)
    throw std::invalid_argument("mujoco.condim must be 1, 3, 4 or 6, got " + std::to_string(s.condim));
  if (s.iterations < 1) throw std::invalid_argument("mujoco.iterations must be >= 1");
  if (s.noslip_iterations < 0) throw std::invalid_argument("mujoco.noslip_iterations must be >= 0");
  if (!(s.tolerance >= 0.0)) throw std::invalid_argument("mujoco.tolerance must be >= 0");
  if (!(s.impratio > 0.0)) throw std::invalid_argument("mujoco.impratio must be > 0");
  if (s.kp < 0.0 || s.kv < 0.0) throw std::invalid_argument("mujoco.kp and mujoco.kv must be >= 0");
  if (s.kp == 0.0 && !(s.servo_wn_dt > 0.0)) throw std::invalid_argument("mujoco.servo_wn_dt must be > 0");
  if (!(s.foot_radius_m > 0.0)) throw std::invalid_argument("mujoco.foot_radius_m must be > 0");
  if (!(s.body_height_m > s.foot_radius_m + kTailGeomRadius))
    throw std::invalid_argument("quadruped.com_height_m (the MuJoCo body height) must exceed mujoco.foot_radius_m + tail radius");
  if (!(s.settle_s >= 0.0)) throw std::invalid_argument("mujoco.settle_s must be >= 0");
}

}  // namespace

std::array<double, 2> footXY(const QuadrupedParams& q, int k) {
  // Eq. (17): feet 1, 2 front (+x), 3, 4 rear; 1, 4 left (+y), 2, 3 right.
  if (k < 1 || k > 4) throw std::invalid_argument("foot index must be 1..4");
  const double x = (k == 1 || k == 2) ? 0.5 * q.l_F_m : -0.5 * q.l_F_m;
  const double y = (k == 1 || k == 4) ? 0.5 * q.w_F_m : -0.5 * q.w_F_m;
  return {q.d_Q2C_m + x, y};
}

std::array<double, 3> quadrupedDiagInertia(const QuadrupedParams& q) {
  // Box a x b x c with a:b = l_F:w_F and m (a^2 + b^2) / 12 = I_zz,Q.
  const double r = q.w_F_m / q.l_F_m;
  const double a2 = 12.0 * q.izz_kgm2 / (q.mass_kg * (1.0 + r * r));
  const double b2 = r * r * a2, c2 = kBoxHeight * kBoxHeight;
  return {q.mass_kg * (b2 + c2) / 12.0, q.mass_kg * (a2 + c2) / 12.0, q.izz_kgm2};
}

std::array<double, 3> tailLinkDiagInertia(const TailLink& l) { return {0.01 * l.izz_kgm2, l.izz_kgm2, l.izz_kgm2}; }

std::vector<double> tailJointInertias(const RobotParams& p) {
  const int n = p.numLinks();
  std::vector<double> I(n, 0.0);
  for (int i = 0; i < n; ++i) {
    double dist = 0.0;  // joint i -> joint j along the straight tail
    for (int j = i; j < n; ++j) {
      const TailLink& l = p.tail[j];
      const double r = dist + l.com_offset_m;
      I[i] += l.izz_kgm2 + l.mass_kg * r * r;
      dist += l.length_m;
    }
  }
  return I;
}

ServoGains tailServoGains(const RobotParams& p, const MujocoSettings& s) {
  const std::vector<double> I = tailJointInertias(p);
  const double wn = s.servo_wn_dt / s.timestep_s;
  ServoGains g;
  for (double Ii : I) {
    g.kp.push_back(s.kp > 0.0 ? s.kp : Ii * wn * wn);
    g.kv.push_back(s.kv > 0.0 ? s.kv : 2.0 * Ii * (s.kp > 0.0 ? std::sqrt(s.kp / Ii) : wn));
  }
  return g;
}

double footFrictionCoefficient(const RobotParams& p, const MujocoSettings& s, const Effects& e) {
  switch (e.friction) {
    case FrictionLaw::kNone: return 0.0;
    case FrictionLaw::kContinuous: return 0.0;  // mu(0) = 0; updated each step from the slip speed
    case FrictionLaw::kStiction: break;
  }
  return s.mu >= 0.0 ? s.mu : std::max(p.friction.mu_s, p.friction.mu_d);
}

namespace {

using tinyxml2::XMLElement;

std::string solrefText(const MujocoSettings& s) { return nums({s.solref[0], s.solref[1]}); }
std::string solimpText(const MujocoSettings& s) {
  return nums({s.solimp[0], s.solimp[1], s.solimp[2], s.solimp[3], s.solimp[4]});
}

// <mujoco model=...> with the "generated" comment in front.
XMLElement* addRoot(tinyxml2::XMLDocument& doc, int n) {
  doc.InsertEndChild(doc.NewComment(
      (" " + std::string(kGeneratedMjcfMarker) + " (src/mujoco_model/mjcf_generator.cc) from RobotParams + MujocoSettings + Effects. "
       "Quadruped + planar tail of Rone & Ben-Tzvi 2016; see docs/mujoco-model.md. Do not edit by hand. ")
          .c_str()));
  XMLElement* root = doc.NewElement("mujoco");
  doc.InsertEndChild(root);
  root->SetAttribute("model", ("tailsim_quadruped_tail" + std::to_string(n)).c_str());
  return root;
}

// <compiler> and <option>: the solver settings, gravity and the disabled effects.
void addCompilerAndOptions(XMLElement* root, const RobotParams& p, const MujocoSettings& s, const Effects& e) {
  XMLElement* compiler = child(root, "compiler");
  compiler->SetAttribute("angle", "radian");
  compiler->SetAttribute("inertiafromgeom", "false");

  XMLElement* option = child(root, "option");
  option->SetAttribute("timestep", num(s.timestep_s).c_str());
  option->SetAttribute("integrator", name(s.integrator));
  option->SetAttribute("solver", name(s.solver));
  option->SetAttribute("iterations", s.iterations);
  option->SetAttribute("tolerance", num(s.tolerance).c_str());
  option->SetAttribute("cone", name(s.cone));
  option->SetAttribute("noslip_iterations", s.noslip_iterations);
  option->SetAttribute("impratio", num(s.impratio).c_str());
  option->SetAttribute("gravity", nums({0.0, 0.0, e.gravity ? -p.gravity_mps2 : 0.0}).c_str());
  if (!e.gravity || !e.ground_contact) {
    XMLElement* flag = child(option, "flag");
    if (!e.gravity) flag->SetAttribute("gravity", "disable");
    if (!e.ground_contact) flag->SetAttribute("contact", "disable");
  }
}

// Default class "visual": geoms that never collide and weigh nothing.
void addVisualDefault(XMLElement* dmain) {
  XMLElement* visual = child(dmain, "default");
  visual->SetAttribute("class", "visual");
  XMLElement* g = child(visual, "geom");
  g->SetAttribute("contype", 0);
  g->SetAttribute("conaffinity", 0);
  g->SetAttribute("group", 2);
  g->SetAttribute("density", 0);
}

// The foot geom's MJCF type and size (mujoco_settings.h MujocoFootShape); its centre is
// foot_radius_m above its lowest point for every shape.
std::string footGeomSize(const MujocoSettings& s) {
  switch (s.foot_shape) {
    case MujocoFootShape::kCapsule: return nums({s.foot_radius_m, s.foot_half_length_m});
    case MujocoFootShape::kBox: return nums({s.foot_radius_m, s.foot_radius_m, s.foot_radius_m});
    case MujocoFootShape::kSphere: break;
  }
  return num(s.foot_radius_m);
}

// Default class "foot": the contact geoms (spheres unless foot_shape says otherwise) with the
// friction law's mu and condim.
// priority (Menagerie robot file): the feet's contact parameters win over any floor's.
void addFootDefault(XMLElement* dmain, const MujocoSettings& s, double mu, int condim, bool priority = false) {
  XMLElement* foot = child(dmain, "default");
  foot->SetAttribute("class", "foot");
  XMLElement* g = child(foot, "geom");
  g->SetAttribute("type", name(s.foot_shape));
  g->SetAttribute("size", footGeomSize(s).c_str());
  g->SetAttribute("contype", 1);
  g->SetAttribute("conaffinity", 1);
  g->SetAttribute("condim", condim);
  if (priority) g->SetAttribute("priority", 1);
  g->SetAttribute("friction", nums({mu, s.torsional_friction_m, 0.0}).c_str());
  g->SetAttribute("solref", solrefText(s).c_str());
  g->SetAttribute("solimp", solimpText(s).c_str());
  g->SetAttribute("group", 3);
}

// Default class "tail": hinge joints about z, visual capsules, affine (PD) actuators.
// ctrl_range > 0 (Menagerie robot file): ctrl limited to +-ctrl_range, so a viewer's sliders span it.
void addTailDefault(XMLElement* dmain, double ctrl_range = 0.0) {
  XMLElement* tail = child(dmain, "default");
  tail->SetAttribute("class", "tail");
  XMLElement* j = child(tail, "joint");
  j->SetAttribute("type", "hinge");
  j->SetAttribute("axis", "0 0 1");
  j->SetAttribute("damping", 0);
  j->SetAttribute("armature", 0);
  j->SetAttribute("limited", "false");
  XMLElement* g = child(tail, "geom");
  g->SetAttribute("type", "capsule");
  g->SetAttribute("size", num(kTailGeomRadius).c_str());
  g->SetAttribute("contype", 0);
  g->SetAttribute("conaffinity", 0);
  g->SetAttribute("group", 2);
  g->SetAttribute("density", 0);
  XMLElement* a = child(tail, "general");
  a->SetAttribute("dyntype", "none");
  a->SetAttribute("gaintype", "fixed");
  a->SetAttribute("biastype", "affine");
  if (ctrl_range > 0.0) {
    a->SetAttribute("ctrllimited", "true");
    a->SetAttribute("ctrlrange", nums({-ctrl_range, ctrl_range}).c_str());
  } else {
    a->SetAttribute("ctrllimited", "false");
  }
  a->SetAttribute("forcelimited", "false");
}

// Default classes: "tailsim" holds everything.
void addDefaults(XMLElement* root, const MujocoSettings& s, double mu, int condim) {
  XMLElement* dmain = child(child(root, "default"), "default");
  dmain->SetAttribute("class", "tailsim");
  addVisualDefault(dmain);
  addFootDefault(dmain, s, mu, condim);
  addTailDefault(dmain);
}

// The floor's checker texture and material.
void addAssets(XMLElement* root) {
  XMLElement* asset = child(root, "asset");
  XMLElement* t = child(asset, "texture");
  t->SetAttribute("name", "grid");
  t->SetAttribute("type", "2d");
  t->SetAttribute("builtin", "checker");
  t->SetAttribute("rgb1", "0.2 0.3 0.4");
  t->SetAttribute("rgb2", "0.1 0.2 0.3");
  t->SetAttribute("width", 512);
  t->SetAttribute("height", 512);
  XMLElement* mtl = child(asset, "material");
  mtl->SetAttribute("name", "grid");
  mtl->SetAttribute("texture", "grid");
  mtl->SetAttribute("texrepeat", "1 1");
  mtl->SetAttribute("texuniform", "true");
  mtl->SetAttribute("reflectance", "0.1");
}

// <worldbody> with its light and, with ground contact, the floor.
XMLElement* addWorld(XMLElement* root, const MujocoSettings& s, const Effects& e) {
  XMLElement* world = child(root, "worldbody");
  XMLElement* light = child(world, "light");
  light->SetAttribute("name", "top");
  light->SetAttribute("pos", "0 0 3");
  light->SetAttribute("dir", "0 0 -1");
  light->SetAttribute("directional", "true");
  if (e.ground_contact) {
    // The floor takes its friction and condim from the feet (MuJoCo mixes with max()).
    XMLElement* floor = child(world, "geom");
    floor->SetAttribute("name", mjcf::kFloorGeom);
    floor->SetAttribute("type", "plane");
    floor->SetAttribute("size", "5 5 0.05");
    floor->SetAttribute("material", "grid");
    floor->SetAttribute("contype", 1);
    floor->SetAttribute("conaffinity", 1);
    floor->SetAttribute("condim", 1);
    floor->SetAttribute("friction", "0 0 0");
    floor->SetAttribute("solref", solrefText(s).c_str());
    floor->SetAttribute("solimp", solimpText(s).c_str());
  }
  return world;
}

// The quadruped's joints to the world: free, or (translation off) height slide + ball.
void addRootJoints(XMLElement* body, const Effects& e) {
  if (e.translation) {
    XMLElement* fj = child(body, "freejoint");
    fj->SetAttribute("name", mjcf::kRootJoint);
    return;
  }
  // x, y locked: the body may still settle (slide z) and tilt on its feet (ball); yaw is free.
  XMLElement* jz = child(body, "joint");
  jz->SetAttribute("name", mjcf::kHeightJoint);
  jz->SetAttribute("type", "slide");
  jz->SetAttribute("axis", "0 0 1");
  jz->SetAttribute("limited", "false");
  XMLElement* jb = child(body, "joint");
  jb->SetAttribute("name", mjcf::kRootJoint);
  jb->SetAttribute("type", "ball");
  jb->SetAttribute("limited", "false");
}

// Torso box, four visual legs and the four contact feet (Eq. 17 positions).
void addQuadrupedGeoms(XMLElement* body, const QuadrupedParams& q, double h, double rf, MujocoFootShape shape) {
  XMLElement* torso = child(body, "geom");
  torso->SetAttribute("name", "torso");
  torso->SetAttribute("class", "visual");
  torso->SetAttribute("type", "box");
  torso->SetAttribute("pos", nums({q.d_Q2C_m, 0.0, 0.0}).c_str());
  torso->SetAttribute("size", nums({0.5 * q.l_F_m + 0.04, 0.5 * q.w_F_m - 0.02, 0.04}).c_str());
  torso->SetAttribute("rgba", "0.7 0.7 0.75 1");
  for (int k = 1; k <= 4; ++k) {
    const std::array<double, 2> xy = footXY(q, k);
    XMLElement* leg = child(body, "geom");
    leg->SetAttribute("name", ("leg" + std::to_string(k)).c_str());
    leg->SetAttribute("class", "visual");
    leg->SetAttribute("type", "capsule");
    leg->SetAttribute("size", "0.012");
    leg->SetAttribute("fromto", nums({xy[0], xy[1], 0.0, xy[0], xy[1], -(h - rf)}).c_str());
    leg->SetAttribute("rgba", "0.5 0.5 0.55 1");
  }
  for (int k = 1; k <= 4; ++k) {
    const std::array<double, 2> xy = footXY(q, k);
    XMLElement* foot = child(body, "geom");
    foot->SetAttribute("name", mjcf::footGeomName(k).c_str());
    foot->SetAttribute("class", "foot");
    foot->SetAttribute("pos", nums({xy[0], xy[1], -(h - rf)}).c_str());  // lowest point / bottom face at z = 0
    if (shape == MujocoFootShape::kCapsule) foot->SetAttribute("zaxis", "1 0 0");  // capsule axis along body x
    foot->SetAttribute("rgba", "0.2 0.2 0.2 1");
  }
}

// Quadruped: body frame origin = quadruped COM at height h, x forward, z up (paper Fig. 2).
XMLElement* addQuadruped(XMLElement* world, const QuadrupedParams& q, const MujocoSettings& s, const Effects& e) {
  const double h = s.body_height_m;
  XMLElement* body = child(world, "body");
  body->SetAttribute("name", mjcf::kQuadrupedBody);
  body->SetAttribute("childclass", "tailsim");
  body->SetAttribute("pos", nums({0.0, 0.0, h}).c_str());
  addRootJoints(body, e);
  const std::array<double, 3> I = quadrupedDiagInertia(q);
  XMLElement* in = child(body, "inertial");
  in->SetAttribute("pos", "0 0 0");
  in->SetAttribute("mass", num(q.mass_kg).c_str());
  in->SetAttribute("diaginertia", nums({I[0], I[1], I[2]}).c_str());
  addQuadrupedGeoms(body, q, h, s.foot_radius_m, s.foot_shape);
  return body;
}

// Tail: base B at -d_Q2B x (Eq. 2), R_B = R_Q R_Z(180 deg) (Eq. 1): quaternion (0, 0, 0, 1);
// link i is a child of link i-1, joint i at the end of link i-1 (Eq. 3).
void addTail(XMLElement* body, const RobotParams& p) {
  XMLElement* parent = body;
  for (int i = 1; i <= p.numLinks(); ++i) {
    const TailLink& l = p.tail[i - 1];
    XMLElement* link = child(parent, "body");
    link->SetAttribute("name", mjcf::tailBodyName(i).c_str());
    link->SetAttribute("childclass", "tail");
    if (i == 1) {
      link->SetAttribute("pos", nums({-p.quadruped.d_Q2B_m, 0.0, 0.0}).c_str());
      link->SetAttribute("quat", "0 0 0 1");
    } else {
      link->SetAttribute("pos", nums({p.tail[i - 2].length_m, 0.0, 0.0}).c_str());
    }
    XMLElement* j = child(link, "joint");
    j->SetAttribute("name", mjcf::tailJointName(i).c_str());
    const std::array<double, 3> I = tailLinkDiagInertia(l);
    XMLElement* in = child(link, "inertial");
    in->SetAttribute("pos", nums({l.com_offset_m, 0.0, 0.0}).c_str());
    in->SetAttribute("mass", num(l.mass_kg).c_str());
    in->SetAttribute("diaginertia", nums({I[0], I[1], I[2]}).c_str());
    XMLElement* g = child(link, "geom");
    g->SetAttribute("name", ("tail_geom" + std::to_string(i)).c_str());
    g->SetAttribute("fromto", nums({0.0, 0.0, 0.0, l.length_m, 0.0, 0.0}).c_str());
    g->SetAttribute("rgba", i % 2 ? "0.85 0.45 0.1 1" : "0.95 0.65 0.2 1");
    parent = link;
  }
}

// PD position servos: force = kp ctrl - kp theta - kv theta_dot (MuJoCo 2.2 <position> has no kv).
void addActuators(XMLElement* root, const ServoGains& gains) {
  XMLElement* actuator = child(root, "actuator");
  for (int i = 1; i <= static_cast<int>(gains.kp.size()); ++i) {
    XMLElement* a = child(actuator, "general");
    a->SetAttribute("name", mjcf::tailActuatorName(i).c_str());
    a->SetAttribute("class", "tail");
    a->SetAttribute("joint", mjcf::tailJointName(i).c_str());
    a->SetAttribute("gainprm", num(gains.kp[i - 1]).c_str());
    a->SetAttribute("biasprm", nums({0.0, -gains.kp[i - 1], -gains.kv[i - 1]}).c_str());
  }
}

// Keyframe "home": body at height h, upright, tail straight.
void addHomeKey(XMLElement* root, int n, double h, const Effects& e) {
  XMLElement* key = child(child(root, "keyframe"), "key");
  key->SetAttribute("name", mjcf::kHomeKey);
  std::string qpos = e.translation ? nums({0.0, 0.0, h, 1.0, 0.0, 0.0, 0.0}) : nums({0.0, 1.0, 0.0, 0.0, 0.0});
  for (int i = 0; i < n; ++i) qpos += " 0";
  key->SetAttribute("qpos", qpos.c_str());
}

}  // namespace

std::string generateMjcf(const RobotParams& p, const MujocoSettings& s, const Effects& e) {
  validate(p);
  validateSettings(s);
  const int condim = e.friction == FrictionLaw::kNone ? 1 : s.condim;
  tinyxml2::XMLDocument doc;
  XMLElement* root = addRoot(doc, p.numLinks());
  addCompilerAndOptions(root, p, s, e);
  addDefaults(root, s, footFrictionCoefficient(p, s, e), condim);
  addAssets(root);
  addTail(addQuadruped(addWorld(root, s, e), p.quadruped, s, e), p);
  addActuators(root, tailServoGains(p, s));
  addHomeKey(root, p.numLinks(), s.body_height_m, e);
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

RobotParams paperRobot(int links) {
  RobotParams p;  // Table 1 defaults
  p.tail.assign(links, paperTailLink(links));
  return p;
}

bool writeMjcfFile(int links, const std::string& out) {
  return writeUserFile(out, generateMjcf(paperRobot(links), MujocoSettings{}, Effects{}), kGeneratedMjcfMarker);
}

// ---- Menagerie form -------------------------------------------------------------------------------

double menagerieFootFriction(const RobotParams& p, const MujocoSettings& s, const Effects& e) {
  if (e.friction == FrictionLaw::kContinuous) return s.mu >= 0.0 ? s.mu : std::max(p.friction.mu_s, p.friction.mu_d);
  return footFrictionCoefficient(p, s, e);
}

namespace {

// Numbers in comments: 6 significant digits.
std::string g6(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v == 0.0 ? 0.0 : v);
  return buf;
}
std::string g6s(const std::vector<double>& vs) {
  std::string s = "[";
  for (size_t i = 0; i < vs.size(); ++i) s += (i ? ", " : "") + g6(vs[i]);
  return s + "]";
}

// The feet's shape in words, for the Menagerie file's comment (the sphere text as before the setting).
std::string footNote(const MujocoSettings& s) {
  switch (s.foot_shape) {
    case MujocoFootShape::kCapsule:
      return "capsules of radius " + g6(s.foot_radius_m) + " m, half-length " + g6(s.foot_half_length_m) +
             " m along x,";
    case MujocoFootShape::kBox: return "cubes of half-size " + g6(s.foot_radius_m) + " m, bottom face";
    case MujocoFootShape::kSphere: break;
  }
  return "spheres of radius " + g6(s.foot_radius_m) + " m";
}

// A comment node in front of element e (XML comments hold no "--": the texts below have none).
void noteBefore(XMLElement* e, const std::string& text) {
  tinyxml2::XMLComment* c = e->GetDocument()->NewComment((" " + text + " ").c_str());
  if (tinyxml2::XMLNode* prev = e->PreviousSibling())
    e->Parent()->InsertAfterChild(prev, c);
  else
    e->Parent()->InsertFirstChild(c);
}

XMLElement* childNamed(XMLElement* parent, const char* tag, const std::string& name) {
  for (XMLElement* c = parent->FirstChildElement(tag); c; c = c->NextSiblingElement(tag))
    if (const char* n = c->Attribute("name"); n && name == n) return c;
  throw std::logic_error("mjcf generator: no <" + std::string(tag) + " name=\"" + name + "\">");
}

const char* lawName(FrictionLaw f) {
  switch (f) {
    case FrictionLaw::kNone: return "none";
    case FrictionLaw::kStiction: return "stiction";
    case FrictionLaw::kContinuous: return "continuous, simulated as mu of the slip speed; stiction value here";
  }
  return "?";
}

void requireStem(const std::string& stem) {
  bool ok = !stem.empty() && stem.size() <= 120 && stem[0] != '.' && stem[0] != '-';
  for (char c : stem)
    ok = ok && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                std::string("._=,~-").find(c) != std::string::npos);
  if (!ok)
    throw std::invalid_argument("MJCF file stem '" + stem +
                                "' must be one file name of [A-Za-z0-9._=,~-], not starting with '.' or '-'");
}

std::string robotHeader(const RobotParams& p, const MujocoSettings& s, const Effects& e, const std::string& scene,
                        double mu) {
  const QuadrupedParams& q = p.quadruped;
  std::vector<double> m, L, Izz, c;
  for (const TailLink& l : p.tail) {
    m.push_back(l.mass_kg);
    L.push_back(l.length_m);
    Izz.push_back(l.izz_kgm2);
    c.push_back(l.com_offset_m);
  }
  std::string t;
  t += "\n  tailsim robot: a standing quadruped turned by a planar " + std::to_string(p.numLinks()) +
       "-link tail (Rone & Ben-Tzvi, ASME JDSMC 2016).\n";
  t += "  Generated by tailsim (src/mujoco_model/mjcf_generator.cc, `tailsim mjcf ... --menagerie DIR`); do not edit\n";
  t += "  by hand. This file has no floor: open " + scene + ". Model card: mjcf/README.md. SI units, radians.\n";
  t += "  Paper symbols (Tables 1, 2):\n";
  t += "    m_Q = " + g6(q.mass_kg) + " kg, I_zz,Q = " + g6(q.izz_kgm2) + " kg m^2 (quadruped, about its COM Q)\n";
  t += "    d_Q2C = " + g6(q.d_Q2C_m) + " m, l_F = " + g6(q.l_F_m) + " m, w_F = " + g6(q.w_F_m) +
       " m (feet, Eq. 17); d_Q2B = " + g6(q.d_Q2B_m) + " m (tail base, Eq. 2)\n";
  t += "    tail links i = 1..n: m_L,i = " + g6s(m) + " kg, L_L,i = " + g6s(L) + " m,\n";
  t += "      I_zz,L,i = " + g6s(Izz) + " kg m^2 about the link COM, COM " + g6s(c) + " m from joint i\n";
  t += "    mu = " + g6(mu) + " on the feet (friction law: " + lawName(e.friction) + "; mu_s = " + g6(p.friction.mu_s) +
       ", mu_d = " + g6(p.friction.mu_d) + "), g = " + g6(e.gravity ? p.gravity_mps2 : 0.0) +
       " m/s^2, body height h = " + g6(s.body_height_m) + " m\n";
  return t + "  ";
}

// The Menagerie robot file's comments: the paper's symbols next to the elements that carry them.
void annotateMenagerieRobot(XMLElement* root, XMLElement* dmain, XMLElement* body, const RobotParams& p,
                            const MujocoSettings& s, double mu) {
  const QuadrupedParams& q = p.quadruped;
  XMLElement* foot_default = dmain->FirstChildElement("default")->NextSiblingElement("default");
  noteBefore(foot_default->FirstChildElement("geom"),
             "mu = " + g6(mu) + ": the paper's foot friction. priority=\"1\": a foot's contact takes the foot's "
             "friction, condim, solref and solimp, whatever the floor's (equal priorities would take the larger "
             "friction: a floor of friction 1 would win).");
  XMLElement* tail_default = foot_default->NextSiblingElement("default");
  noteBefore(tail_default->FirstChildElement("general"),
             "PD position servo: force = kp (ctrl - theta) - kv theta_dot (gainprm kp, biasprm 0 -kp -kv)");
  const std::array<double, 3> Iq = quadrupedDiagInertia(q);
  noteBefore(body->FirstChildElement("inertial"),
             "Q: quadruped COM, frame origin, h = " + g6(s.body_height_m) + " m above the ground, x forward, z up. m_Q = " +
                 g6(q.mass_kg) + " kg, I_zz,Q = " + g6(q.izz_kgm2) + " kg m^2; Ixx, Iyy = " + g6(Iq[0]) + ", " +
                 g6(Iq[1]) + " kg m^2 from a 0.1 m high box of the same I_zz (only I_zz enters the planar model)");
  noteBefore(childNamed(body, "geom", mjcf::footGeomName(1)),
             "feet k = 1..4 (FL, FR, RR, RL) at (d_Q2C +- l_F/2, +-w_F/2), Eq. 17: d_Q2C = " + g6(q.d_Q2C_m) +
                 " m, l_F = " + g6(q.l_F_m) + " m, w_F = " + g6(q.w_F_m) + " m; " + footNote(s) + " touching z = 0. Only the feet collide.");
  XMLElement* link = childNamed(body, "body", mjcf::tailBodyName(1));
  noteBefore(link, "tail base B at -d_Q2B along x, d_Q2B = " + g6(q.d_Q2B_m) +
                       " m (Eq. 2); R_B = R_Q R_Z(180 deg) (Eq. 1): theta_i = 0 is the tail straight back");
  const std::vector<double> I = tailJointInertias(p);
  for (int i = 1; i <= p.numLinks(); ++i) {
    const TailLink& l = p.tail[i - 1];
    noteBefore(link->FirstChildElement("joint"),
               "link " + std::to_string(i) + ": m_L," + std::to_string(i) + " = " + g6(l.mass_kg) + " kg, I_zz,L," +
                   std::to_string(i) + " = " + g6(l.izz_kgm2) + " kg m^2 about its COM, L_L," + std::to_string(i) +
                   " = " + g6(l.length_m) + " m (joint " + std::to_string(i) + " to joint " + std::to_string(i + 1) +
                   "), COM " + g6(l.com_offset_m) + " m from joint " + std::to_string(i) + "; joint " +
                   std::to_string(i) + ": theta_" + std::to_string(i) + ", relative to link " + std::to_string(i - 1));
    if (i < p.numLinks()) link = childNamed(link, "body", mjcf::tailBodyName(i + 1));
  }
  XMLElement* actuator = root->FirstChildElement("actuator");
  noteBefore(actuator->FirstChildElement("general"),
             "drive the tail: ctrl_i = theta_ref,i(t), the split-cycle profile (Eqs. 20-23), plus (kv/kp) "
             "theta_dot_ref,i for velocity feed-forward (mjcf/README.md). kp_i = I_i w_n^2, kv_i = 2 I_i w_n "
             "(critically damped), w_n = " + g6(s.servo_wn_dt / s.timestep_s) + " rad/s, I_i = " + g6s(I) +
                 " kg m^2: links i..n about joint i, tail straight");
  noteBefore(root->FirstChildElement("keyframe")->FirstChildElement("key"),
             "home: Q at h = " + g6(s.body_height_m) + " m, upright, heading 0, tail straight (theta = 0), at rest");
}

// The Menagerie robot file: the model under one "tailsim" default class, no floor, annotated.
std::string menagerieRobotXml(const RobotParams& p, const MujocoSettings& s, const Effects& e,
                              const MenagerieFiles& f, const std::string& model, double mu) {
  const int condim = e.friction == FrictionLaw::kNone ? 1 : s.condim;
  tinyxml2::XMLDocument doc;
  doc.InsertEndChild(doc.NewComment(robotHeader(p, s, e, f.scene_file, mu).c_str()));
  XMLElement* root = doc.NewElement("mujoco");
  doc.InsertEndChild(root);
  root->SetAttribute("model", model.c_str());
  addCompilerAndOptions(root, p, s, e);
  XMLElement* dmain = child(child(root, "default"), "default");
  dmain->SetAttribute("class", "tailsim");
  addVisualDefault(dmain);
  addFootDefault(dmain, s, mu, condim, /*priority=*/true);
  addTailDefault(dmain, kMenagerieCtrlRange);
  XMLElement* world = child(root, "worldbody");
  XMLElement* body = addQuadruped(world, p.quadruped, s, e);
  addTail(body, p);
  addActuators(root, tailServoGains(p, s));
  addHomeKey(root, p.numLinks(), s.body_height_m, e);
  annotateMenagerieRobot(root, dmain, body, p, s, mu);
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

// The scene's look: camera statistic, headlight, haze, skybox and the checker ground's texture.
void addSceneLookAndAssets(XMLElement* root, const RobotParams& p, const MujocoSettings& s) {
  const QuadrupedParams& q = p.quadruped;
  double tail_len = 0.0;
  for (const TailLink& l : p.tail) tail_len += l.length_m;
  const double front = q.d_Q2C_m + 0.5 * q.l_F_m + 0.04, back = -(q.d_Q2B_m + tail_len);
  XMLElement* stat = child(root, "statistic");
  stat->SetAttribute("center", nums({0.5 * (front + back), 0.0, 0.5 * s.body_height_m}).c_str());
  stat->SetAttribute("extent", num(front - back).c_str());
  XMLElement* visual = child(root, "visual");
  XMLElement* head = child(visual, "headlight");
  head->SetAttribute("diffuse", "0.6 0.6 0.6");
  head->SetAttribute("ambient", "0.3 0.3 0.3");
  head->SetAttribute("specular", "0 0 0");
  child(visual, "rgba")->SetAttribute("haze", "0.15 0.25 0.35 1");
  XMLElement* global = child(visual, "global");
  global->SetAttribute("azimuth", 120);
  global->SetAttribute("elevation", -25);
  XMLElement* asset = child(root, "asset");
  XMLElement* sky = child(asset, "texture");
  sky->SetAttribute("type", "skybox");
  sky->SetAttribute("builtin", "gradient");
  sky->SetAttribute("rgb1", "0.3 0.5 0.7");
  sky->SetAttribute("rgb2", "0 0 0");
  sky->SetAttribute("width", 512);
  sky->SetAttribute("height", 3072);
  XMLElement* tex = child(asset, "texture");
  tex->SetAttribute("type", "2d");
  tex->SetAttribute("name", "groundplane");
  tex->SetAttribute("builtin", "checker");
  tex->SetAttribute("mark", "edge");
  tex->SetAttribute("rgb1", "0.2 0.3 0.4");
  tex->SetAttribute("rgb2", "0.1 0.2 0.3");
  tex->SetAttribute("markrgb", "0.8 0.8 0.8");
  tex->SetAttribute("width", 300);
  tex->SetAttribute("height", 300);
  XMLElement* mtl = child(asset, "material");
  mtl->SetAttribute("name", "groundplane");
  mtl->SetAttribute("texture", "groundplane");
  mtl->SetAttribute("texuniform", "true");
  mtl->SetAttribute("texrepeat", "5 5");
  mtl->SetAttribute("reflectance", "0.2");
}

// The Menagerie scene file: includes the robot file, adds the look, a light and the floor.
std::string menagerieSceneXml(const RobotParams& p, const MujocoSettings& s, const MenagerieFiles& f,
                              const std::string& model, double mu) {
  tinyxml2::XMLDocument doc;
  doc.InsertEndChild(doc.NewComment(
      (" Scene for " + f.robot_file + ": floor, light, skybox (MuJoCo Menagerie layout). Generated by tailsim "
       "(src/mujoco_model/mjcf_generator.cc); do not edit by hand. The floor keeps MuJoCo's default friction (1): "
       "the feet's priority gives the paper's mu = " + g6(mu) + " here and in any other scene. mjcf/README.md. ")
          .c_str()));
  XMLElement* root = doc.NewElement("mujoco");
  doc.InsertEndChild(root);
  root->SetAttribute("model", (model + " scene").c_str());
  child(root, "include")->SetAttribute("file", f.robot_file.c_str());
  addSceneLookAndAssets(root, p, s);
  XMLElement* world = child(root, "worldbody");
  XMLElement* light = child(world, "light");
  light->SetAttribute("pos", "0 0 1.5");
  light->SetAttribute("dir", "0 0 -1");
  light->SetAttribute("directional", "true");
  XMLElement* floor = child(world, "geom");
  floor->SetAttribute("name", mjcf::kFloorGeom);
  floor->SetAttribute("size", "0 0 0.05");
  floor->SetAttribute("type", "plane");
  floor->SetAttribute("material", "groundplane");
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

}  // namespace

MenagerieFiles generateMenagerie(const RobotParams& p, const MujocoSettings& s, const Effects& e,
                                 const std::string& stem) {
  validate(p);
  validateSettings(s);
  requireStem(stem);
  MenagerieFiles f;
  f.robot_file = "tailsim_" + stem + ".xml";
  f.scene_file = "scene_" + stem + ".xml";
  const std::string model = "tailsim_" + stem;
  const double mu = menagerieFootFriction(p, s, e);
  f.robot_xml = menagerieRobotXml(p, s, e, f, model, mu);
  f.scene_xml = menagerieSceneXml(p, s, f, model, mu);
  return f;
}

std::vector<std::string> writeMenagerie(const MenagerieFiles& f, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const std::string robot = (fs::path(dir) / f.robot_file).string(), scene = (fs::path(dir) / f.scene_file).string();
  // A file there is replaced only when it is what would be written, or what tailsim wrote and
  // unchanged since (DIR/.tailsim-manifest): a hand-edited model file is never overwritten.
  for (const auto& [name, text] : {std::make_pair(f.robot_file, &f.robot_xml), std::make_pair(f.scene_file, &f.scene_xml)}) {
    const std::optional<std::string> there = readResultFile((fs::path(dir) / name).string());
    if (there && *there != *text && !manifestNames(dir, name, *there))
      throw std::runtime_error((fs::path(dir) / name).string() +
                               " was not written by tailsim or was edited since: not replaced (move it away, or "
                               "choose another --menagerie folder)");
  }
  for (const auto& [name, text] : {std::make_pair(f.robot_file, &f.robot_xml), std::make_pair(f.scene_file, &f.scene_xml)}) {
    recordInManifest(dir, name, *text);
    writeFileAtomic((fs::path(dir) / name).string(), *text);
  }
  compactManifest(dir);
  return {robot, scene};
}

std::vector<std::string> writeMenagerieFiles(int links, const std::string& dir) {
  return writeMenagerie(
      generateMenagerie(paperRobot(links), MujocoSettings{}, Effects{}, "n" + std::to_string(links)), dir);
}

}  // namespace tailsim
