#include "plotting/result_page.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "experiments/model_registry.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"
#include "plotting/figure_sheet.h"
#include "plotting/result_folder.h"
#include "plotting/result_page_assets.h"
#include "rendering/replay.h"
#include "common/atomic_file.h"
#include "results/columns.h"
#include "common/number_text.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

// The marker that says a DIR/index.html is tailsim's (and may be replaced).
constexpr const char* kGeneratorMeta = "<meta name=\"generator\" content=\"tailsim result page\">";
constexpr const char* kThreeDir = "/usr/share/javascript/three";
constexpr const char* kThreeCopyright = "/usr/share/doc/libjs-three/copyright";
// Rows of a model's series written into a case's replay file at most (longer series are thinned
// evenly; the first and last rows are always kept).
constexpr size_t kMaxReplayRows = 6000;

// Length of the UTF-8 sequence starting at s[i] (1..4), or 0 if it is not valid UTF-8.
size_t utf8Length(const std::string& s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  size_t n = 0;
  unsigned cp = 0;
  if (c < 0x80) return 1;
  if ((c & 0xE0) == 0xC0) n = 2, cp = c & 0x1F;
  else if ((c & 0xF0) == 0xE0) n = 3, cp = c & 0x0F;
  else if ((c & 0xF8) == 0xF0) n = 4, cp = c & 0x07;
  else return 0;
  if (i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((b(i + k) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b(i + k) & 0x3F);
  }
  static const unsigned kMin[5] = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < kMin[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return n;
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  return formatG(v == 0.0 ? 0.0 : v, 9);
}

std::string numArray(const std::vector<double>& v) {
  std::string o = "[";
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) o += ',';
    o += num(v[i]);
  }
  return o + "]";
}

template <class T, class F>
std::string array(const std::vector<T>& v, F each) {
  std::string o = "[";
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) o += ',';
    o += each(v[i]);
  }
  return o + "]";
}

std::string strArray(const std::vector<std::string>& v) { return array(v, jsString); }

std::string joined(const std::vector<std::string>& v, const std::string& sep) {
  std::string o;
  for (size_t i = 0; i < v.size(); ++i) o += (i ? sep : "") + v[i];
  return o;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}


// ---------------------------------------------------------------- geometry

std::string vec(const mjtNum* v, int n) {
  std::vector<double> d(v, v + n);
  return numArray(d);
}

// The robot as the page draws it, from the compiled MJCF: its bodies below the world (parent,
// pose in the parent, the tail joint that turns it about z), the root joint's initial pose and
// the quadruped COM in the root body (as setReplayQpos places it), and every geom of a body
// (type, size, pose in the body, colour; feet numbered 1..4).
std::string geometryJson(const mjModel* m, int links) {
  const MujocoReplayLayout L = findReplayLayout(m, links);
  std::vector<int> tail_of_body(m->nbody, -1);
  std::vector<std::array<double, 3>> jpos(m->nbody, std::array<double, 3>{0, 0, 0});
  for (int i = 1; i <= links; ++i) {
    const int j = mj_name2id(m, mjOBJ_JOINT, mjcf::tailJointName(i).c_str());
    const int b = m->jnt_bodyid[j];
    tail_of_body[b] = i - 1;
    for (int k = 0; k < 3; ++k) jpos[b][k] = m->jnt_pos[3 * j + k];
  }
  std::ostringstream o;
  o << "{\"root\":{\"body\":" << L.root_body - 1 << ",\"free\":" << (L.free_root ? "true" : "false")
    << ",\"pos0\":" << numArray({L.root_pos0[0], L.root_pos0[1], L.root_pos0[2]})
    << ",\"quat0\":" << numArray({L.root_quat0[0], L.root_quat0[1], L.root_quat0[2], L.root_quat0[3]})
    << ",\"com\":" << numArray({L.com_offset[0], L.com_offset[1]}) << "},\"bodies\":[";
  for (int b = 1; b < m->nbody; ++b) {
    o << (b > 1 ? "," : "") << "{\"parent\":" << m->body_parentid[b] - 1 << ",\"pos\":" << vec(m->body_pos + 3 * b, 3)
      << ",\"quat\":" << vec(m->body_quat + 4 * b, 4) << ",\"tail\":" << tail_of_body[b]
      << ",\"jpos\":" << numArray({jpos[b][0], jpos[b][1], jpos[b][2]}) << "}";
  }
  o << "],\"geoms\":[";
  static const std::map<int, const char*> kType = {{mjGEOM_BOX, "box"},         {mjGEOM_SPHERE, "sphere"},
                                                   {mjGEOM_CAPSULE, "capsule"}, {mjGEOM_CYLINDER, "cylinder"},
                                                   {mjGEOM_ELLIPSOID, "ellipsoid"}};
  bool first = true;
  for (int g = 0; g < m->ngeom; ++g) {
    const int b = m->geom_bodyid[g];
    const auto type = kType.find(m->geom_type[g]);
    if (b == 0 || type == kType.end()) continue;  // the floor, meshes and height fields are not drawn
    int foot = 0;
    const char* name = mj_id2name(m, mjOBJ_GEOM, g);
    for (int k = 1; k <= 4; ++k)
      if (name && mjcf::footGeomName(k) == name) foot = k;
    o << (first ? "" : ",") << "{\"body\":" << b - 1 << ",\"type\":\"" << type->second << "\",\"size\":"
      << vec(m->geom_size + 3 * g, 3) << ",\"pos\":" << vec(m->geom_pos + 3 * g, 3)
      << ",\"quat\":" << vec(m->geom_quat + 4 * g, 4) << ",\"rgba\":" << numArray({m->geom_rgba[4 * g], m->geom_rgba[4 * g + 1], m->geom_rgba[4 * g + 2], m->geom_rgba[4 * g + 3]})
      << ",\"foot\":" << foot << "}";
    first = false;
  }
  o << "],\"mass_kg\":" << num(mj_getTotalmass(m)) << ",\"g\":" << num(-m->opt.gravity[2]) << "}";
  return o.str();
}

