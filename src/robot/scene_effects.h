// Which physical effects a scene simulates (issue 6). Both models read this.
#pragma once


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

// Effects a scene asks for (issue 6). Defaults reproduce the paper.
struct Effects {
  FrictionLaw friction = FrictionLaw::kStiction;
  bool translation = true;          // false: x, y locked
  bool gravity = true;              // false: no weight, hence no friction
  bool ground_contact = true;       // MuJoCo: feet touch a ground plane
  FootLoadModel foot_loads = FootLoadModel::kDistributed;
  bool load_decomposition = true;   // compute M_zT's acceleration-/speed-driven parts
};

}  // namespace tailsim
