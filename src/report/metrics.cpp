#include "report/metrics.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/file_io.hpp"

namespace comorph::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json number_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

double read_number_or_null(const nlohmann::json& j, const std::string& key, const std::string& where) {
  if (j.is_null()) return kNaN;
  if (!j.is_number()) throw std::runtime_error(fmt::format("{}: key '{}' is not a number or null", where, key));
  return j.get<double>();
}

// A stair-height key: a number of metres (stair_key's text).
bool is_stair_key(const std::string& key) {
  double value = 0;
  const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), value);
  return ec == std::errc() && end == key.data() + key.size() && value >= 0;
}

const nlohmann::json& need(const nlohmann::json& j, const std::string& key, const std::string& where) {
  auto it = j.find(key);
  if (it == j.end()) throw std::runtime_error(fmt::format("{}: missing key '{}'", where, key));
  return *it;
}

}  // namespace

double objective_F(const EpisodeRecord& e, const task::ObjectiveWeights& w) {
  return task::objective(w, e.time_s, e.energy_J, e.distance_fraction);
}

std::string stair_key(double stair_height_m) { return fmt::format("{}", stair_height_m); }

std::vector<std::string> stair_keys(const EvalSummary& summary) {
  std::vector<std::pair<double, std::string>> heights;
  for (const auto& [key, rate] : summary.success_rate)
    if (key != "avg") heights.emplace_back(std::stod(key), key);
  std::sort(heights.begin(), heights.end());
  std::vector<std::string> keys;
  for (const auto& [height, key] : heights) keys.push_back(key);
  return keys;
}

EvalSummary summarize(const std::vector<EpisodeRecord>& records, const task::ObjectiveWeights& weights,
                      const std::vector<double>& stair_heights) {
  EvalSummary m;
  m.episodes = static_cast<int>(records.size());
  std::map<std::string, std::pair<int, int>> per_height;  // key -> (successes, episodes)
  std::map<std::string, std::pair<double, int>> first;    // key -> (sum of first modules, episodes with a choice)
  for (const double h : stair_heights) {
    per_height[stair_key(h)] = {0, 0};
    first[stair_key(h)] = {0.0, 0};
  }
  double time_sum = 0, energy_sum = 0, F_sum = 0;
  int successes = 0, climbed = 0, shed = 0;
  for (const auto& r : records) {
    const std::string key = stair_key(r.stair_height_m);
    auto& [wins, count] = per_height[key];
    ++count;
    if (r.success) {
      ++wins;
      ++successes;
      time_sum += r.time_s;
      energy_sum += r.energy_J;
    }
    F_sum += objective_F(r, weights);
    ++m.configurations[key][configuration_sequence(r.configurations)];
    ++m.terminations[r.termination];
    first[key];  // a height seen has a first_modules entry, NaN without choices
    if (!r.configurations.empty()) {
      first[key].first += r.configurations.front();
      ++first[key].second;
    }
    if (r.stairs_climbed && !r.configurations.empty()) {
      ++climbed;
      shed += r.configurations.back() <= 3;
    }
  }
  for (const auto& [key, sc] : first) m.first_modules[key] = sc.second > 0 ? sc.first / sc.second : kNaN;
  m.shed_after_stairs = climbed > 0 ? static_cast<double>(shed) / climbed : kNaN;
  double rate_sum = 0;
  int heights = 0;
  for (const auto& [key, wc] : per_height) {
    const auto [wins, count] = wc;
    m.success_rate[key] = count > 0 ? static_cast<double>(wins) / count : kNaN;
    if (count > 0) {
      rate_sum += m.success_rate[key];
      ++heights;
    }
  }
  m.success_rate["avg"] = heights > 0 ? rate_sum / heights : kNaN;
  m.time_s = successes > 0 ? time_sum / successes : kNaN;
  m.energy_J = successes > 0 ? energy_sum / successes : kNaN;
  m.F = m.episodes > 0 ? F_sum / m.episodes : kNaN;
  return m;
}

nlohmann::json to_json(const EvalSummary& m) {
  nlohmann::json j;
  j["success_rate"] = nlohmann::json::object();
  for (const auto& [k, v] : m.success_rate) j["success_rate"][k] = number_or_null(v);
  j["time_s"] = number_or_null(m.time_s);
  j["energy_J"] = number_or_null(m.energy_J);
  j["F"] = number_or_null(m.F);
  j["configurations"] = nlohmann::json::object();
  for (const auto& [height, counts] : m.configurations) j["configurations"][height] = counts;
  j["terminations"] = m.terminations;
  j["episodes"] = m.episodes;
  j["first_modules"] = nlohmann::json::object();
  for (const auto& [k, v] : m.first_modules) j["first_modules"][k] = number_or_null(v);
  j["shed_after_stairs"] = number_or_null(m.shed_after_stairs);
  return j;
}

EvalSummary metrics_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw std::runtime_error(fmt::format("{}: not a JSON object", where));
  EvalSummary m;
  const auto& rates = need(j, "success_rate", where);
  if (!rates.is_object()) throw std::runtime_error(fmt::format("{}: key 'success_rate' is not an object", where));
  need(rates, "avg", where + " success_rate");
  for (auto it = rates.begin(); it != rates.end(); ++it) {
    if (it.key() != "avg" && !is_stair_key(it.key()))
      throw std::runtime_error(fmt::format("{}: key 'success_rate.{}' is not a stair height (m) or avg", where, it.key()));
    m.success_rate[it.key()] = read_number_or_null(it.value(), "success_rate." + it.key(), where);
  }
  m.time_s = read_number_or_null(need(j, "time_s", where), "time_s", where);
  m.energy_J = read_number_or_null(need(j, "energy_J", where), "energy_J", where);
  m.F = read_number_or_null(need(j, "F", where), "F", where);
  try {
    m.configurations = need(j, "configurations", where).get<std::map<std::string, std::map<std::string, int>>>();
    m.terminations = need(j, "terminations", where).get<std::map<std::string, int>>();
    m.episodes = need(j, "episodes", where).get<int>();
    m.shed_after_stairs = kNaN;
    if (j.contains("first_modules") && j["first_modules"].is_object())
      for (auto it = j["first_modules"].begin(); it != j["first_modules"].end(); ++it)
        m.first_modules[it.key()] = read_number_or_null(it.value(), "first_modules." + it.key(), where);
    if (j.contains("shed_after_stairs"))
      m.shed_after_stairs = read_number_or_null(j["shed_after_stairs"], "shed_after_stairs", where);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(fmt::format("{}: configurations, terminations or episodes malformed: {}", where, e.what()));
  }
  return m;
}

void write_metrics_json(const std::string& path, const EvalSummary& metrics) {
  write_file_atomic(path, to_json(metrics).dump(2) + "\n");
}

EvalSummary read_metrics_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("cannot open {}", path));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(fmt::format("{}: invalid JSON: {}", path, e.what()));
  }
  return metrics_from_json(j, path);
}

}  // namespace comorph::report
