// The keys of a `kind: optimize` file's `optimize:` section, declared once (fields.h style): the
// section itself, its `limits:` map and the map form of `objective:`. The JSON Schema, the key
// tables of docs/experiment-format.md (experiments/settings_schema.cc) and the lists of allowed
// keys of the optimize reader (design/optimize_config.cc) derive from these declarations. The
// reader reads the values itself, with the checks across keys (restart_growth against population,
// directions_kept with enumerate, max_runs against the first population, ...); the member
// initializers are the defaults it applies (design/stroke_optimizer.h's OptimizerSettings and
// design/stroke_family.h take theirs from here).
//
// Besides fields.h's visitor methods, these use (files without sweeps)
//   interval(const Field&, std::array<double, 2>& x, Limits)   [low, high], both within Limits
//   jointLimit(const Field&, Limits, bool range, TextRule words) a number within Limits (range: a
//        [low, high] pair within Limits) for every joint, or a list of one per joint; or one of words
//   integerList(const Field&, Limits, int max)                  1..max distinct integers within Limits
//   section(const Field&, S& sub)                               a map of sub's declared keys
//   nameOrSection(const Field&, std::string& x, TextRule, S& sub) one of TextRule's names, or a map of
//        sub's declared keys
#pragma once

#include <array>
#include <string>

#include "common/work_limits.h"
#include "settings/fields.h"

namespace tailsim {

// objective: {quantity, model, search, candidates}.
struct OptimizeObjectiveSection {
  std::string quantity = "phi_net";
  std::string model = "analytic";
  std::string search = "perfoot";  // model: mujoco only
  int candidates = 8;              // model: mujoco only
};

// limits: the stroke limits; a joint limit not given here is the robot file's tail entry's.
struct OptimizeLimitsSection {
  std::string end = "rest";
  std::array<double, 2> dT_s{0.05, 1.0};
  std::array<double, 2> w_ss{0.05, 0.95};
  double start_delay_s = 0.0;
  std::string over_torque = "penalize";
};

// The optimize: section. Required: family and limits.
struct OptimizeSection {
  std::string family;  // required
  int knots = 3;
  std::string objective = "phi_net";
  OptimizeObjectiveSection objective_map;
  OptimizeLimitsSection limits;
  std::string algorithm = "cmaes";
  int islands = 2;
  int population = 16;
  int generations = 60;
  int restarts = 1;
  int restart_growth = 1;
  int refine_generations = 0;
  int local_restarts = 0;
  double local_step = 0.1;
  std::string directions = "free";
  int directions_kept = 0;
  std::string polish = "cobyla";
  int polish_evaluations = 200;
  int restart_polish_evaluations = 0;
  int max_runs = 0;
  int pareto_points = 0;
  bool mujoco_check = true;
  double min_turn_deg = 0.1;
};

template <class V, class S>
settings::For<S, OptimizeObjectiveSection> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::TextRule;
  v.text(Field{"quantity", "the objective: phi_net, phi_net_per_torque or phi_net_per_energy"}, s.quantity,
         TextRule{false, {"phi_net", "phi_net_per_torque", "phi_net_per_energy"}});
  v.text(Field{"model", "the model whose phi_net the objective is"}, s.model, TextRule{false, {"analytic", "perfoot", "mujoco"}});
  v.text(Field{"search", "model: mujoco only: the model the candidates are searched on"}, s.search,
         TextRule{false, {"analytic", "perfoot"}});
  v.integer(Field{"candidates", "model: mujoco only: how many of the search's best MuJoCo re-ranks"}, s.candidates,
            settings::Limits::closed(1, 50));
}

template <class V, class S>
settings::For<S, OptimizeLimitsSection> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.jointLimit(Field{"theta_deg", "every joint angle stays in [low, high] (else each joint's range from the robot) [deg]"},
               Limits::closed(-360, 360), true, settings::TextRule{});
  v.jointLimit(Field{"thetadot_max_dps", "every joint speed stays within this (else the robot's) [deg/s]"},
               Limits::closed(1, 36000), false, settings::TextRule{});
  v.jointLimit(Field{"torque_max_Nm", "every joint torque stays within this (else the robot's); base: the base "
                                      "stroke's own peak joint torque; none: no torque limit [N m]"},
               Limits::positive(), false, settings::TextRule{false, {"base", "none"}});
  v.text(Field{"end", "rest (anywhere) or start (back where it started: spline only)"}, s.end,
         settings::TextRule{false, {"rest", "start"}});
  v.interval(Field{"dT_s", "stroke duration range [s]"}, s.dT_s, Limits::closed(0.01, 10));
  v.interval(Field{"w_ss", "split_cycle only: acceleration share range"}, s.w_ss, Limits::closed(0.01, 0.99));
  v.number(Field{"start_delay_s", "per-joint start delay range [0, this] [s]"}, s.start_delay_s, Limits::closed(0, 10));
  v.text(Field{"over_torque", "a stroke over the torque limit: penalize (searched as it is, the excess a violation) "
                              "or slow_down (slowed in time by one factor until its peak torque meets the limit)"},
         s.over_torque, settings::TextRule{false, {"penalize", "slow_down"}});
}

