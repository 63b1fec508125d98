#include "design/stroke_optimizer.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <nlopt.hpp>
#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/de.hpp>
#include <pagmo/archipelago.hpp>
#include <pagmo/island.hpp>
#include <pagmo/islands/thread_island.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <stdexcept>

#include "models/analytic/analytic_simulation.h"
#include "models/perfoot/per_foot_model.h"
#include "design/stiction_reach.h"
#include "common/work_limits.h"
#include "common/units.h"

namespace tailsim {

double StrokeEvaluation::fitness() const {
  if (!ok) return kFailedFitness;
  if (violation > 0.0) return violation;
  return -score();
}

Effects searchEffects(const ExperimentCase& base) {
  Effects e = base.effects;
  e.load_decomposition = false;  // output rows only
  // Eq. (9) as the paper writes it is diagonal and the rotational friction (Eq. 16, or the ADAMS
  // law) needs only the tail pose and phi_dot: the yaw does not depend on the translation. Locked,
  // the run skips the slide's two stiff phases (Fig. 7: 362 right-hand sides instead of 1,149).
  if (base.analytic.coupling == Coupling::kPaper) e.translation = false;
  return e;
}

StrokeEvaluation evaluateStroke(const StrokeProblem& p, const TailTrajectory& traj, const StrokeFigures* figures) {
  StrokeEvaluation e;
  e.figures = figures ? *figures : strokeFigures(p.base.robot.tail, traj);
  e.violation = limitViolation(e.figures, p.space.limits);
  OutputSettings out;
  out.settle_s = p.base.output.settle_s;
  out.duration_s = 0.0;
  // Two rows, t = 0 and the end: phi_net comes from the state, not the rows, and a row while the
  // tail moves costs an evaluation with the M_z,T decomposition (one every 10 ms was ~1/4 of a run).
  out.sample_dt_s = traj.endTime() + out.settle_s;
  RunResult r;
  if (p.search_model == ObjectiveModel::kPerFoot) {
    Effects pe = p.base.effects;
    pe.load_decomposition = false;
    try {
      r = simulatePerFoot(p.base.robot, traj, p.base.perfoot, pe, out);
    } catch (const std::exception& ex) {  // settings it cannot run with: this point fails, the search goes on
      e.error = ex.what();
      return e;
    }
  } else {
    r = simulateAnalytic(p.base.robot, traj, p.base.analytic, searchEffects(p.base), out);
  }
  e.ok = r.summary.ok && std::isfinite(r.summary.phi_net_deg);
  e.error = r.summary.error;
  if (e.ok) {
    e.phi_net_rad = units::radians(r.summary.phi_net_deg);
    e.objective = objectiveValue(p.objective, e.phi_net_rad, e.figures);
    if (e.phi_net_rad == 0.0) e.stiction_ratio = stictionReach(p.base, traj).ratio;
  }
  return e;
}

StrokeEvaluation evaluateStroke(const StrokeProblem& p, const std::vector<double>& x) {
  StrokeFigures f;
  bool have = false;
  const TailTrajectory t = p.space.trajectory(x, &f, &have);
  return evaluateStroke(p, t, have ? &f : nullptr);
}

namespace {

using Clock = std::chrono::steady_clock;

// Shared by every island's copy of the problem: counts runs and keeps the best feasible point.
struct Tracker {
  std::mutex mu;
  long evaluations = 0;
  double best_objective = 0.0;
  bool have_best = false;
  std::vector<double> best_x;
  StrokeEvaluation best;
  std::size_t keep = 0;  // candidates kept (StrokeProblem::keep_candidates)
  std::vector<std::pair<std::vector<double>, StrokeEvaluation>> top;  // best first, distinct objectives