// The geometry of a case: its folder's MJCF (DIR/mjcf/<hash>.xml, when MuJoCo ran) or the one
// generated from the case as run. Cached by the MJCF text. "null" with a note when neither works.
class GeometryCache {
 public:
  std::string of(const ExperimentResults& r, const ExperimentCase* c, std::vector<std::string>* notes) {
    if (!c) return "null";
    if (c->robot_model) {
      const std::string why = "the 3D replay of " + r.name + " draws the rigid box of the robot's derived parameters; "
                              "its MuJoCo run was the model file's own robot (articulated: legs, feet, servos), "
                              "which the replay does not draw";
      if (std::find(notes->begin(), notes->end(), why) == notes->end()) notes->push_back(why);
    }
    std::string xml;
    try {
      xml = generateMjcf(c->robot, c->mujoco, c->effects);
    } catch (const std::exception& e) {
      return remember("", "the robot of " + r.name + " cannot be drawn: " + e.what(), notes);
    }
    if (auto it = cache_.find(xml); it != cache_.end()) return it->second;
    try {
      MujocoMessages quiet;
      ModelPtr m = loadModelFromXml(xml);
      return cache_[xml] = geometryJson(m.get(), c->robot.numLinks());
    } catch (const std::exception& e) {
      return remember(xml, "the robot of " + r.name + " cannot be drawn: " + e.what(), notes);
    }
  }

 private:
  std::string remember(const std::string& xml, const std::string& why, std::vector<std::string>* notes) {
    if (std::find(notes->begin(), notes->end(), why) == notes->end()) notes->push_back(why);
    return cache_[xml] = "null";
  }
  std::map<std::string, std::string> cache_;
};

// ---------------------------------------------------------------- series

// The columns a replay uses, in the order found in the series.
bool replayColumn(const std::string& name) {
  static const std::vector<std::string> fixed = {
      col::kT, "x_m", "y_m", col::kPhi, "phidot_dps", "MzT_Nm", "MzF_Nm", "Izz_phiddot_Nm", "FFx_N", "FFy_N"};
  if (std::find(fixed.begin(), fixed.end(), name) != fixed.end()) return true;
  const auto starts = [&](const char* p) { return name.rfind(p, 0) == 0; };
  const auto ends = [&](const char* s) {
    const size_t n = std::char_traits<char>::length(s);
    return name.size() >= n && name.compare(name.size() - n, n, s) == 0;
  };
  if (starts("theta") && ends("_deg") && name.find("dot") == std::string::npos) return true;  // theta<i>_deg
  if (starts("foot") && (ends("_Fn_N") || ends("_Ft_N"))) return true;                       // MuJoCo feet
  if (name.size() >= 4 && (name[0] == 'N' || name[0] == 'F') && std::isdigit(static_cast<unsigned char>(name[1])) &&
      ends("_N"))
    return true;  // per-foot N<k>_N, F<k>x_N, F<k>y_N
  return false;
}

