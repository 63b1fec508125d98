#include "experiments/keyword_args.h"

namespace tailsim {

std::string simulateExperimentText(const nlohmann::ordered_json& robot, const nlohmann::ordered_json& trajectory,
                                   const std::string& model, const nlohmann::ordered_json& sections) {
  if (!sections.is_object()) throw KeywordError("tailsim.simulate: the keyword arguments must be a mapping");
  for (const char* k : {"name", "robot", "models"})
    if (sections.contains(k))
      throw KeywordError(std::string("tailsim.simulate: '") + k + "' is not a keyword here" +
                         (std::string(k) == "models" ? " (model='analytic' or 'mujoco': one model a call)" : ""));
  nlohmann::ordered_json doc = nlohmann::ordered_json::object();
  doc["name"] = "simulate";
  doc["robot"] = robot;
  // Appended (an ordered_json object's operator[] searches linearly: O(n^2) for n keywords); the
  // keywords' names are distinct and none is name, robot or models.
  auto& entries = static_cast<nlohmann::ordered_json::object_t::Container&>(doc.get_ref<nlohmann::ordered_json::object_t&>());
  for (const auto& kv : sections.items()) entries.emplace_back(kv.key(), kv.value());
  if (!trajectory.is_null()) doc["trajectory"] = trajectory;
  doc["models"] = nlohmann::ordered_json::array({model});
  return doc.dump(1, ' ', true, nlohmann::ordered_json::error_handler_t::replace);
}

}  // namespace tailsim