  void record(const std::vector<double>& x, const StrokeEvaluation& e) {
    std::lock_guard<std::mutex> lock(mu);
    ++evaluations;
    if (keep > 0 && e.feasible() && e.objective > 0.0 &&
        (top.size() < keep || e.objective > top.back().second.objective)) {
      // Distinct: a point within 1e-6 of a kept one's objective is the same optimum (the polish
      // and the local restarts revisit it many times).
      bool same = false;
      for (auto& t : top)
        if (std::abs(t.second.objective - e.objective) <= 1e-6 * t.second.objective) {
          same = true;
          if (e.objective > t.second.objective) t = {x, e};
          break;
        }
      if (!same) {
        top.emplace_back(x, e);
        std::stable_sort(top.begin(), top.end(), [](const auto& a, const auto& b) { return a.second.objective > b.second.objective; });
        if (top.size() > keep) top.pop_back();
      } else {
        std::stable_sort(top.begin(), top.end(), [](const auto& a, const auto& b) { return a.second.objective > b.second.objective; });
      }
    }
    if (e.feasible() && (!have_best || e.betterThan(best) ||
                         (!best.betterThan(e) && x < best_x))) {  // ties: deterministic
      have_best = true;
      best_objective = e.objective;
      best_x = x;
      best = e;
    }
  }
};

struct PagmoStroke {
  std::shared_ptr<const StrokeProblem> p;
  std::shared_ptr<Tracker> tracker;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    const StrokeEvaluation e = evaluateStroke(*p, x);
    tracker->record(x, e);
    return {e.fitness()};
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    const auto d = static_cast<std::size_t>(p ? p->space.dim() : 1);
    return {pagmo::vector_double(d, 0.0), pagmo::vector_double(d, 1.0)};
  }
  std::string get_name() const { return "tailsim stroke"; }
};

pagmo::algorithm makeAlgorithm(const OptimizerSettings& s, unsigned seed) {
  if (s.algorithm == "cmaes")
    return pagmo::algorithm(pagmo::cmaes(1u, -1, -1, -1, -1, 0.3, 1e-9, 1e-9, true, true, seed));
  if (s.algorithm == "de") return pagmo::algorithm(pagmo::de(1u, 0.8, 0.9, 2u, 1e-9, 1e-9, seed));
  throw std::invalid_argument("unknown algorithm '" + s.algorithm + "' (cmaes, de)");
}

}  // namespace

namespace {

// The search in one space, in stages: restarts of the global search (and refine), the local
// restarts, the polish. Enumerated directions run the global stage in every pattern first and the
// later stages only in the best patterns (directions_kept), so the stages are separate calls.
class SpaceSearch {
 public:
  SpaceSearch(const StrokeProblem& prob, const OptimizerSettings& s, ProgressFn progress = {})
      : prob_(prob), s_(s), progress_(std::move(progress)), shared_(std::make_shared<const StrokeProblem>(prob)), tracker_(std::make_shared<Tracker>()),
        pp_(PagmoStroke{shared_, tracker_}) {
    tracker_->keep = static_cast<std::size_t>(std::max(0, prob.keep_candidates));
    if (s.islands < 1 || s.population < 5 || s.generations < 1 || s.polish_evaluations < 0 || s.restarts < 1 ||
        s.restart_growth < 1 || s.refine_generations < 0 || s.restart_polish_evaluations < 0 || s.local_restarts < 0 || !(s.local_step > 0.0) ||
        s.directions_kept < 0)
      throw std::invalid_argument("optimizer settings out of range");
    if (s.max_runs > 0) setMaxRuns(s.max_runs, true);
    // The start: the base experiment's own trajectory (e.g. Eq. 25), in every island's population.
    x0_ = prob.space.pointOf(prob.base.joints);
    res_.start = evaluateStroke(prob, prob.base.trajectory());
    tracker_->record(x0_, evaluateStroke(prob, x0_));
    snapshot("global");
    endStage();
  }

  // At most max_runs runs in all, counted from this search's first (OptimizerSettings::max_runs);
  // with_polish: the last polish_evaluations of them are kept for the polish.
  void setMaxRuns(long max_runs, bool with_polish) {
    max_runs_ = max_runs;
    budget_ = max_runs - (with_polish && s_.polish != "none" ? s_.polish_evaluations : 0);
  }

  long evaluations() const {
    std::lock_guard<std::mutex> lock(tracker_->mu);
    return tracker_->evaluations;
  }

  double bestObjective() const {
    std::lock_guard<std::mutex> lock(tracker_->mu);
    return tracker_->have_best ? tracker_->best_objective : -1.0;
  }

