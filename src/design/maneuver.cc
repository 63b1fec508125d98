#include "design/maneuver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "models/analytic/analytic_simulation.h"
#include "design/design_yaml.h"
#include "design/optimize_experiment.h"
#include "experiments/render_case.h"
#include "models/mujoco/mujoco_simulation.h"
#include "plotting/gnuplot.h"
#include "common/atomic_file.h"
#include "common/work_limits.h"
#include "common/units.h"

namespace tailsim {
namespace {

using namespace design_yaml;
using units::kDegPerRad;

std::string g17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

OutputSettings segmentOutput(const ExperimentCase& base, double duration_s) {
  OutputSettings o = base.output;
  o.duration_s = duration_s;
  o.time_series = TimeSeriesOutput::kFull;
  return o;
}

TailTrajectory atZero(const TailTrajectory& t) { return shiftedToZero(t); }

// Columns kept in a maneuver's series (what plots and the video need).
std::vector<std::string> keptColumns(int n) {
  std::vector<std::string> c{"t_s", "x_m", "y_m", "phi_deg", "phidot_dps"};
  for (int i = 1; i <= n; ++i) c.push_back("theta" + std::to_string(i) + "_deg");
  return c;
}

TimeSeries emptySeries(int n) {
  TimeSeries ts;
  for (const std::string& c : keptColumns(n)) ts.addColumn(c);
  return ts;
}

// Appends an analytic segment (starting at rest at t = 0, pose 0) placed at time t_off and at the
// pose (x0, y0, phi0) where the previous one ended; the segment's last row is dropped (the next
// segment's first row is the same instant) unless `last`.
void appendSegment(TimeSeries& out, const TimeSeries& seg, int n, double t_off, double x0, double y0, double phi0, bool last) {
  const auto names = keptColumns(n);
  std::vector<int> idx;
  for (const auto& c : names) idx.push_back(seg.column(c));
  const double c0 = std::cos(phi0), s0 = std::sin(phi0);
  const double xs = seg.at(0, idx[1]), ys = seg.at(0, idx[2]), ps = seg.at(0, idx[3]);
  const std::size_t rows = seg.numRows() - (last ? 0 : 1);
  std::vector<double> row(names.size());
  for (std::size_t r = 0; r < rows; ++r) {
    const double x = seg.at(r, idx[1]) - xs, y = seg.at(r, idx[2]) - ys;
    row[0] = t_off + seg.at(r, idx[0]);
    row[1] = x0 + c0 * x - s0 * y;
    row[2] = y0 + s0 * x + c0 * y;
    row[3] = phi0 * kDegPerRad + seg.at(r, idx[3]) - ps;
    for (std::size_t k = 4; k < names.size(); ++k) row[k] = idx[k] >= 0 ? seg.at(r, idx[k]) : 0.0;
    out.appendRow(row);
  }
}

// Heading figures of a finished run (series phi_deg relative to its first row).
void finishFigures(ManeuverRun& run, const ManeuverSettings& s) {
  const std::vector<double>& t = run.series.values("t_s");
  const std::vector<double>& p = run.series.values("phi_deg");
  if (t.empty()) return;
  const double target = s.heading(), sign = target >= 0 ? 1.0 : -1.0;
  double over = 0;
  long last_out = -1;
  for (std::size_t r = 0; r < t.size(); ++r) {
    const double h = (p[r] - p[0]) / kDegPerRad;
    over = std::max(over, sign * (h - target));
    if (std::abs(target - h) > s.tolerance()) last_out = static_cast<long>(r);
  }
  run.overshoot_rad = over;
  run.final_error_rad = target - (p.back() - p[0]) / kDegPerRad;
  if (last_out + 1 < static_cast<long>(t.size())) {
    run.t_within_s = t[static_cast<std::size_t>(last_out + 1)];
    run.strokes_to_within = 0;
    for (const StrokeRecord& k : run.strokes)
      if (k.t_start_s < run.t_within_s) ++run.strokes_to_within;
  }
}

// The MuJoCo series reduced to the kept columns, phi relative to the start.
TimeSeries keepColumns(const TimeSeries& ts, int n) {
  TimeSeries out = emptySeries(n);
  const auto names = keptColumns(n);
  std::vector<int> idx;
  for (const auto& c : names) idx.push_back(ts.column(c));
  std::vector<double> row(names.size());
  for (std::size_t r = 0; r < ts.numRows(); ++r) {
    for (std::size_t k = 0; k < names.size(); ++k) row[k] = idx[k] >= 0 ? ts.at(r, idx[k]) : 0.0;
    out.appendRow(row);
  }
  return out;
}

double headingAt(const TimeSeries& ts, double t) {  // relative to the first row  [rad]
  const std::vector<double>& tt = ts.values("t_s");
  const std::vector<double>& p = ts.values("phi_deg");
  if (tt.empty()) return 0.0;
  const auto it = std::lower_bound(tt.begin(), tt.end(), t - 1e-9);
  const std::size_t r = it == tt.end() ? tt.size() - 1 : static_cast<std::size_t>(it - tt.begin());
  return (p[r] - p[0]) / kDegPerRad;
}

ManeuverRun fromMujoco(const RunResult& rm, const std::string& label, int n) {
  ManeuverRun run;
  run.label = label;
  run.ok = rm.summary.ok;
  run.error = rm.summary.error;
  run.warnings = rm.summary.warnings;
  run.series = keepColumns(rm.series, n);
  return run;
}

}  // namespace

CycleYaw analyticCycleYaw(const ExperimentCase& base, const ManeuverSettings& s, double scale) {
  const int n = base.robot.numLinks();
  const CycleStrokes c = cycleStrokes(s, n, {scale, 1}, 0.0);
  CycleYaw y;
  const RunResult a = simulateAnalytic(base.robot, atZero(c.fast), base.analytic, base.effects,
                                       segmentOutput(base, c.fast.endTime() - c.fast.startTime() + s.rest_s));
  const RunResult b = simulateAnalytic(base.robot, atZero(c.back), base.analytic, base.effects,
                                       segmentOutput(base, s.return_dT_s + s.rest_s));
  if (!a.summary.ok || !b.summary.ok) throw std::runtime_error("analytic cycle failed: " + a.summary.error + b.summary.error);
  y.fast_rad = a.summary.phi_net_deg / kDegPerRad;
  y.back_rad = b.summary.phi_net_deg / kDegPerRad;
  y.at_rest = a.summary.at_rest && b.summary.at_rest;
  return y;
}

double derivedMinScale(const ExperimentCase& base, const ManeuverSettings& s, double floor) {
  const double tol = s.tolerance();
  if (std::abs(analyticCycleYaw(base, s, 1.0).total()) <= tol) return 1.0;
  double lo = floor, hi = 1.0;
  if (std::abs(analyticCycleYaw(base, s, lo).total()) >= tol) return lo;
  for (int it = 0; it < 30 && hi - lo > 1e-4; ++it) {
    const double mid = 0.5 * (lo + hi);
    (std::abs(analyticCycleYaw(base, s, mid).total()) < tol ? lo : hi) = mid;
  }
  return lo;  // its cycle turns by at most the tolerance
}

YawMap analyticYawMap(const ExperimentCase& base, const ManeuverSettings& s) {
  YawMap m;
  const int N = s.map_points;
  const double full = analyticCycleYaw(base, s, 1.0).total();
  const double sign = full >= 0 ? 1.0 : -1.0;
  double best = 0.0;
  for (int k = 0; k < N; ++k) {
    const double sc = k + 1 == N ? 1.0 : s.min_scale + (1.0 - s.min_scale) * k / (N - 1);
    const double y = k + 1 == N ? full : analyticCycleYaw(base, s, sc).total();
    best = std::max(best, sign * y);  // monotone |yaw| (a running maximum)
    m.scale.push_back(sc);
    m.yaw_rad.push_back(sign * best);
  }
  return m;
}

std::vector<StrokeCommand> planOpenLoop(const ExperimentCase& base, const ManeuverSettings& s, const YawMap& map,
                                        const std::string& where) {
  std::vector<StrokeCommand> plan;
  const double target = s.heading(), full = map.full();
  if (std::abs(target) <= s.tolerance()) return plan;
  const int dir = (target > 0) == (full > 0) ? 1 : -1;
  const int n_full = static_cast<int>(std::floor(std::abs(target) / std::abs(full)));
  for (int k = 0; k < n_full; ++k) plan.push_back({1.0, dir});
  const double rest = std::abs(target) - n_full * std::abs(full);
  if (rest > s.tolerance() * 1e-3) {
    // Bisection on the analytic cycle yaw for the last cycle's scale.
    double lo = s.min_scale, hi = 1.0;
    if (std::abs(analyticCycleYaw(base, s, lo).total()) >= rest) {
      hi = lo;
    } else {
      for (int it = 0; it < 40 && hi - lo > 1e-7; ++it) {
        const double mid = 0.5 * (lo + hi);
        (std::abs(analyticCycleYaw(base, s, mid).total()) < rest ? lo : hi) = mid;
      }
    }
    // Only when it brings the heading nearer: a remainder smaller than half the smallest cycle's
    // turn is nearer without it (target 10 deg by cycles of 1.995: 9.975 deg, not 10.977).
    if (std::abs(rest - std::abs(analyticCycleYaw(base, s, hi).total())) < rest) plan.push_back({hi, dir});
  }
  if (static_cast<int>(plan.size()) > s.max_strokes)
    throw ConfigError((where.empty() ? std::string("maneuver.max_strokes") : where) + ": the plan needs " +
                      std::to_string(plan.size()) + " cycles to turn " + fmtG(s.heading_deg) + " deg, more than max_strokes = " +
                      std::to_string(s.max_strokes) + ": raise max_strokes or lower heading_deg");
  return plan;
}

ManeuverRun runAnalyticOpenLoop(const ExperimentCase& base, const ManeuverSettings& s, const std::vector<StrokeCommand>& plan) {
  const int n = base.robot.numLinks();
  ManeuverRun run;
  run.label = "analytic_open_loop";
  run.series = emptySeries(n);
  double t = 0, x = 0, y = 0, phi = 0;
  std::vector<double> pose = cycleStartPose(s, n, 1);  // the tail starts at direction +1's start pose
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const CycleStrokes c = cycleStrokes(s, n, plan[k], 0.0, &pose);
    pose = cycleStartPose(s, n, plan[k].direction);
    StrokeRecord rec{t, plan[k], phi, phi};
    const char* names[] = {" move to the start", " stroke", " return"};
    int part = 0;
    for (const TailTrajectory* tr : {&c.pre, &c.fast, &c.back}) {
      if (tr->joints.empty()) {
        ++part;
        continue;
      }
      const double dur = (part == 1 ? tr->endTime() - tr->startTime() : s.return_dT_s) + s.rest_s;
      const RunResult a = simulateAnalytic(base.robot, atZero(*tr), base.analytic, base.effects, segmentOutput(base, dur));
      if (!a.summary.ok) {
        run.ok = false;
        run.error = "cycle " + std::to_string(k + 1) + names[part] + ": " + a.summary.error;
        break;
      }
      if (!a.summary.at_rest)
        run.warnings.push_back("cycle " + std::to_string(k + 1) + names[part] +
                               ": the body is still moving when the next stroke starts (raise maneuver.rest_s)");
      for (const std::string& w : a.summary.warnings) run.warnings.push_back("cycle " + std::to_string(k + 1) + names[part] + ": " + w);
      appendSegment(run.series, a.series, n, t, x, y, phi, k + 1 == plan.size() && part == 2);
      const std::size_t last = a.series.numRows() - 1;
      const double dx = a.series.at(last, a.series.column("x_m")) - a.series.at(0, a.series.column("x_m"));
      const double dy = a.series.at(last, a.series.column("y_m")) - a.series.at(0, a.series.column("y_m"));
      x += std::cos(phi) * dx - std::sin(phi) * dy;
      y += std::sin(phi) * dx + std::cos(phi) * dy;
      phi += a.summary.phi_net_deg / kDegPerRad;
      t += dur;
      ++part;
    }
    if (!run.ok) break;
    rec.heading_after_rad = phi;
    run.strokes.push_back(rec);
  }
  if (plan.empty()) run.series.appendRow(std::vector<double>(run.series.numColumns(), 0.0));
  finishFigures(run, s);
  return run;
}

