// Strict checks of numbers on the command line: a value that is not a whole
// base-10 number (for counts and seeds), not finite (nan, inf), or out of the
// option's range is an error naming the option (CLI11 prefixes the name),
// never a silent fallback or a wrapped-around unsigned value
// (CLI11 2.1 reads "-1" into a uint64 option as 2^64-1 and lets nan pass a
// CLI::Range). Use: opt->check(comorph::cli::whole_in(0, 2000000000)).
#pragma once

#include <CLI/CLI.hpp>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

#include "common/file_io.hpp"  // quote_value

namespace comorph::cli {

inline CLI::Validator whole_in(long long lo, long long hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& input) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long long v = std::strtoll(input.c_str(), &end, 10);
        if (input.empty() || end != input.c_str() + input.size() || errno == ERANGE || v < lo || v > hi)
          return "expected a whole number in " + range + ", got '" + quote_value(input) + "'";
        return "";
      },
      "INT in " + range);
}

inline CLI::Validator finite_in(double lo, double hi) {
  const std::string range = "[" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& input) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(input.c_str(), &end);
        if (input.empty() || end != input.c_str() + input.size() || !std::isfinite(v) || v < lo || v > hi)
          return "expected a finite number in " + range + ", got '" + quote_value(input) + "'";
        return "";
      },
      "NUMBER in " + range);
}

}  // namespace comorph::cli