std::string seriesJson(const TimeSeries& ts) {
  const size_t rows = ts.numRows();
  std::vector<size_t> keep;
  if (rows <= kMaxReplayRows) {
    for (size_t i = 0; i < rows; ++i) keep.push_back(i);
  } else {
    for (size_t k = 0; k < kMaxReplayRows; ++k)
      keep.push_back(static_cast<size_t>(std::llround(static_cast<double>(k) * (rows - 1) / (kMaxReplayRows - 1))));
  }
  std::string o = "{";
  bool first = true;
  for (size_t c = 0; c < ts.numColumns(); ++c) {
    if (!replayColumn(ts.names()[c])) continue;
    std::vector<double> v;
    v.reserve(keep.size());
    for (size_t i : keep) v.push_back(ts.at(i, static_cast<int>(c)));
    o += (first ? "" : ",") + jsString(ts.names()[c]) + ":" + numArray(v);
    first = false;
  }
  return o + "}";
}

// ---------------------------------------------------------------- the page

std::string indexHtml(bool three) {
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n" << kGeneratorMeta << "\n"
    << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
    << "<title>tailsim results</title>\n<style>\n" << kResultPageCss << "</style>\n</head>\n<body>\n"
    << kResultPageBody
    << (three ? "<script src=\"page/three.min.js\"></script>\n<script src=\"page/OrbitControls.js\"></script>\n" : "")
    << "<script src=\"page/tailsim.js\"></script>\n<script src=\"page/data.js\"></script>\n</body>\n</html>\n";
  return o.str();
}

std::string modelsJson(const ExperimentResults& r) {
  return array(r.models, [&r](const std::string& name) {
    const ModelEntry* e = findModel(name);
    return "{\"name\":" + jsString(name) + ",\"title\":" + jsString(r.modelTitle(name)) +
           ",\"color\":" + jsString(e ? e->color : std::string("#000000")) + "}";
  });
}

std::vector<std::string> figuresOf(const ExperimentResults& r, const fs::path& root) {
  std::vector<std::string> out;
  const fs::path plots = fs::path(r.dir) / "plots";
  std::error_code ec;
  if (!fs::is_directory(plots, ec)) return out;
  for (const auto& e : fs::directory_iterator(plots, ec))
    if (e.path().extension() == ".png" && e.path().filename().string().find(".tmp.") == std::string::npos &&
        e.path().filename().string().find(".tailsim-tmp.") == std::string::npos)
      out.push_back(relUrl(e.path().string(), root.string()));
  std::sort(out.begin(), out.end());
  return out;
}

// Writes DIR/name of the page's own files: replaced only when tailsim wrote them (DIR's manifest,
// or the data of an earlier tailsim's page, recognised by its first call).
void writePageFile(const fs::path& dir, const std::string& name, const std::string& text) {
  writeOwnedFile(dir.string(), name, text, [](const std::string& there) {
    return there.compare(0, 19, "tailsim.caseLoaded(") == 0 || there.compare(0, 19, "tailsim.dataLoaded(") == 0;
  });
}

// One model's per-case columns of data.js, in case order; ok/warnings/error as JS literals.
struct RunColumns {
  std::vector<double> phi, u, tstop, events, wall;
  std::vector<std::string> ok, warn, err;
};

// Appends case c's run of model m (or its absence) to the model's columns.
void addRun(RunColumns& cols, const CaseRecord& c, const std::string& m) {
  const auto run = c.runs.find(m);
  const bool has = run != c.runs.end();
  cols.phi.push_back(has ? run->second.phi_net_deg : NAN);
  cols.u.push_back(has ? run->second.phi_net_uncertainty_deg : NAN);
  cols.tstop.push_back(has ? run->second.t_stop_s : NAN);
  cols.events.push_back(has ? run->second.stick_slip_events : NAN);
  cols.wall.push_back(has ? run->second.wall_time_s : NAN);
  cols.ok.push_back(!has ? "null" : run->second.ok ? "1" : "0");
  cols.warn.push_back(has ? jsString(joined(run->second.warnings, "; ")) : "\"\"");
  cols.err.push_back(has ? jsString(run->second.error) : "\"\"");
}