ManeuverRun runMujocoOpenLoop(const ExperimentCase& base, const ManeuverSettings& s, const std::vector<StrokeCommand>& plan) {
  const int n = base.robot.numLinks();
  // The schedule: at each switch time the reference becomes the next stroke (the previous one has
  // ended and holds the angle the next one starts from).
  std::vector<std::pair<double, TailTrajectory>> schedule;
  std::vector<StrokeRecord> strokes;
  double t = 0;
  std::vector<double> pose = cycleStartPose(s, n, 1);
  for (const StrokeCommand& c : plan) {
    const CycleStrokes cs = cycleStrokes(s, n, c, t, &pose);
    pose = cycleStartPose(s, n, c.direction);
    strokes.push_back({t, c, 0, 0});
    if (cs.hasPre()) {
      schedule.emplace_back(t, cs.pre);
      schedule.emplace_back(cs.pre.endTime(), cs.fast);  // holds its start pose until it starts
    } else {
      schedule.emplace_back(t, cs.fast);
    }
    schedule.emplace_back(cs.fast.endTime(), cs.back);
    t = cs.end();
  }
  if (schedule.empty()) schedule.emplace_back(0.0, cycleStrokes(s, n, {1.0, 1}, 1e9).fast);  // held at the start pose
  std::size_t next = 1;
  const double eps = 1e-9;
  const MujocoTrajectoryHook hook = [&](double ts, double, const mjModel*, const mjData*, TailTrajectory& ref) {
    if (next < schedule.size() && ts >= schedule[next].first - eps) {
      ref = schedule[next++].second;
      return true;
    }
    return false;
  };
  const RunResult rm = simulateMujoco(base.robot, schedule.front().second, base.mujoco, base.effects,
                                      segmentOutput(base, std::max(t, base.output.sample_dt_s)), nullptr, nullptr, hook);
  ManeuverRun run = fromMujoco(rm, "mujoco_open_loop", n);
  for (std::size_t k = 0; k < strokes.size(); ++k) {
    strokes[k].heading_before_rad = headingAt(run.series, strokes[k].t_start_s);
    strokes[k].heading_after_rad =
        headingAt(run.series, k + 1 < strokes.size() ? strokes[k + 1].t_start_s : run.series.values("t_s").back());
  }
  run.strokes = strokes;
  finishFigures(run, s);
  return run;
}

