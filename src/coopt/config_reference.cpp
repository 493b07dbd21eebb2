#include "coopt/config_reference.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace comorph::coopt {
namespace {

std::string type_and_range(const Setting& s) {
  return s.range.empty() ? s.type : s.type + " in " + s.range;
}

// A Markdown table cell: a '|' would end it.
std::string cell(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

}  // namespace

std::string config_keys_text(const CooptConfig* preset) {
  const auto defaults = settings_sections(default_coopt_config());
  const auto values = preset ? settings_sections(*preset) : defaults;
  std::string out;
  for (std::size_t i = 0; i < defaults.size(); ++i) {
    const SettingsSection& section = defaults[i];
    out += fmt::format("{}: {}\n", section.name, section.about);
    std::size_t key_width = 0, value_width = 0, default_width = 0, type_width = 0;
    for (std::size_t k = 0; k < section.settings.size(); ++k) {
      key_width = std::max(key_width, section.settings[k].key.size());
      value_width = std::max(value_width, values[i].settings[k].value.size());
      default_width = std::max(default_width, section.settings[k].value.size());
      type_width = std::max(type_width, type_and_range(section.settings[k]).size());
    }
    for (std::size_t k = 0; k < section.settings.size(); ++k) {
      const Setting& d = section.settings[k];
      const std::string& value = values[i].settings[k].value;
      if (preset)
        out += fmt::format("{} {:<{}}  {:<{}}  default {:<{}}  {:<{}}  {}\n", value != d.value ? '*' : ' ', d.key,
                           key_width, value, value_width, d.value, default_width, type_and_range(d), type_width,
                           d.meaning);
      else
        out += fmt::format("  {:<{}}  {:<{}}  {:<{}}  {}\n", d.key, key_width, d.value, default_width,
                           type_and_range(d), type_width, d.meaning);
    }
    out += "\n";
  }
  if (preset) out += "* = the preset's value differs from the default\n";
  return out;
}

std::string config_reference_markdown() {
  std::string out =
      "# Settings\n"
      "\n"
      "Every setting a run's config file can hold: its key, default, type and\n"
      "range, and meaning. A config file (configs/*.yaml) sets some of them,\n"
      "`--set key=value` others; a run's config.yaml holds all of them, resolved.\n"
      "`comorph config keys --preset FILE` shows what a preset sets and which\n"
      "values differ from the default. A preset can build on another with\n"
      "`base: other.yaml` and list only what it changes.\n"
      "\n"
      "The defaults of `env:` are the files of configs/sim/; those of the other\n"
      "sections are in the code. This page is generated from the declarations\n"
      "the config reader uses (a test fails when it is out of date):\n"
      "`build/apps/comorph config keys --markdown > docs/config.md`.\n";
  for (const SettingsSection& section : settings_sections(default_coopt_config())) {
    out += fmt::format("\n## {}\n\n{}\n\n| key | default | type | meaning |\n|---|---|---|---|\n", section.name,
                       section.about);
    for (const Setting& s : section.settings)
      out += fmt::format("| `{}` | `{}` | {} | {} |\n", s.key, cell(s.value), cell(type_and_range(s)), cell(s.meaning));
  }
  return out;
}

}  // namespace comorph::coopt
