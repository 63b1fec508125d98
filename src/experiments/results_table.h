// DIR/results.csv: one row per case and model of one or more experiments (docs/ARCHITECTURE.md
// "Result folder"), built from their summary.json objects, so a resumed run rebuilds it whole.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace tailsim {

// Columns: experiment, case, model; every swept key of any of the experiments (dotted, as in
// swept_keys, value as written: numbers stay numbers); phi_net_deg, t_stop_s, stick_slip_events,
// solver_steps, wall_time_s, ok, error, at_rest, warnings ("; "-joined); then every model-specific
// extra figure, sorted by name. Empty: null (a failed run's phi_net_deg and at_rest, a non-finite
// extra) or absent (a key another experiment sweeps, an extra another model writes). Numbers as
// summary.json writes them (shortest text that reads back to the same double), booleans
// true/false, RFC 4180 quoting. `summaries`: summary.json objects ({"experiment", "swept_keys",
// "cases": [{"name", "sweep", "runs"}]}).
std::string resultsCsv(const std::vector<nlohmann::json>& summaries);

// The same from each experiment's name, swept keys and a function that calls its argument with
// each case entry in turn (summary.json's "cases" items): a sweep of 10^5 cases need not hold
// them all parsed. The entries are read twice (the columns, then the rows) unless extra_names is given.
struct ResultsCsvInput {
  nlohmann::json experiment;  // the experiment's name
  nlohmann::json swept_keys;  // array of dotted keys
  std::function<void(const std::function<void(const nlohmann::json&)>&)> for_each_case;
  // The names of every run's extra figures, when the caller has them: the cases are then read
  // once (the rows) instead of twice.
  const std::set<std::string>* extra_names = nullptr;
};
std::string resultsCsv(const std::vector<ResultsCsvInput>& experiments);

}  // namespace tailsim