  // Restarts (a multimodal problem): each is a fresh archipelago with its own sub-seeds
  // and random populations; only the first holds the start point (CMA-ES centres on a population's
  // best, so the start in every restart would pull each back to the same basin). IPOP: the
  // population grows by restart_growth per restart. The tracker keeps the best over all restarts.
  // Restarts [first, last) of the global search.
  void globalStage(int first, int last) {
    stage_start_ = Clock::now();
    long pop_size = s_.population;
    for (int r = 0; r < first; ++r) pop_size *= s_.restart_growth;
    for (int r = first; r < last; ++r, pop_size *= s_.restart_growth) {
      if (!room(s_.islands * pop_size)) break;  // the budget cannot hold its first population
      pagmo::archipelago archi;
      for (int i = 0; i < s_.islands; ++i) {
        const unsigned seed = subSeed(i, r);
        pagmo::population pop(pp_, static_cast<pagmo::population::size_type>(pop_size), seed);
        if (r == 0) pop.set_x(0, x0_);
        archi.push_back(pagmo::thread_island{}, makeAlgorithm(s_, seed + 1u), std::move(pop));
      }
      evolve(archi, s_.generations, "global", s_.islands * pop_size);
      // Refine: CMA-ES continues on each island's population, centred on its best point with a
      // small step (5 % of the box): the global search (e.g. DE, which explores widely but
      // converges slowly) finds the basin, CMA-ES converges in it.
      if (s_.refine_generations > 0) {
        for (int i = 0; i < s_.islands; ++i)
          archi[static_cast<pagmo::archipelago::size_type>(i)].set_algorithm(
              pagmo::algorithm(pagmo::cmaes(1u, -1, -1, -1, -1, 0.05, 1e-9, 1e-9, true, true, subSeed(i, r) + 2u)));
        evolve(archi, s_.refine_generations, "refine", s_.islands * pop_size);
      }
      // This restart's basin converged by the polish's algorithm from the restart's best point
      // (not the best over all restarts: that one is polished at the end).
      if (s_.restart_polish_evaluations > 0 && s_.polish != "none") {
        const std::size_t best = bestIsland(archi);
        const pagmo::population pop = archi[best].get_population();
        long evals = s_.restart_polish_evaluations;
        {
          std::lock_guard<std::mutex> lock(tracker_->mu);
          evals = std::min(evals, budget_ - tracker_->evaluations);
        }
        polish(pop.champion_x(), evals);
      }
    }
    endStage();
  }

  // Local restarts: CMA-ES runs with a small step (local_step of the box), each centred on the
  // best point found so far (pagmo's CMA-ES centres its first generation on the population's
  // best: the incumbent, placed in a random population). Iterated local search: each run starts
  // from the best of all before it, so the search moves on to better neighbouring basins and
  // converges further in the best one (the optimum lies on many bounds at once, where one short
  // CMA-ES run stops early). Then the polish from the best feasible point (NLopt, same unit box).
  void localStageAndPolish() {
    stage_start_ = Clock::now();
    for (int k = 0; k < s_.local_restarts; ++k) {
      if (!room(static_cast<long>(s_.islands) * s_.population)) break;
      std::vector<double> centre;
      {
        std::lock_guard<std::mutex> lock(tracker_->mu);
        centre = tracker_->have_best ? tracker_->best_x : x0_;
      }
      pagmo::archipelago archi;
      for (int i = 0; i < s_.islands; ++i) {
        const unsigned seed = subSeed(i, s_.restarts + k) + 5u;
        pagmo::population pop(pp_, static_cast<pagmo::population::size_type>(s_.population), seed);
        pop.set_x(0, centre);
        archi.push_back(pagmo::thread_island{},
                        pagmo::algorithm(pagmo::cmaes(1u, -1, -1, -1, -1, s_.local_step, 1e-9, 1e-9, true, true, seed + 1u)),
                        std::move(pop));
      }
      evolve(archi, s_.generations, "local", static_cast<long>(s_.islands) * s_.population);
    }
    if (s_.polish != "none" && s_.polish_evaluations > 0 && tracker_->have_best) {
      std::vector<double> x;
      long evals = s_.polish_evaluations;
      {
        std::lock_guard<std::mutex> lock(tracker_->mu);
        x = tracker_->best_x;
        evals = std::min(evals, max_runs_ - tracker_->evaluations);
      }
      polish(x, evals);
    }
    endStage();
  }

  OptimizeResult finish() {
    res_.evaluations = tracker_->evaluations;
    res_.wall_s = wall_s_;
    if (tracker_->have_best) {
      res_.x = tracker_->best_x;
      res_.best = tracker_->best;
    } else {
      res_.x = x0_;
      res_.best = evaluateStroke(prob_, x0_);
    }
    res_.directions = prob_.space.directions;
    res_.trajectory = prob_.space.trajectory(res_.x);
    for (const auto& [x, e] : tracker_->top) res_.candidates.push_back({prob_.space.trajectory(x), e});
    return std::move(res_);
  }