ManeuverRun runMujocoClosedLoop(const ExperimentCase& base, const ManeuverSettings& s, const YawMap& map, double duration_s) {
  const int n = base.robot.numLinks();
  const HeadingController ctl(s, map);
  std::vector<StrokeRecord> strokes;
  // The cycle's parts still to come: (switch time, reference); the next cycle once none is left
  // and its last rest is over.
  std::vector<std::pair<double, TailTrajectory>> pending;
  std::vector<double> pose = cycleStartPose(s, n, 1);  // the pose the tail holds between cycles
  double yaw_factor = 1.0;  // measured / predicted yaw of the partial cycles so far (HeadingController::next)
  double t_free = 0.0;  // the cycle's strokes and rests are over from this time
  double phi_prev = 0.0;
  bool done = false;
  const double dt = base.output.sample_dt_s;
  const double kRestRate = 0.5 / kDegPerRad;  // |phi_dot| below this: the body is at rest [rad/s]
  const MujocoTrajectoryHook hook = [&](double ts, double phi, const mjModel*, const mjData*, TailTrajectory& ref) {
    const double rate = std::abs(phi - phi_prev) / dt;
    phi_prev = phi;
    if (!pending.empty()) {
      if (ts < pending.front().first - 1e-9) return false;
      ref = std::move(pending.front().second);
      pending.erase(pending.begin());
      return true;
    }
    if (done || strokes.size() >= static_cast<std::size_t>(s.max_strokes)) return false;
    // Next cycle: the last one is over and the body is at rest (measured), or waited 1 s more.
    if (ts < t_free - 1e-9 || (rate > kRestRate && ts < t_free + 1.0)) return false;
    if (!strokes.empty()) {
      strokes.back().heading_after_rad = phi;
      // A partial cycle that turned the body less (or more) than the analytic map predicts: the
      // next partial cycle asks for the error divided by that factor (MuJoCo's stiction threshold
      // differs from the analytic model's, so a small stroke can turn it far less).
      const StrokeRecord& last = strokes.back();
      if (last.command.scale < 1.0) {
        const double predicted = map.yawAt(last.command.scale);
        const double measured = std::abs(last.heading_after_rad - last.heading_before_rad);
        if (predicted > 0.0) yaw_factor = std::min(2.0, std::max(0.05, measured / predicted));
      }
    }
    const std::optional<StrokeCommand> c = ctl.next(phi, yaw_factor);
    if (!c) {
      done = true;
      return false;
    }
    const CycleStrokes cur = cycleStrokes(s, n, *c, ts, &pose);
    pose = cycleStartPose(s, n, c->direction);
    t_free = cur.end();
    strokes.push_back({ts, *c, phi, phi});
    if (cur.hasPre()) {
      ref = cur.pre;
      pending.emplace_back(cur.pre.endTime(), cur.fast);
    } else {
      ref = cur.fast;
    }
    pending.emplace_back(cur.fast.endTime(), cur.back);
    return true;
  };
  // The reference starts held at the start pose (a stroke that never starts within the run).
  const TailTrajectory hold = cycleStrokes(s, n, {1.0, 1}, 1e6).fast;
  const RunResult rm = simulateMujoco(base.robot, hold, base.mujoco, base.effects, segmentOutput(base, duration_s), nullptr,
                                      nullptr, hook);
  ManeuverRun run = fromMujoco(rm, "mujoco_closed_loop", n);
  if (!strokes.empty()) strokes.back().heading_after_rad = headingAt(run.series, run.series.values("t_s").back());
  run.strokes = strokes;
  if (!done) run.warnings.push_back("the controller was still turning when the run ended (raise maneuver.max_strokes?)");
  finishFigures(run, s);
  return run;
}

