#include "experiments/results_table.h"

#include <algorithm>
#include <set>

namespace tailsim {
using json = nlohmann::json;

namespace {

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

// A JSON value as a CSV cell: null empty, strings as they are, numbers and booleans as JSON text.
std::string cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s;
    for (const json& x : v) s += (s.empty() ? "" : "; ") + cell(x);
    return s;
  }
  return v.dump();
}

const json& field(const json& o, const char* key) {
  static const json kNull;
  if (!o.is_object()) return kNull;
  const auto it = o.find(key);
  return it == o.end() ? kNull : *it;
}

}  // namespace

std::string resultsCsv(const std::vector<ResultsCsvInput>& experiments) {
  static const char* const kSummaryFields[] = {"phi_net_deg", "t_stop_s", "stick_slip_events", "solver_steps",
                                               "wall_time_s", "ok",       "error",             "at_rest",
                                               "warnings"};
  std::vector<std::string> swept;
  std::set<std::string> extras;
  for (const ResultsCsvInput& s : experiments) {
    for (const json& k : s.swept_keys)
      if (k.is_string() && std::find(swept.begin(), swept.end(), k.get<std::string>()) == swept.end())
        swept.push_back(k.get<std::string>());
    if (s.extra_names) {
      extras.insert(s.extra_names->begin(), s.extra_names->end());
      continue;
    }
    s.for_each_case([&](const json& c) {
      for (const auto& [model, run] : field(c, "runs").items())
        for (const auto& [name, v] : field(run, "extra").items()) extras.insert(name);
    });
  }
  std::string out = "experiment,case,model";
  for (const std::string& k : swept) out += "," + csvField(k);
  for (const char* f : kSummaryFields) out += std::string(",") + f;
  out += ",verdict";  // the case's verdict across its models (experiments/verdict.h), on each of its rows
  for (const std::string& x : extras) out += "," + csvField(x);
  out += "\n";
  for (const ResultsCsvInput& s : experiments)
    s.for_each_case([&](const json& c) {
      for (const auto& [model, run] : field(c, "runs").items()) {
        out += csvField(cell(s.experiment)) + "," + csvField(cell(field(c, "name"))) + "," + csvField(model);
        for (const std::string& k : swept) out += "," + csvField(cell(field(field(c, "sweep"), k.c_str())));
        for (const char* f : kSummaryFields) out += "," + csvField(cell(field(run, f)));
        out += "," + csvField(cell(field(c, "verdict")));
        for (const std::string& x : extras) out += "," + csvField(cell(field(field(run, "extra"), x.c_str())));
        out += "\n";
      }
    });
  return out;
}

std::string resultsCsv(const std::vector<json>& summaries) {
  std::vector<ResultsCsvInput> in;
  for (const json& s : summaries) {
    const json& swept = field(s, "swept_keys");
    in.push_back({field(s, "experiment"), swept.is_array() ? swept : json::array(),
                  [&s](const std::function<void(const json&)>& f) {
                    const json& cases = field(s, "cases");
                    if (cases.is_array())
                      for (const json& c : cases) f(c);
                  }});
  }
  return resultsCsv(in);
}

}  // namespace tailsim
