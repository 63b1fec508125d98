// The Python module `tailsim` (docs/python.md): the experiments layer seen from
// Python. Every input goes through the YAML loader (experiments/experiment_loader.h): a file by its
// path (run), or keyword arguments shaped like the sections of an experiment file, written as the
// YAML text of one experiment (simulate). So keys, units, ranges, defaults and error messages are
// the CLI's, declared once (settings/fields.h). No file is written except by run().
//
// The GIL is released while the loader and the models work, so Python threads run cases in parallel.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/keyword_args.h"
#include "experiments/model_registry.h"
#include "experiments/settings_json.h"
#include "experiments/robot_model_cases.h"
#include "results/columns.h"
#include "results/thin_series.h"
#include "tailsim_version.h"

namespace py = pybind11;
using json = nlohmann::json;

namespace tailsim {
namespace {

namespace fs = std::filesystem;

// JSON -> Python objects through Python's own json module (floats round-trip exactly both ways).
py::object toPython(const json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// Writes a settings struct under its YAML keys and units (the value as an experiment file gives it).
struct YamlKeyWriter {
  json& j;
  void number(const settings::Field& f, double x, const settings::Limits&) { j[f.key] = x / f.scale; }
  void integer(const settings::Field& f, int x, const settings::Limits&, const settings::IntSet& = {}) { j[f.key] = x; }
  void boolean(const settings::Field& f, bool x) { j[f.key] = x; }
  template <class E>
  void choice(const settings::Field& f, E x, const settings::EnumNames<E>& names) {
    j[f.key] = settings::nameOf(names, x);
  }
  void text(const settings::Field& f, const std::string& x, const settings::TextRule&) { j[f.key] = x; }
  template <std::size_t N>
  void numbers(const settings::Field& f, const std::array<double, N>& x) {
    j[f.key] = std::vector<double>(x.begin(), x.end());
  }
  template <class T>
  void internal(const settings::Field&, const T&) {}  // not a YAML key
};
template <class S>
json yamlKeys(const S& s) {
  json j = json::object();
  YamlKeyWriter w{j};
  declareFields(w, s);
  return j;
}

constexpr const char* kSimulateLabel = "<tailsim.simulate>";

// A Python value -> JSON, as Python's json module writes it (keys that are numbers, booleans or
// None become their text); numpy scalars and arrays become plain numbers and lists. Bounded as the
// YAML loader bounds a file (kMaxYamlDepth levels, kMaxYamlNodes values), so a list or dict that
// contains itself, or one nested 10^5 deep, is a ConfigError, not a stack overflow. A NUL in a key
// or string and a NaN or infinite number are refused naming their key (the YAML text would cut the
// string at the NUL and write NaN as an empty value).
class JsonFromPython {
 public:
  nlohmann::ordered_json operator()(py::handle o, const std::string& path) { return convert(o, path, 0); }

 private:
  long nodes_ = 0;

  [[noreturn]] static void fail(const std::string& path, const std::string& what) {
    throw ConfigError(std::string(kSimulateLabel) + ": " + (path.empty() ? std::string("(arguments)") : path) + ": " + what);
  }
  static std::string shown(const std::string& s) {  // a NUL as \0, for the message
    std::string out;
    for (const char c : s) out += c == '\0' ? std::string("\\0") : std::string(1, c);
    return out;
  }

  nlohmann::ordered_json convert(py::handle o, const std::string& path, int depth) {
    using oj = nlohmann::ordered_json;
    if (depth > kMaxYamlDepth)
      fail(path.substr(0, 200), "nested deeper than " + std::to_string(kMaxYamlDepth) +
                                    " levels of lists and dicts (a list or dict that contains itself?)");
    if (++nodes_ > kMaxYamlNodes)
      fail(path.substr(0, 200), "more than " + std::to_string(kMaxYamlNodes) + " values in the arguments");
    if (o.is_none()) return nullptr;
    if (py::isinstance<py::bool_>(o)) return o.cast<bool>();
    if (py::isinstance<py::int_>(o)) {
      try {
        return o.cast<long long>();
      } catch (const py::cast_error&) {
      }
      try {
        return o.cast<double>();  // beyond 64 bits: the loader's ranges refuse it
      } catch (const py::cast_error&) {
        fail(path, "the integer is beyond a float's range (about 1.8e308): give a finite number");
      }
    }
    if (py::isinstance<py::float_>(o)) {
      const double x = o.cast<double>();
      if (std::isnan(x)) fail(path, "nan is not a value (give a finite number)");
      if (std::isinf(x)) fail(path, std::string(x > 0 ? "inf" : "-inf") + " is not a value (give a finite number)");
      return x;
    }
    if (py::isinstance<py::str>(o)) {
      std::string v = o.cast<std::string>();
      if (v.find('\0') != std::string::npos) fail(path, "the value '" + shown(v) + "' holds a NUL character");
      return v;
    }
    if (py::isinstance<py::dict>(o)) {
      oj j = oj::object();
      // An ordered_json object finds a key by a linear search: appended through its vector, with a
      // hash set of the keys seen, so a dict of n keys takes O(n), not O(n^2).
      auto& entries = static_cast<oj::object_t::Container&>(j.get_ref<oj::object_t&>());
      std::unordered_set<std::string> seen;
      for (auto kv : o.cast<py::dict>()) {
        const py::handle k = kv.first;
        if (!py::isinstance<py::str>(k) && !py::isinstance<py::int_>(k) && !py::isinstance<py::float_>(k) && !k.is_none())
          throw py::type_error("tailsim: keys must be strings, not " + std::string(py::str(k.get_type().attr("__name__"))));
        const std::string key = k.is_none() ? "null"
                                : py::isinstance<py::bool_>(k) ? (k.cast<bool>() ? "true" : "false")
                                                                : std::string(py::str(k));
        const std::string sub = path.empty() ? key : path + "." + key;
        if (key.find('\0') != std::string::npos) fail(shown(sub), "the key '" + shown(key) + "' holds a NUL character");
        oj v = convert(kv.second, sub, depth + 1);
        if (seen.insert(key).second) entries.emplace_back(key, std::move(v));
        else j[key] = std::move(v);  // 1 and '1': one key, the later value (as before)
      }
      return j;
    }
    if (py::isinstance<py::list>(o) || py::isinstance<py::tuple>(o)) {
      oj j = oj::array();
      std::size_t i = 0;
      for (py::handle e : o) j.push_back(convert(e, path + "[" + std::to_string(i++) + "]", depth + 1));
      return j;
    }
    if (py::hasattr(o, "tolist")) return convert(o.attr("tolist")(), path, depth);
    throw py::type_error("tailsim: cannot use a value of type " + std::string(py::str(o.get_type().attr("__name__"))) +
                         " in a setting (numbers, strings, booleans, lists and dicts only)");
  }
};

// What simulate() returns: the time series (columns in the CSV's order), the summary (summary.json's
// entry for the run) and every resolved parameter (result.json's "resolved").
struct Simulation {
  py::dict series;     // column name -> 1-D float64 numpy array
  py::list columns;    // the names, in the CSV's column order
  py::dict summary;
  py::dict resolved;
  std::string model;
};

py::dict seriesToNumpy(const TimeSeries& ts, py::list& columns) {
  py::dict out;
  for (std::size_t c = 0; c < ts.numColumns(); ++c) {
    const std::vector<double>& v = ts.values(static_cast<int>(c));
    py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
    std::copy(v.begin(), v.end(), a.mutable_data());
    out[py::str(ts.names()[c])] = a;
    columns.append(py::str(ts.names()[c]));
  }
  return out;
}

// A path or name given as a Python str: a NUL would silently cut it where the C library reads it,
// so it is refused as Python's own file functions refuse it.
void requireNoNul(const std::string& s, const char* arg) {
  if (s.find('\0') != std::string::npos) throw py::value_error(std::string(arg) + ": embedded null character");
}

Simulation simulate(py::object robot, py::object trajectory, const std::string& model, py::kwargs sections) {
  if (py::isinstance<py::str>(robot)) requireNoNul(robot.cast<std::string>(), "robot");
  else if (!py::isinstance<py::dict>(robot))
    throw py::type_error("robot: a built-in name or a robot file's path (str), or {'mjcf': PATH, ...} (dict)");
  requireNoNul(model, "model");
  std::string text;
  try {
    JsonFromPython tj;
    const nlohmann::ordered_json traj = tj(trajectory, "trajectory");
    text = simulateExperimentText(tj(robot, "robot"), traj, model, tj(sections, ""));
  } catch (const KeywordError& e) {
    throw py::type_error(e.what());
  }

  std::vector<RunResult> runs;
  ExperimentCase c;
  {
    py::gil_scoped_release free;
    Experiment e = loadExperimentText(text, kSimulateLabel);
    resolveRobotModels(e);  // a robot from its model file: stood and derived before the run
    if (e.cases.size() != 1)
      throw ConfigError(std::string(kSimulateLabel) + ": the arguments sweep " + std::to_string(e.cases.size()) +
                        " cases (" + e.swept_keys.front() + ", ...); simulate() runs one case: give single values, "
                        "or loop in Python, or save the experiment and use tailsim.run()");
    c = std::move(e.cases.front());
    runs = runCase(c);
  }
  const RunResult& r = runs.front();
  Simulation s;
  TimeSeries ordered =
      c.kind == CaseKind::kSimulate ? col::inColumnOrder(r.series, modelColumnOrder(col::links(r.series))) : r.series;
  // output.time_series as in a result folder: thin keeps the rows a CSV would (results/thin_series.h),
  // none keeps no rows (the columns stay, empty).
  if (c.kind == CaseKind::kSimulate && c.output.time_series == TimeSeriesOutput::kThin)
    ordered = thinRows(ordered, c.trajectory().breakpoints());
  else if (c.kind == CaseKind::kSimulate && c.output.time_series == TimeSeriesOutput::kNone) {
    TimeSeries empty;
    for (const std::string& name : ordered.names()) empty.addColumn(name);
    ordered = empty;
  }
  s.series = seriesToNumpy(ordered, s.columns);
  s.summary = toPython(summaryJson(r.summary));
  json resolved = resolvedJson(c);
  resolved.erase("source_file");
  s.resolved = toPython(resolved);
  s.model = r.summary.model;
  return s;
}

// tailsim run EXPERIMENT --out DIR [--models ...] [--threads N] [--case NAME] [--fresh] [--no-render]
py::object run(const std::string& experiment, const std::string& out, std::vector<std::string> models, int threads,
               const std::string& case_name, bool fresh, bool render, bool progress) {
  requireNoNul(experiment, "experiment");
  requireNoNul(out, "out");
  requireNoNul(case_name, "case");
  if (out.empty()) throw py::value_error("out: the result folder is empty (give a folder name)");
  checkThreads(threads);  // std::invalid_argument: ValueError
  std::vector<Experiment> suite;
  bool interrupted = false;  // Python's SIGINT handler raised (KeyboardInterrupt is pending)
  {
    py::gil_scoped_release free;
    suite = loadExperimentSuite(experiment);  // all errors before any work
    resolveRobotModels(suite);                 // robots from their model files, before any case runs
    selectModels(suite, models, experiment);  // the CLI's checks and messages (ConfigError)
    requireCase(suite, experiment, case_name);
    RunOptions o;
    o.out_dir = out;
    o.threads = threads;
    o.render = render;
    o.resume = !fresh;
    o.progress = progress;
    o.only_case = case_name;
    // Ctrl-C: Python's handler only sets a flag; run its handlers between cases so a KeyboardInterrupt
    // stops the sweep as the CLI's first Ctrl-C does (finished cases saved).
    o.should_stop = [&interrupted] {
      if (interrupted) return true;
      py::gil_scoped_acquire gil;
      interrupted = PyErr_CheckSignals() != 0;
      return interrupted;
    };
    try {
      runSuite(suite, o);
    } catch (const std::exception&) {
      if (!interrupted) throw;  // else the KeyboardInterrupt is what the caller sees
    }
  }
  if (interrupted) throw py::error_already_set();
  // The summary as the folder holds it (a suite: one per member, by experiment name).
  auto read = [](const fs::path& f) {
    std::ifstream in(f);
    if (!in) throw std::runtime_error(f.string() + ": cannot read the summary");
    return toPython(json::parse(in));
  };
  if (suite.size() == 1) return read(fs::path(out) / "summary.json");
  py::dict all;
  for (const Experiment& e : suite) all[py::str(e.name)] = read(fs::path(out) / e.name / "summary.json");
  return all;
}

py::dict robotDict(const std::string& name_or_path) {
  requireNoNul(name_or_path, "name_or_path");
  const RobotFileData rf = loadRobotFile(name_or_path);
  json j;
  j["quadruped"] = yamlKeys(rf.base.quadruped);
  j["friction"] = yamlKeys(rf.base.friction);
  j["gravity_mps2"] = rf.base.gravity_mps2;
  py::dict d = toPython(j);
  py::dict tails;
  for (const auto& [n, link] : rf.tails) tails[py::int_(n)] = toPython(yamlKeys(link));
  d["tails"] = tails;
  d["file"] = rf.file;
  return d;
}

}  // namespace
}  // namespace tailsim

PYBIND11_MODULE(tailsim, m) {
  using namespace tailsim;
  m.doc() = "tailsim: a quadruped turned by a planar robotic tail (Rone & Ben-Tzvi 2016), analytic and MuJoCo "
            "models. Settings use the YAML keys and units of experiment files (docs/experiment-format.md); "
            "see docs/python.md.";
  m.attr("__version__") = kVersion;
  py::register_exception<ConfigError>(m, "ConfigError", PyExc_ValueError);
  // pybind11 sets up numpy's C API in a function-local static on the first array made. Made first by
  // two pool threads at once, one waits in the static's guard holding nothing while the other imports
  // numpy and waits for the GIL: a deadlock. Do it here, once, while importing the module.
  try {
    py::module_::import("numpy");
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_ImportError)) throw;
    throw py::import_error(
        "tailsim: numpy is missing (tailsim returns time series as numpy arrays): install it, e.g. "
        "apt-get install python3-numpy (scripts/setup.sh installs it); import error: " +
        std::string(e.what()));
  }
  (void)py::array_t<double>(0);

  py::class_<Simulation>(m, "Simulation", "The result of tailsim.simulate(): one model run of one case")
      .def_readonly("series", &Simulation::series, "column name -> 1-D numpy array (the CSV's columns)")
      .def_readonly("columns", &Simulation::columns, "column names in the CSV's order")
      .def_readonly("summary", &Simulation::summary, "the run's summary, as summary.json's runs.<model>")
      .def_readonly("resolved", &Simulation::resolved, "every parameter used, SI units (result.json's resolved)")
      .def_readonly("model", &Simulation::model)
      .def("__getitem__", [](const Simulation& s, const std::string& k) -> py::object {
        if (!s.series.contains(k)) throw py::key_error(k);
        return s.series[py::str(k)];
      })
      .def("__repr__", [](const Simulation& s) {
        const py::object phi = s.summary["phi_net_deg"];
        return "<tailsim.Simulation " + s.model + ": " + std::to_string(py::len(s.columns)) + " columns, " +
               std::to_string(s.series.contains("t_s") ? py::len(s.series["t_s"]) : 0) + " rows, phi_net_deg=" +
               std::string(py::repr(phi)) + ">";
      });

  m.def("simulate", &simulate, py::arg("robot") = "paper", py::arg("trajectory") = py::none(),
        py::arg("model") = "analytic",
        "simulate(robot='paper', trajectory={...}, model='analytic'|'mujoco'|'perfoot', **sections) -> Simulation\n\n"
        "robot: a built-in name, a robot file's path, or a robot from its MuJoCo model file as in an experiment,\n"
        "{'mjcf': PATH, 'stance': {...}, ...} with tail={'mount': {...}, 'links': n} (docs/your-robot.md).\n"
        "One case, no files written. The keywords are the top-level keys of an experiment file (tail, quadruped,\n"
        "friction, gravity_mps2, kind, pose, analytic, perfoot, mujoco, effects, output) with dicts shaped as in\n"
        "YAML, e.g. trajectory={'theta0_deg': 0, 'dtheta_deg': -90, 'dT_s': 0.25, 'w_ss': 0.25}.\n"
        "Raises ConfigError with the loader's message ('<tailsim.simulate>:line:col: key: what is wrong').");
  m.def("run", &run, py::arg("experiment"), py::arg("out"), py::arg("models") = std::vector<std::string>{},
        py::arg("threads") = 0, py::arg("case") = "", py::arg("fresh") = false, py::arg("render") = true,
        py::arg("progress") = false,
        "run(experiment, out, models=[], threads=0, case='', fresh=False, render=True, progress=False) -> dict\n\n"
        "`tailsim run EXPERIMENT --out OUT`: writes the result folder and returns its summary.json as a dict\n"
        "(a suite: {experiment name: summary}). Raises ConfigError for a bad experiment file.");
  m.def("robot", &robotDict, py::arg("name_or_path") = "paper",
        "robot('paper' | 'path/to/robot.yaml') -> dict: the robot file as read and validated (YAML keys and units;\n"
        "tails by link count), plus 'file', the path it was read from");
  m.def("models", &modelNames, "the model names (analytic, perfoot, mujoco)");
}