namespace {

// Stage 2: the runs: the analytic open loop, and with maneuver.mujoco MuJoCo's open and closed loops.
void runManeuverModels(const ExperimentCase& base, const ManeuverSettings& s, bool progress,
                       const std::function<int()>& stopped, ManeuverReport& rep) {
  const auto stop = [&] { return stopped && (rep.stop_signal = stopped()) != 0; };
  rep.runs.push_back(runAnalyticOpenLoop(base, s, rep.plan));
  if (!s.mujoco || stop()) return;
  rep.runs.push_back(runMujocoOpenLoop(base, s, rep.plan));
  if (progress) std::fprintf(stderr, "MuJoCo open loop done\n");
  if (stop()) return;
  // Closed loop: time for twice the plan's cycles plus two (MuJoCo turns less per cycle), at most max_strokes.
  const int cycles = std::min(s.max_strokes, 2 * static_cast<int>(rep.plan.size()) + 2);
  const double dur = cycles * (cycleDuration(s, 1.0) + 0.2) + 0.5;
  rep.runs.push_back(runMujocoClosedLoop(base, s, rep.map, dur));
  if (progress) std::fprintf(stderr, "MuJoCo closed loop done\n");
}

// Stage 3: maneuver.csv: heading of each run on the output grid (empty where a run has no row).
void writeHeadings(const ExperimentCase& base, const std::string& out_dir, ManeuverReport& rep) {
  std::ostringstream csv;
  csv << "t_s";
  std::size_t rows = 0;
  for (const ManeuverRun& r : rep.runs) {
    csv << "," << r.label << "_heading_deg";
    rows = std::max(rows, r.series.numRows());
  }
  csv << "\n";
  const double dt = base.output.sample_dt_s;
  for (std::size_t k = 0; k < rows; ++k) {
    csv << g17(k * dt);
    for (const ManeuverRun& r : rep.runs) {
      csv << ",";
      if (k < r.series.numRows()) csv << g17(r.series.values("phi_deg")[k] - r.series.values("phi_deg")[0]);
    }
    csv << "\n";
  }
  writeOwnedFile(out_dir, "maneuver.csv", csv.str());
  rep.files.push_back("maneuver.csv");
}

// Stage 4: strokes.csv, a row per stroke of every run.
void writeStrokes(const ManeuverSettings& s, int n, const std::string& out_dir, ManeuverReport& rep) {
  std::ostringstream csv;
  csv << "run,cycle,t_start_s,scale,direction,dtheta_deg,dT_s,return_dT_s,heading_before_deg,heading_after_deg,yaw_deg\n";
  for (const ManeuverRun& r : rep.runs)
    for (std::size_t k = 0; k < r.strokes.size(); ++k) {
      const StrokeRecord& x = r.strokes[k];
      // Joint 1's fast-stroke angle change and the fast stroke's duration.
      const CycleStrokes cs = cycleStrokes(s, n, x.command, 0.0);
      std::vector<JointState> a, b;
      cs.fast.evaluate(-1.0, a);
      cs.fast.evaluate(cs.fast.endTime() + 1.0, b);
      csv << r.label << "," << k + 1 << "," << g17(x.t_start_s) << "," << g17(x.command.scale) << "," << x.command.direction
          << "," << g17((b[0].theta - a[0].theta) * kDegPerRad) << "," << g17(cs.fast.endTime() - cs.fast.startTime())
          << "," << g17(s.return_dT_s) << "," << g17(x.heading_before_rad * kDegPerRad) << ","
          << g17(x.heading_after_rad * kDegPerRad) << "," << g17((x.heading_after_rad - x.heading_before_rad) * kDegPerRad)
          << "\n";
    }
  writeOwnedFile(out_dir, "strokes.csv", csv.str());
  rep.files.push_back("strokes.csv");
}

// Stage 5: yaw_map.csv, the analytic cycle yaw against the stroke scale.
void writeYawMap(const std::string& out_dir, ManeuverReport& rep) {
  std::ostringstream csv;
  csv << "scale,cycle_yaw_deg\n";
  for (std::size_t k = 0; k < rep.map.scale.size(); ++k)
    csv << g17(rep.map.scale[k]) << "," << g17(rep.map.yaw_rad[k] * kDegPerRad) << "\n";
  writeOwnedFile(out_dir, "yaw_map.csv", csv.str());
  rep.files.push_back("yaw_map.csv");
}

// Stage 6: plots/heading.png, every run's heading against the target.
void plotHeadings(const ManeuverSpec& spec, const ManeuverSettings& s, const std::string& out_dir, ManeuverReport& rep) {
  GnuplotFigure fig;
  fig.stem = "heading";
  std::ostringstream b;
  std::ostringstream title;
  title << "Maneuver " << spec.name << ": heading to " << s.heading_deg << " deg";
  b << "set datafile separator ','\nset key bottom right\nset grid\n"
    << "set title " << gpQuote(title.str()) << " noenhanced\n"
    << "set xlabel 't [s]'\nset ylabel 'heading change [deg]'\n";
  // The time axis ends 15 % after the last action: the last stroke's return and rest, or the
  // closed loop settling within tolerance (the runs idle afterwards).
  double t_action = 0;
  for (const ManeuverRun& r : rep.runs) {
    if (!r.strokes.empty()) {
      const StrokeRecord& x = r.strokes.back();
      t_action = std::max(t_action, x.t_start_s + cycleDuration(s, x.command.scale));
    }
    t_action = std::max(t_action, r.t_within_s);
  }
  if (t_action > 0) b << "set xrange [0:" << g17(1.15 * t_action) << "]\n";
  b << "plot " << s.heading_deg << " with lines dt 2 lc rgb '#000000' title 'target'";
  // Runs that follow the same heading stay visible: wide solid under narrower dashed lines.
  const char* colours[] = {"#0072B2", "#E69F00", "#009E73"};
  const char* lines[] = {"lw 5 dt 1", "lw 2.5 dt 2", "lw 2 dt 4"};
  for (std::size_t i = 0; i < rep.runs.size(); ++i)
    b << ", " << gpFileName("../maneuver.csv") << " every ::1 using 1:" << i + 2 << " with lines " << lines[i % 3] << " lc rgb "
      << gpQuote(colours[i % 3]) << " title " << gpQuote(rep.runs[i].label) << " noenhanced";
  b << "\n";
  fig.body = b.str();
  renderFigure((fs::path(out_dir) / "plots").string(), fig);
  rep.files.push_back("plots/heading.png");
}

// Stage 7 (--video with MuJoCo): the video of the analytic open loop beside MuJoCo's closed loop.
void renderManeuverVideo(const ManeuverSpec& spec, const ManeuverSettings& s, int n, const std::string& out_dir,
                         ManeuverReport& rep) {
  ExperimentCase c = spec.base;
  c.name = spec.name;
  c.render.enabled = true;
  c.render.slowmo = 1.0;
  // Show the turn and 2 s after the closed loop is within tolerance (the run idles afterwards).
  if (rep.runs[2].t_within_s >= 0) c.render.duration_s = rep.runs[2].t_within_s + 2.0;
  std::vector<RunResult> runs(2);
  runs[0].summary.model = "analytic";
  runs[0].series = rep.runs[0].series;
  runs[1].summary.model = "mujoco";
  runs[1].series = rep.runs[2].series;
  // The video's phase text follows the case trajectory: the first planned stroke.
  c.joints.clear();
  c.splines.clear();
  if (!rep.plan.empty())
    for (const auto& jp : cycleStrokes(s, n, rep.plan.front(), 0.0).fast.joints) {
      if (jp.isSpline()) c.splines.push_back(jp.spline());
      else c.joints.push_back(jp.params());
    }
  renderCase(c, runs, (fs::path(out_dir) / "renders").string(), "open-loop plan (analytic)");
  rep.files.push_back("renders/" + spec.name + ".mp4");
}

// Stage 8: summary.json.
void writeManeuverSummary(const ManeuverSpec& spec, const ManeuverSettings& s, const std::string& out_dir,
                          const ManeuverReport& rep) {
  nlohmann::json j;
  j["experiment"] = spec.name;
  j["source"] = spec.source_file;
  j["base"] = spec.base_file;
  j["target_deg"] = s.heading_deg;
  j["min_scale"] = s.min_scale;
  j["min_scale_derived"] = !spec.min_scale_given;
  j["stroke_from"] = spec.stroke_file.empty() ? (s.stroke_shape.joints.empty() ? "stroke_deg" : "base") : spec.stroke_file;
  j["tolerance_deg"] = s.tolerance_deg;
  j["analytic_cycle"] = {{"stroke_yaw_deg", rep.full_cycle.fast_rad * kDegPerRad},
                         {"return_yaw_deg", rep.full_cycle.back_rad * kDegPerRad},
                         {"cycle_yaw_deg", rep.full_cycle.total() * kDegPerRad},
                         {"at_rest_between_strokes", rep.full_cycle.at_rest}};
  nlohmann::json plan = nlohmann::json::array();
  for (const StrokeCommand& c : rep.plan) plan.push_back({{"scale", c.scale}, {"direction", c.direction}});
  j["plan"] = plan;
  for (const ManeuverRun& r : rep.runs) {
    auto num = [](double v, bool ok) { return ok ? nlohmann::json(v) : nlohmann::json(); };
    j["runs"][r.label] = {{"ok", r.ok},
                          {"error", r.error},
                          {"strokes", r.strokes.size()},
                          {"strokes_to_within_tolerance", num(r.strokes_to_within, r.t_within_s >= 0)},
                          {"time_to_within_tolerance_s", num(r.t_within_s, r.t_within_s >= 0)},
                          {"final_heading_deg", (s.heading() - r.final_error_rad) * kDegPerRad},
                          {"final_error_deg", r.final_error_rad * kDegPerRad},
                          {"overshoot_deg", r.overshoot_rad * kDegPerRad},
                          {"end_time_s", r.series.numRows() ? r.series.values("t_s").back() : 0.0},
                          {"warnings", r.warnings}};
  }
  j["wall_s"] = rep.wall_s;
  j["files"] = rep.files;
  writeOwnedFile(out_dir, "summary.json", j.dump(2) + "\n");
}

}  // namespace

