// The named scenarios episodes are drawn in (trainer.scenario, `comorph eval
// --scenario`), declared once: each row says what sets its scene apart.
#pragma once

#include <string>

#include "common/enum_names.hpp"
#include "sim/scene.hpp"  // Variant

namespace comorph::task {

// The value of "default" is `standard` ("default" is a C++ keyword).
enum class Scenario { standard, obstacles7, obstacles8, mixed };

struct ScenarioSpec {
  Scenario value;
  const char* name;      // in configs, on the command line and in eval-<name>.json
  int obstacles;         // K on the flat area; -1 = SceneParams::obstacles
  sim::Variant variant;  // mixed: some of them on the stair treads
};

inline constexpr ScenarioSpec kScenarios[] = {
    {Scenario::standard, "default", -1, sim::Variant::standard},
    {Scenario::obstacles7, "obstacles7", 7, sim::Variant::standard},
    {Scenario::obstacles8, "obstacles8", 8, sim::Variant::standard},
    {Scenario::mixed, "mixed", -1, sim::Variant::mixed},
};
constexpr const auto& enum_names(Scenario) { return kScenarios; }

const ScenarioSpec& scenario_spec(Scenario scenario);
// Throws std::runtime_error "unknown scenario '<name>' (default | obstacles7 | ...)".
const ScenarioSpec& scenario_named(const std::string& name);

}  // namespace comorph::task