// Case k's replay: writes page/cases/e<index>c<k>.js with every model's series that can be read
// and returns its URL as a JS string, or "null" when the case kept no series.
std::string caseReplay(const ExperimentResults& r, size_t k, int index, const fs::path& cases_dir,
                       GeometryCache& geometry, std::vector<std::string>& notes) {
  const CaseRecord& c = r.cases[k];
  const ExperimentCase* rc = r.resolvedCase(c);
  if (rc && rc->output.time_series == TimeSeriesOutput::kNone) return "null";
  std::string models;
  for (const std::string& m : r.models) {
    if (!c.runs.count(m)) continue;
    try {
      const TimeSeries ts = r.series(c, m);
      if (ts.numRows() == 0) continue;
      models += (models.empty() ? "" : ",") + jsString(m) + ":" + seriesJson(ts);
    } catch (const std::exception&) {  // a failed run or a missing file: the case has no replay of it
    }
  }
  if (models.empty()) return "null";
  const std::string id = "e" + std::to_string(index) + "c" + std::to_string(k);
  std::vector<double> phases;  // t0, t1, t2 of each joint's stroke (accelerating / decelerating)
  if (rc)
    for (const SplitCycleParams& j : rc->joints) {
      phases.push_back(j.t0_s);
      phases.push_back(j.t0_s + j.w_ss * j.dT_s);
      phases.push_back(j.t0_s + j.dT_s);
    }
  std::string text = "tailsim.caseLoaded({\"id\":" + jsString(id) + ",\"name\":" + jsString(c.name) +
                     ",\"geometry\":" + geometry.of(r, rc, &notes) + ",\"links\":" +
                     std::to_string(rc ? rc->robot.numLinks() : 0) + ",\"strokes\":" + numArray(phases) +
                     ",\"models\":{" + models + "}});\n";
  writePageFile(cases_dir, id + ".js", text);
  return jsString("page/cases/" + id + ".js");
}

// The "axes" entries of data.js: each swept key, its values and each case's index into them.
std::vector<std::string> axesJson(const ExperimentResults& r, const std::vector<std::vector<int>>& axis_index) {
  std::vector<std::string> a;
  for (size_t i = 0; i < r.axes.size(); ++i) {
    const SweepAxis& ax = r.axes[i];
    std::vector<double> numbers;
    for (size_t v = 0; v < ax.values.size(); ++v) numbers.push_back(ax.number(v));
    a.push_back("{\"key\":" + jsString(ax.key) + ",\"label\":" + jsString(axisLabel(leafKey(ax.key))) +
                ",\"numeric\":" + (ax.numeric ? "true" : "false") + ",\"values\":" + strArray(ax.values) +
                ",\"numbers\":" + numArray(numbers) + ",\"index\":" +
                array(axis_index[i], [](int v) { return std::to_string(v); }) + "}");
  }
  return a;
}

// The "runs" object of data.js: per model, its columns over the cases.
std::string runsJson(const std::vector<std::string>& models, std::map<std::string, RunColumns>& runs) {
  std::ostringstream o;
  const auto raw = [](const std::string& s) { return s; };
  for (size_t i = 0; i < models.size(); ++i) {
    const std::string& m = models[i];
    const RunColumns& c = runs[m];
    o << (i ? "," : "") << jsString(m) << ":{\"phi_net_deg\":" << numArray(c.phi)
      << ",\"phi_net_uncertainty_deg\":" << numArray(c.u) << ",\"t_stop_s\":" << numArray(c.tstop)
      << ",\"stick_slip_events\":" << numArray(c.events) << ",\"wall_time_s\":" << numArray(c.wall)
      << ",\"ok\":" << array(c.ok, raw) << ",\"warnings\":" << array(c.warn, raw) << ",\"error\":" << array(c.err, raw)
      << "}";
  }
  return o.str();
}

// One experiment's entry of data.js; writes the replay file of each case that kept time series.
std::string experimentJson(const ExperimentResults& r, int index, const fs::path& root, GeometryCache& geometry) {
  std::vector<std::string> notes;
  if (!r.resolve_error.empty()) notes.push_back(r.resolve_error);
  if (const std::string n = r.seriesNote(); !n.empty()) notes.push_back(n);
  const size_t n = r.cases.size();
  std::vector<std::string> names, replay, verdicts;
  std::vector<std::vector<int>> axis_index(r.axes.size(), std::vector<int>(n, -1));
  std::map<std::string, RunColumns> runs;
  for (size_t k = 0; k < n; ++k) {
    const CaseRecord& c = r.cases[k];
    names.push_back(c.name);
    verdicts.push_back(c.verdict);
    for (size_t a = 0; a < r.axes.size(); ++a)
      if (auto it = c.sweep.find(r.axes[a].key); it != c.sweep.end()) axis_index[a][k] = r.axes[a].indexOf(it->second);
    for (const std::string& m : r.models) addRun(runs[m], c, m);
    replay.push_back(caseReplay(r, k, index, root / "page" / "cases", geometry, notes));
  }
  std::ostringstream o;
  o << "{\"name\":" << jsString(r.name) << ",\"description\":" << jsString(r.description)
    << ",\"kind\":" << jsString(r.kind) << ",\"dir\":" << jsString(relUrl(r.dir, root.string()))
    << ",\"models\":" << modelsJson(r) << ",\"notes\":" << strArray(notes)
    << ",\"figures\":" << strArray(figuresOf(r, root)) << ",\"axes\":[" << joined(axesJson(r, axis_index), ",")
    << "],\"cases\":{\"name\":" << strArray(names) << ",\"verdict\":" << strArray(verdicts) << ",\"replay\":" << array(replay, [](const std::string& s) { return s; })
    << ",\"runs\":{" << runsJson(r.models, runs) << "}}}";
  return o.str();
}

}  // namespace

