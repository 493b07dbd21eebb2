// The list of a run's settings for people: `comorph config keys` prints it,
// docs/config.md is its Markdown form (a test keeps the page in step).
#pragma once

#include <string>

#include "coopt/config.hpp"

namespace comorph::coopt {

// Every key of every section with its default, type and range, and meaning.
// With a preset: its value beside the default, "*" marking each that differs.
std::string config_keys_text(const CooptConfig* preset = nullptr);
// docs/config.md: the same as Markdown tables, under a page header.
std::string config_reference_markdown();

}  // namespace comorph::coopt
