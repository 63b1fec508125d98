// The settings sections whose checks span keys (mujoco, output, render), and the rules across a
// whole case: the continuous friction law's thresholds, the work limits.
#include "experiments/loader_parts.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "experiments/model_registry.h"
#include "experiments/work_estimate.h"
#include "common/work_limits.h"
#include "common/number_text.h"
#include "common/units.h"
#include "settings/trajectory_section.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <type_traits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <utility>

namespace tailsim {
namespace loader {

MujocoSettings readMujoco(const Reader& r, const Item& item) {
  MujocoSettings s;
  if (!r.pick(item) && item.node.IsMap())
    if (const YAML::Node b = item.node["body_height_m"])
      loader::fail(Loc{r.file(), b.Mark(), joinKey(item.key, "body_height_m")},
                    "not a key: the MuJoCo body stands at the robot's COM height, quadruped.com_height_m "
                    "(one key for both)");
  const MapView m = readDeclared(r, item, s);
  // MuJoCo's own rules on solref and solimp (element by element).
  if (const Item* x = m.get("solref")) {
    const std::vector<Item> v = r.list(*x);
    // MuJoCo: both > 0 (time constant, damping ratio) or direct (-stiffness, -damping).
    if (s.solref[0] > 0.0 && !(s.solref[1] > 0.0)) r.fail(v[1], "damping ratio must be > 0 when solref[0] > 0");
    if (s.solref[0] < 0.0 && s.solref[1] > 0.0) r.fail(v[1], "must be <= 0 (-damping) when solref[0] < 0");
    if (s.solref[0] == 0.0) r.fail(v[0], "must not be 0");
  }
  if (const Item* x = m.get("solimp")) {
    const std::vector<Item> v = r.list(*x);
    for (int i : {0, 1, 3})
      if (!(s.solimp[i] > 0.0 && s.solimp[i] < 1.0)) r.fail(v[i], "must lie in (0, 1), got " + formatG(s.solimp[i]));
    if (!(s.solimp[2] > 0.0)) r.fail(v[2], "width must be > 0, got " + formatG(s.solimp[2]));
    if (!(s.solimp[4] >= 1.0)) r.fail(v[4], "power must be >= 1, got " + formatG(s.solimp[4]));
  }
  return s;
}

// tail_end_s: when the tail stops (kind: simulate), or < 0 (kind: pose, no time series).
OutputSettings readOutput(const Reader& r, const Item& item, double tail_end_s) {
  OutputSettings o;
  const MapView m = readDeclared(r, item, o);
  // The time series needs at least 2 rows (t = 0 and the end); a longer spacing is a mistake.
  const double t_end = o.runEnd(tail_end_s);
  if (tail_end_s >= 0 && o.sample_dt_s > t_end) {
    const Item* at = m.get("sample_dt_s") ? m.get("sample_dt_s") : m.get("duration_s") ? m.get("duration_s") : &item;
    r.fail(*at, "sample_dt_s = " + formatG(o.sample_dt_s) + " s is longer than the run (" + formatG(t_end) +
                    " s): the time series needs at least 2 rows");
  }
  return o;
}

// run_end_s: simulated seconds of the run (the video shows at most that), or < 0 when unknown.
// Field limits: render_settings.h, the same the renderer checks.
RenderSettings readRender(const Reader& r, const Item& item, double run_end_s) {
  RenderSettings s;
  s.enabled = true;  // the section's presence asks for a video
  if (item.node.IsNull() && !r.pick(item)) return s;  // `render:` with nothing: all defaults
  const MapView m = readDeclared(r, item, s);
  if (const Item* x = m.get("size")) {  // a frame-size preset (render_settings.h)
    if (m.get("width") || m.get("height")) r.fail(*x, "give either size or width/height, not both");
    for (const RenderSizePreset& p : kRenderSizePresets)
      if (s.size == p.name) s.width = p.width, s.height = p.height;
  }
  if (run_end_s >= 0.0) {
    const double span = s.duration_s > 0.0 ? std::min(s.duration_s, run_end_s) : run_end_s;
    const double frames = renderFrameCount(span, s);
    if (!(frames <= kRenderMaxFrames)) {
      const Item* at = m.get("duration_s") ? m.get("duration_s") : m.get("slowmo") ? m.get("slowmo") : m.get("fps") ? m.get("fps") : &item;
      r.fail(*at, "the video would have " + formatG(frames) + " frames (" + formatG(span) + " s simulated x fps " +
                      std::to_string(s.fps) + " x slowmo " + formatG(s.slowmo) + "), more than " +
                      formatG(kRenderMaxFrames) + ": lower fps, slowmo or render.duration_s");
    }
  }
  return s;
}

// Refuses a case whose work estimate (experiments/work_estimate.h) exceeds a limit, at the first
// key among the estimate's culprits that the file sets (else at the section, else the file).
void checkCaseWork(const Reader& r, const MapView& top, const ExperimentCase& c) {
  const WorkExcess x = checkWork(c);
  if (x.what.empty()) return;
  const Item* first_section = nullptr;
  for (const std::string& key : x.keys) {
    const std::size_t dot = key.find('.');
    const Item* sec = top.get(key.substr(0, dot));
    if (!sec) continue;
    if (!first_section) first_section = sec;
    const YAML::Node& secNode = sec->node;
    if (r.pick(*sec) || !secNode.IsMap()) continue;
    const YAML::Node v = secNode[key.substr(dot + 1)];
    if (v) r.fail(Item{v, key, v.Mark().is_null() ? sec->mark : v.Mark()}, x.what);
  }
  if (first_section) r.fail(*first_section, x.what);
  r.fail(r.root(top.self.node), x.what);
}

// effects.friction: continuous needs the law's thresholds (robot file or the experiment's friction:):
// phidot_s/d_radps always, v_s/d_mps when translation is simulated.
void requireContinuousThresholds(const Reader& r, const MapView& top, const ExperimentCase& c, const Origins& origin) {
  if (c.effects.friction != FrictionLaw::kContinuous) return;
  const Item* eff = top.get("effects");
  // effects.friction: continuous is set there. (No Item assignment: a YAML::Node's operator=
  // would rewrite the document.)
  const bool direct = !r.pick(*eff) && eff->node.IsMap() && eff->node["friction"];
  const Item at = direct ? Item{eff->node["friction"], "effects.friction", eff->node["friction"].Mark()} : *eff;
  for (const char* k : kContinuousKeys) {
    const bool translation = k[0] == 'v';
    if (translation && !c.effects.translation) continue;
    if (!origin.count(std::string("friction.") + k))
      r.fail(at, std::string("the continuous law needs friction.") + k + " (in the robot file or the experiment's friction:)" +
                     (translation ? "; or effects: {translation: false}" : ""));
  }
}

}  // namespace loader
}  // namespace tailsim