std::string jsString(const std::string& s) {
  static const char* hex = "0123456789abcdef";
  std::string o = "\"";
  o.reserve(s.size() + 2);
  for (size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const size_t n = utf8Length(s, i);
    if (n == 0) {  // not UTF-8: U+FFFD
      o += "\\ufffd";
      ++i;
      continue;
    }
    if (n == 3 && c == 0xE2 && static_cast<unsigned char>(s[i + 1]) == 0x80 &&
        (static_cast<unsigned char>(s[i + 2]) == 0xA8 || static_cast<unsigned char>(s[i + 2]) == 0xA9)) {
      o += static_cast<unsigned char>(s[i + 2]) == 0xA8 ? "\\u2028" : "\\u2029";
      i += 3;
      continue;
    }
    if (n > 1) {
      o.append(s, i, n);
      i += n;
      continue;
    }
    switch (c) {
      case '"': o += "\\\""; break;
      case '\\': o += "\\\\"; break;
      case '\n': o += "\\n"; break;
      case '\t': o += "\\t"; break;
      case '\r': o += "\\r"; break;
      case '<': o += "\\u003c"; break;
      case '>': o += "\\u003e"; break;
      case '&': o += "\\u0026"; break;
      default:
        if (c < 0x20 || c == 0x7F) {
          o += "\\u00";
          o += hex[c >> 4];
          o += hex[c & 15];
        } else {
          o += static_cast<char>(c);
        }
    }
    ++i;
  }
  return o + "\"";
}

std::string resultPagePath(const std::string& dir) { return (fs::path(dir) / "index.html").string(); }

std::string writeResultPage(const std::string& dir) {
  const fs::path root(dir);
  const std::string index = resultPagePath(dir);
  std::error_code ec;
  if (fs::exists(fs::symlink_status(index, ec))) {
    if (!fs::is_regular_file(fs::symlink_status(index, ec)) || readFile(index).find(kGeneratorMeta) == std::string::npos)
      throw std::runtime_error(index + " exists and was not written by tailsim: not replaced (move it away to get the result page)");
  }
  // three.js, its orbit control and licence; without them (libjs-three not installed) the page has
  // its tables and plots and says why the 3D view is missing.
  std::string three, orbit, licence, three_note;
  try {
    three = readFile(std::string(kThreeDir) + "/three.min.js");
    orbit = readFile(std::string(kThreeDir) + "/examples/js/controls/OrbitControls.js");
    licence = readFile(kThreeCopyright);
  } catch (const std::exception& e) {
    three.clear();
    three_note = std::string("no 3D view: ") + e.what() + " (Debian package libjs-three; apt install libjs-three, then tailsim plot again)";
  }
  const std::vector<ExperimentResults> tree = loadResultTree(dir);
  const fs::path page = root / "page";
  makeResultDir(page.string());
  makeResultDir((page / "cases").string());
  GeometryCache geometry;
  std::vector<std::string> experiments;
  for (size_t i = 0; i < tree.size(); ++i) experiments.push_back(experimentJson(tree[i], static_cast<int>(i), root, geometry));
  const bool figures_html = fs::exists(root / "figures.html", ec);
  const std::string folder = fs::absolute(root).lexically_normal().filename().string();
  const std::string data = "tailsim.dataLoaded({\"folder\":" + jsString(folder) + ",\"note\":" + jsString(three_note) +
                           ",\"figures_html\":" + (figures_html ? "true" : "false") + ",\"experiments\":[" +
                           joined(experiments, ",\n") + "]});\n";
  if (!three.empty()) {
    writePageFile(page, "three.min.js", three);
    writePageFile(page, "OrbitControls.js", orbit);
    writePageFile(page, "three-LICENSE", licence);
  }
  writePageFile(page, "tailsim.js", kResultPageJs);
  writePageFile(page, "data.js", data);
  writeOwnedFile(root.string(), "index.html", indexHtml(!three.empty()),
                 [](const std::string& text) { return text.find(kGeneratorMeta) != std::string::npos; });
  if (!three_note.empty()) std::fprintf(stderr, "note: %s: %s\n", index.c_str(), three_note.c_str());
  return index;
}

}  // namespace tailsim