 private:
  unsigned subSeed(int island, int restart) const {
    return static_cast<unsigned>(s_.seed * 1000003u + static_cast<unsigned>(island) * 7919u +
                                 static_cast<unsigned>(restart) * 104729u);
  }

  // True when `runs` more keep the search within its budget (OptimizerSettings::max_runs).
  bool room(long runs) const {
    std::lock_guard<std::mutex> lock(tracker_->mu);
    return tracker_->evaluations + runs <= budget_;
  }

  // The island whose population holds the archipelago's best point so far (the lowest fitness;
  // ties: the lower index).
  static std::size_t bestIsland(const pagmo::archipelago& archi) {
    std::size_t best = 0;
    double f_best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < archi.size(); ++i) {
      const double f = archi[i].get_population().champion_f()[0];
      if (f < f_best) {
        f_best = f;
        best = i;
      }
    }
    return best;
  }

  // `generations` generations of every island, each of at most `runs_per_generation` runs; stops
  // before a generation the budget cannot hold.
  void evolve(pagmo::archipelago& archi, int generations, const char* stage, long runs_per_generation) {
    for (int g = 1; g <= generations; ++g) {
      if (!room(runs_per_generation)) break;
      archi.evolve(1);
      archi.wait_check();
      ++gen_count_;
      snapshot(stage);
    }
  }

  void endStage() { wall_s_ += std::chrono::duration<double>(Clock::now() - stage_start_).count(); }

  void snapshot(const char* stage) {
    SearchProgress p;
    {
      std::lock_guard<std::mutex> lock(tracker_->mu);
      res_.history.push_back({gen_count_, tracker_->evaluations,
                              wall_s_ + std::chrono::duration<double>(Clock::now() - stage_start_).count(),
                              tracker_->have_best ? tracker_->best_objective : 0.0,
                              tracker_->have_best ? tracker_->best.phi_net_rad : 0.0, stage});
      p = {stage, tracker_->evaluations, res_.history.back().best_objective, res_.history.back().best_phi_net_rad};
    }
    if (progress_) progress_(p);
  }

  // NLopt (polish: cobyla | bobyqa) from x, at most evals runs.
  void polish(std::vector<double> x, long evals) {
    const unsigned d = static_cast<unsigned>(prob_.space.dim());
    nlopt::opt opt(s_.polish == "cobyla" ? nlopt::LN_COBYLA : nlopt::LN_BOBYQA, d);
    opt.set_lower_bounds(std::vector<double>(d, 0.0));
    opt.set_upper_bounds(std::vector<double>(d, 1.0));
    if (evals <= 0) return;
    opt.set_maxeval(static_cast<int>(evals));
    opt.set_xtol_rel(1e-7);
    opt.set_initial_step(0.02);
    struct Ctx {
      const StrokeProblem* p;
      Tracker* t;
      std::vector<double> last_x;
      StrokeEvaluation last;
      bool bobyqa;
      const StrokeEvaluation& eval(const std::vector<double>& x) {
        if (x != last_x || last_x.empty()) {
          last = evaluateStroke(*p, x);
          last_x = x;
          t->record(x, last);
        }
        return last;
      }
    } ctx{&prob_, tracker_.get(), {}, {}, s_.polish == "bobyqa"};
    opt.set_max_objective(
        [](const std::vector<double>& x, std::vector<double>&, void* data) {
          auto* c = static_cast<Ctx*>(data);
          const StrokeEvaluation& e = c->eval(x);
          if (!e.ok) return -10.0;
          return c->bobyqa ? -e.fitness() : e.score();
        },
        &ctx);
    if (s_.polish == "cobyla")
      opt.add_inequality_constraint(
          [](const std::vector<double>& x, std::vector<double>&, void* data) {
            const StrokeEvaluation& e = static_cast<Ctx*>(data)->eval(x);
            return e.ok ? e.violation : 1.0;
          },
          &ctx, 0.0);
    double f = 0.0;
    try {
      opt.optimize(x, f);
    } catch (const std::exception&) {
      // NLopt's roundoff/forced stops: the tracker holds the best feasible point seen.
    }
    ++gen_count_;
    snapshot("polish");
  }

