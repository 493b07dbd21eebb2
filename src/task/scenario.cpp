#include "task/scenario.hpp"

#include <stdexcept>

#include "common/file_io.hpp"  // quote_value

namespace comorph::task {

const ScenarioSpec& scenario_spec(Scenario scenario) {
  for (const ScenarioSpec& s : kScenarios)
    if (s.value == scenario) return s;
  throw std::logic_error("scenario_spec: a Scenario without a row in kScenarios");
}

const ScenarioSpec& scenario_named(const std::string& name) {
  Scenario s{};
  if (!enum_from_name(name, s))
    throw std::runtime_error("unknown scenario '" + quote_value(name) + "' (" + enum_name_list<Scenario>() + ")");
  return scenario_spec(s);
}

}  // namespace comorph::task
