// The experiment format described from the settings declarations (settings/fields.h): a JSON
// Schema (`tailsim schema`, `tailsim schema --robot`) and the key tables of
// docs/experiment-format.md (`tailsim schema --markdown`, checked by CTest docs_keys_current).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace tailsim {

// Every file kind `tailsim` reads besides robot files (oneOf): experiment files (kind simulate or
// pose; any single value may be a sweep, {sweep: [...]} / {range: [a, b, step]}), suite files, and
// the design files of `tailsim optimize` (kind: optimize) and `tailsim maneuver` (kind: maneuver).
nlohmann::json experimentSchema();
// Robot files (configs/robots/*.yaml).
nlohmann::json robotSchema();
// The generated key tables, Markdown.
std::string settingsMarkdown();

}  // namespace tailsim