template <class V, class S>
settings::For<S, OptimizeSection> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  using settings::TextRule;
  v.text(Field{"family", "required: the stroke family searched"}, s.family, TextRule{false, {"split_cycle", "spline"}});
  v.integer(Field{"knots", "spline only: interior knots K per joint"}, s.knots, Limits::closed(0, limits::kMaxOptimizeKnots));
  v.nameOrSection(Field{"objective", "phi_net, phi_net_per_torque or phi_net_per_energy (the analytic model's), or "
                                     "{quantity, model, search, candidates} (optimize.objective)"},
                  s.objective, TextRule{false, {"phi_net", "phi_net_per_torque", "phi_net_per_energy"}}, s.objective_map);
  v.section(Field{"limits", "required: the stroke limits (optimize.limits)"}, s.limits);
  v.text(Field{"algorithm", "pagmo2's CMA-ES or DE"}, s.algorithm, TextRule{false, {"cmaes", "de"}});
  v.integer(Field{"islands", "thread islands evolved in parallel, no migration"}, s.islands,
            Limits::closed(1, limits::kMaxOptimizeIslands));
  v.integer(Field{"population", "per island"}, s.population, Limits::closed(5, limits::kMaxOptimizePopulation));
  v.integer(Field{"generations", "per island and restart"}, s.generations, Limits::closed(1, limits::kMaxOptimizeGenerations));
  v.integer(Field{"restarts", "global searches per seed (fresh archipelagos, own sub-seeds)"}, s.restarts,
            Limits::closed(1, limits::kMaxOptimizeRestarts));
  v.integer(Field{"restart_growth", "population factor per restart (2: IPOP-CMA-ES)"}, s.restart_growth,
            Limits::closed(1, 4));
  v.integer(Field{"refine_generations", "CMA-ES generations after each restart's global search"}, s.refine_generations,
            Limits::closed(0, limits::kMaxOptimizeGenerations));
  v.integer(Field{"local_restarts", "CMA-ES runs centred on the best point so far, after the global search"},
            s.local_restarts, Limits::closed(0, limits::kMaxOptimizeLocalRestarts));
  v.number(Field{"local_step", "their initial step, a share of the unit box"}, s.local_step, Limits{0, 1, true, false});
  v.text(Field{"directions", "free, or enumerate (split_cycle): one search per joint-direction pattern"}, s.directions,
         TextRule{false, {"free", "enumerate"}});
  v.integer(Field{"directions_kept", "enumerate: local restarts and polish only in the K best patterns (0: all)"},
            s.directions_kept, Limits::closed(0, 1 << limits::kMaxKeptDirectionsLog2));
  v.text(Field{"polish", "NLopt's COBYLA (limits as constraints), BOBYQA (penalised), or none"}, s.polish,
         TextRule{false, {"cobyla", "bobyqa", "none"}});
  v.integer(Field{"polish_evaluations", "the polish's budget of model runs"}, s.polish_evaluations,
            Limits::closed(0, limits::kMaxPolishEvaluations));
  v.integer(Field{"restart_polish_evaluations", "the polish's algorithm from each global restart's best, this many runs (0: none)"},
            s.restart_polish_evaluations, Limits::closed(0, limits::kMaxPolishEvaluations));
  v.integer(Field{"max_runs", "at most this many model runs per seed (every direction pattern's), polish included (0: no cap)"}, s.max_runs,
            Limits::closed(0, static_cast<int>(limits::kMaxOptimizeRuns)));
  v.integerList(Field{"seeds", "one optimisation per seed (distinct); the best is the result (default [1])"},
                Limits::closed(0, 1000000000), limits::kMaxOptimizeSeeds);
  v.integer(Field{"pareto_points", "0, or 2 or more: the phi_net vs peak torque front"}, s.pareto_points,
            Limits::closed(0, limits::kMaxParetoPoints), settings::IntSet::not_(1));
  v.boolean(Field{"mujoco_check", "re-simulate the optimum in MuJoCo"}, s.mujoco_check);
  v.number(Field{"min_turn_deg", "a best stroke turning the body less is no answer [deg]"}, s.min_turn_deg,
           Limits::closed(0, 90));
}

}  // namespace tailsim