  const StrokeProblem& prob_;
  OptimizerSettings s_;
  ProgressFn progress_;
  std::shared_ptr<const StrokeProblem> shared_;
  std::shared_ptr<Tracker> tracker_;
  pagmo::problem pp_;
  std::vector<double> x0_;
  OptimizeResult res_;
  int gen_count_ = 0;
  double wall_s_ = 0.0;
  long max_runs_ = std::numeric_limits<long>::max();  // runs in all, the polish included
  long budget_ = std::numeric_limits<long>::max();    // runs before the polish (max_runs less the polish's share)
  Clock::time_point stage_start_ = Clock::now();  // wall time counts the stages only (not the waits between)
};

OptimizeResult searchSpace(const StrokeProblem& prob, const OptimizerSettings& s, const ProgressFn& progress) {
  SpaceSearch search(prob, s, progress);
  search.globalStage(0, s.restarts);
  search.localStageAndPolish();
  return search.finish();
}

// Progress over all direction patterns: runs summed, the best of the patterns' bests.
class PatternsProgress {
 public:
  PatternsProgress(const ProgressFn& progress, int patterns)
      : progress_(progress), per_pattern_(static_cast<std::size_t>(patterns)) {}
  // Pattern `mask`'s progress function (none without a progress function); it refers to this object.
  ProgressFn forPattern(int mask) {
    if (!progress_) return {};
    return [this, mask](const SearchProgress& p) {
      per_pattern_[static_cast<std::size_t>(mask)] = p;
      SearchProgress all{p.stage, 0, 0.0, 0.0};
      for (const SearchProgress& q : per_pattern_) {
        all.evaluations += q.evaluations;
        if (q.best_objective > all.best_objective) {
          all.best_objective = q.best_objective;
          all.best_phi_net_rad = q.best_phi_net_rad;
        }
      }
      progress_(all);
    };
  }

 private:
  const ProgressFn& progress_;
  std::vector<SearchProgress> per_pattern_;
};

// The problem of each direction pattern: joint j strokes down (-1) where bit j of the mask is set.
std::vector<StrokeProblem> directionProblems(const StrokeProblem& prob, int n) {
  const int patterns = 1 << n;
  std::vector<StrokeProblem> problems(static_cast<std::size_t>(patterns), prob);
  for (int mask = 0; mask < patterns; ++mask) {
    StrokeProblem& p = problems[static_cast<std::size_t>(mask)];
    p.space.directions.assign(static_cast<std::size_t>(n), 1);
    for (int j = 0; j < n; ++j)
      if ((mask >> j) & 1) p.space.directions[static_cast<std::size_t>(j)] = -1;
  }
  return problems;
}

// Successive halving: the first global restart in every pattern, then the other restarts, the
// local restarts and the polish in the `kept` patterns whose first restart found the most (ties:
// the lower pattern index).
void halveDirections(std::vector<std::unique_ptr<SpaceSearch>>& searches, int kept, int restarts, long max_runs) {
  const long patterns = static_cast<long>(searches.size());
  // max_runs is the seed's: the first restarts share it evenly, the kept patterns what they leave.
  for (auto& search : searches) {
    if (max_runs > 0) search->setMaxRuns(max_runs / patterns, false);
    search->globalStage(0, 1);
  }
  std::vector<int> order(searches.size());
  for (std::size_t m = 0; m < order.size(); ++m) order[m] = static_cast<int>(m);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return searches[static_cast<std::size_t>(a)]->bestObjective() > searches[static_cast<std::size_t>(b)]->bestObjective();
  });
  for (int k = 0; k < kept; ++k) {
    SpaceSearch& search = *searches[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])];
    if (max_runs > 0) {  // an even share of the runs left, the earlier kept patterns' unused runs included
      long used = 0;
      for (const auto& other : searches) used += other->evaluations();
      search.setMaxRuns(search.evaluations() + (max_runs - used) / (kept - k), true);
    }
    search.globalStage(1, restarts);
    search.localStageAndPolish();
  }
}