// The stages in order: the plan (before anything is written), the folder's inputs, the runs, the CSV
// files, the heading plot, the video, the summary.
ManeuverReport runManeuver(const ManeuverSpec& spec, const std::string& out_dir, bool video, bool progress,
                           const std::function<int()>& stopped) {
  const auto w0 = std::chrono::steady_clock::now();
  ManeuverSettings s = spec.settings;
  const ExperimentCase& base = spec.base;
  ManeuverReport rep;
  if (!spec.min_scale_given) s.min_scale = derivedMinScale(base, s, minScaleFloor(s, base.robot.numLinks()));
  rep.min_scale = s.min_scale;
  const int n = base.robot.numLinks();
  // Stage 1, the plan first: one that cannot be run leaves nothing in the folder.
  rep.full_cycle = analyticCycleYaw(base, s, 1.0);
  rep.map = analyticYawMap(base, s);
  rep.plan = planOpenLoop(base, s, rep.map, spec.max_strokes_at);
  fs::create_directories(fs::path(out_dir) / "plots");
  // The folder's own inputs: it runs again after a move (tailsim maneuver DIR/maneuver.yaml).
  for (const auto& [name, text] : designFolderInputs(spec.source_file, "maneuver.yaml", spec.base_file, spec.stroke_file)) {
    writeOwnedFile(out_dir, name, text);
    rep.files.push_back(name);
  }
  if (progress)
    std::fprintf(stderr, "analytic cycle: stroke %+.4f deg, return %+.4f deg; plan: %zu cycles (last scale %.4f)\n",
                 rep.full_cycle.fast_rad * kDegPerRad, rep.full_cycle.back_rad * kDegPerRad, rep.plan.size(),
                 rep.plan.empty() ? 0.0 : rep.plan.back().scale);
  runManeuverModels(base, s, progress, stopped, rep);
  if (rep.stop_signal || (stopped && (rep.stop_signal = stopped()) != 0)) return rep;  // results whole or not at all
  writeHeadings(base, out_dir, rep);
  writeStrokes(s, n, out_dir, rep);
  writeYawMap(out_dir, rep);
  plotHeadings(spec, s, out_dir, rep);
  if (video && s.mujoco) renderManeuverVideo(spec, s, n, out_dir, rep);
  rep.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  writeManeuverSummary(spec, s, out_dir, rep);
  rep.files.push_back("summary.json");
  return rep;
}

}  // namespace tailsim
