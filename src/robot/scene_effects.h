// Which physical effects a scene simulates. Both models read this.
#pragma once

#include "settings/fields.h"


namespace tailsim {

enum class FrictionLaw {
  kNone,        // no foot friction at all (free-floating in the plane)
  kStiction,    // the paper's Simulink law, Eqs. (14)-(16), with event-located stick/slip
  kContinuous,  // the paper's ADAMS law (Fig. 4, paper-notes point 6): mu(slip speed)
};

enum class FootLoadModel {
  kDistributed,  // Appendix Eqs. (A1)-(A5): L_F follows the COM
  kConstant,     // L_F frozen at its value for the initial tail pose
};

// Effects a scene asks for. Defaults reproduce the paper.
struct Effects {
  FrictionLaw friction = FrictionLaw::kStiction;
  bool translation = true;          // false: x, y locked
  bool gravity = true;              // false: no weight, hence no friction
  bool ground_contact = true;       // MuJoCo: feet touch a ground plane
  FootLoadModel foot_loads = FootLoadModel::kDistributed;
  bool load_decomposition = true;   // compute M_zT's acceleration-/speed-driven parts
};

// The YAML/JSON keys of Effects (settings/fields.h), declared once.
template <class V, class S>
settings::For<S, Effects> declareFields(V& v, S& s) {
  using settings::Field;
  static const settings::EnumNames<FrictionLaw> kLaws = {
      {FrictionLaw::kNone, "none"}, {FrictionLaw::kStiction, "stiction"}, {FrictionLaw::kContinuous, "continuous"}};
  static const settings::EnumNames<FootLoadModel> kLoads = {{FootLoadModel::kDistributed, "distributed"},
                                                            {FootLoadModel::kConstant, "constant"}};
  v.choice(Field{"friction", "foot friction: none; stiction (Eqs. 14-16, stick/slip events); continuous (mu of slip speed)"},
           s.friction, kLaws);
  v.boolean(Field{"translation", "false: x, y locked"}, s.translation);
  v.boolean(Field{"gravity", "false: no weight, hence no friction"}, s.gravity);
  v.boolean(Field{"ground_contact", "MuJoCo: feet touch a ground plane"}, s.ground_contact);
  v.choice(Field{"foot_loads", "distributed: L_F follows the COM (Eqs. A1-A5); constant: L_F of the initial pose"},
           s.foot_loads, kLoads);
  v.boolean(Field{"load_decomposition", "compute M_zT's acceleration- and speed-driven parts"}, s.load_decomposition);
}

}  // namespace tailsim