// The patterns' results as one: the best feasible (the first pattern's if none is), every
// pattern's best, the candidates, and one history curve over all patterns (rows after each
// pattern's first continue the counts).
OptimizeResult mergePatterns(std::vector<std::unique_ptr<SpaceSearch>>& searches) {
  OptimizeResult all;
  double best_so_far = 0.0, best_phi = 0.0;
  for (std::size_t mask = 0; mask < searches.size(); ++mask) {
    OptimizeResult r = searches[mask]->finish();
    const int gen0 = all.history.empty() ? 0 : all.history.back().generation;
    for (std::size_t k = mask == 0 ? 0 : 1; k < r.history.size(); ++k) {
      HistoryRow row = r.history[k];
      row.generation += gen0;
      row.evaluations += all.evaluations;
      row.wall_s += all.wall_s;
      if (row.best_objective > best_so_far) {
        best_so_far = row.best_objective;
        best_phi = row.best_phi_net_rad;
      }
      row.best_objective = best_so_far;
      row.best_phi_net_rad = best_phi;
      all.history.push_back(row);
    }
    all.evaluations += r.evaluations;
    all.wall_s += r.wall_s;
    all.by_direction.push_back({r.directions, r.best, r.evaluations});
    for (Candidate& c : r.candidates) all.candidates.push_back(std::move(c));
    if (mask == 0) all.start = r.start;
    const bool better = r.best.feasible() && (!all.best.feasible() || r.best.betterThan(all.best));
    if (mask == 0 || better) {
      all.x = r.x;
      all.best = r.best;
      all.directions = r.directions;
      all.trajectory = r.trajectory;
    }
  }
  return all;
}

}  // namespace

// Stages: one search per direction pattern (run through, or halved), their results merged, the
// candidates kept, and the base stroke if no pattern is feasible.
OptimizeResult optimizeStroke(const StrokeProblem& prob, const OptimizerSettings& s, const ProgressFn& progress) {
  if (!s.enumerate_directions) return searchSpace(prob, s, progress);
  if (prob.space.family != StrokeFamily::kSplitCycle)
    throw std::invalid_argument("enumerating stroke directions needs the split-cycle family");
  // The n = 3 problem's basins differ in which joints stroke up and which down (the best found has
  // joint 1 against joints 2 and 3; docs/design-a-tail-stroke.md): one search per pattern, each
  // with its own sub-seeds, finds every pattern's basin instead of the one a single search
  // happens to fall into. All 2^n patterns, mirror images included (no symmetry of the robot or
  // the limits is assumed). Successive halving (directions_kept = K > 0, halveDirections): the
  // others keep their first restart's best. A pattern's search is the same either way (same
  // sub-seeds).
  const int n = prob.space.n_links;
  if (n < 0 || n > limits::kMaxEnumeratedLinks)
    throw std::invalid_argument("enumerating stroke directions: " + std::to_string(n) + " links, at most " +
                                std::to_string(limits::kMaxEnumeratedLinks) + " (2^n patterns)");
  const int patterns = 1 << n;
  const bool halving = s.directions_kept > 0 && s.directions_kept < patterns;
  const std::vector<StrokeProblem> problems = directionProblems(prob, n);
  PatternsProgress all_progress(progress, patterns);
  std::vector<std::unique_ptr<SpaceSearch>> searches;
  for (int mask = 0; mask < patterns; ++mask) {
    OptimizerSettings ps = s;
    ps.seed = s.seed * 4099u + static_cast<std::uint64_t>(mask);
    ps.max_runs = 0;  // the seed's budget is shared out below
    searches.push_back(std::make_unique<SpaceSearch>(problems[static_cast<std::size_t>(mask)], ps,
                                                     all_progress.forPattern(mask)));
    // Without successive halving each pattern's search runs through (as before the option).
    if (!halving) {
      if (s.max_runs > 0) {  // an even share of the runs left, the earlier patterns' unused runs included
        long used = 0;
        for (const auto& other : searches) used += other->evaluations();
        const long later_starts = patterns - 1 - mask;  // the later patterns' start runs
        searches.back()->setMaxRuns(
            searches.back()->evaluations() + (s.max_runs - used - later_starts) / (patterns - mask), true);
      }
      searches.back()->globalStage(0, s.restarts);
      searches.back()->localStageAndPolish();
    }
  }
  if (halving) halveDirections(searches, s.directions_kept, s.restarts, s.max_runs);

  OptimizeResult all = mergePatterns(searches);
  std::stable_sort(all.candidates.begin(), all.candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.eval.objective > b.eval.objective; });
  if (all.candidates.size() > static_cast<std::size_t>(std::max(0, prob.keep_candidates)))
    all.candidates.resize(static_cast<std::size_t>(std::max(0, prob.keep_candidates)));
  // A guard (a stroke of zero length keeps every split-cycle limit, so some pattern is feasible
  // unless every run fails): return the base stroke, as a single search does.
  if (!all.best.feasible()) {
    all.directions = prob.space.directions;
    all.x = prob.space.pointOf(prob.base.joints);
    all.trajectory = prob.space.trajectory(all.x);
    all.best = evaluateStroke(prob, all.x);
  }
  return all;
}

}  // namespace tailsim
