#include "coopt/curriculum.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace comorph::coopt {
namespace {

std::size_t nearest_height(const std::vector<double>& heights, double height_m) {
  std::size_t nearest = 0;
  for (std::size_t i = 1; i < heights.size(); ++i)
    if (std::abs(heights[i] - height_m) < std::abs(heights[nearest] - height_m)) nearest = i;
  return nearest;
}

// The index `weights` gives uniform number u in [0, 1).
std::size_t index_at(const std::vector<double>& weights, double u) {
  double cumulative = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    cumulative += weights[i];
    if (u < cumulative) return i;
  }
  return weights.size() - 1;  // u within rounding of 1
}

}  // namespace

double uniform_from(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

OutcomeWindows::OutcomeWindows(std::size_t keys, int window) : window_(window), outcomes_(keys) {
  if (keys == 0 || window_ < 1) throw std::invalid_argument("OutcomeWindows: no keys or an empty window");
}

void OutcomeWindows::record(std::size_t key, bool success) {
  std::string& o = outcomes_.at(key);
  o.push_back(success ? '1' : '0');
  if (static_cast<int>(o.size()) > window_) o.erase(o.begin());
}

double OutcomeWindows::success_rate(std::size_t key, double if_empty) const {
  const std::string& o = outcomes_.at(key);
  if (o.empty()) return if_empty;
  return static_cast<double>(std::count(o.begin(), o.end(), '1')) / static_cast<double>(o.size());
}

std::string OutcomeWindows::text() const {
  std::string text;
  for (std::size_t i = 0; i < outcomes_.size(); ++i) text += (i > 0 ? "," : "") + outcomes_[i];
  return text;
}

void OutcomeWindows::set_text(const std::string& text, const std::string& option) {
  std::vector<std::string> parts(1);
  for (const char c : text) {
    if (c == ',') {
      parts.emplace_back();
    } else if (c == '0' || c == '1') {
      parts.back().push_back(c);
    } else {
      throw std::runtime_error("curriculum outcomes '" + text + "': only 0, 1 and ',' expected");
    }
  }
  if (parts.size() != outcomes_.size())
    throw std::runtime_error("curriculum outcomes '" + text + "': " + std::to_string(parts.size()) +
                             " kinds of episode, the run has " + std::to_string(outcomes_.size()));
  for (const std::string& p : parts)
    if (static_cast<int>(p.size()) > window_)
      throw std::runtime_error("curriculum outcomes '" + text + "': more than " + option + " (" +
                               std::to_string(window_) + ") of one kind");
  outcomes_ = std::move(parts);
}

StairCurriculum::StairCurriculum(std::vector<double> heights_m, int window)
    : heights_(std::move(heights_m)), outcomes_(heights_.size(), window) {}

void StairCurriculum::record(double height_m, bool success) {
  outcomes_.record(nearest_height(heights_, height_m), success);
}

std::vector<double> StairCurriculum::failure_rates() const {
  std::vector<double> rates;
  for (std::size_t i = 0; i < heights_.size(); ++i) rates.push_back(1.0 - outcomes_.success_rate(i, 0.0));
  return rates;
}

std::vector<double> StairCurriculum::weights(double share) const {
  const std::vector<double> rates = failure_rates();
  double total = 0;
  for (const double r : rates) total += r;
  const double n = static_cast<double>(heights_.size());
  std::vector<double> w;
  for (const double r : rates) w.push_back((1.0 - share) / n + share * (total > 0 ? r / total : 1.0 / n));
  return w;
}

double StairCurriculum::height_at(const std::vector<double>& weights, double u) const {
  return heights_[index_at(weights, u)];
}

double StairCurriculum::draw(const std::vector<double>& weights, std::uint64_t seed) const {
  return height_at(weights, uniform_from(seed));
}

ChainCurriculum::ChainCurriculum(std::vector<double> heights_m, int min_modules, int max_modules, int window)
    : heights_(std::move(heights_m)), min_modules_(min_modules), chains_(max_modules - min_modules + 1),
      outcomes_(heights_.size() * static_cast<std::size_t>(std::max(chains_, 0)), window) {}

void ChainCurriculum::record(double height_m, int modules, bool climbed) {
  if (modules < min_modules_ || modules >= min_modules_ + chains_)
    throw std::invalid_argument("ChainCurriculum: a chain of " + std::to_string(modules) + " modules");
  outcomes_.record(nearest_height(heights_, height_m) * static_cast<std::size_t>(chains_) +
                       static_cast<std::size_t>(modules - min_modules_),
                   climbed);
}

std::vector<double> ChainCurriculum::climb_rates() const {
  std::vector<double> rates;
  for (std::size_t i = 0; i < pairs(); ++i) rates.push_back(outcomes_.success_rate(i, -1.0));
  return rates;
}

std::vector<double> ChainCurriculum::weights() const {
  std::vector<double> w;
  double total = 0;
  for (const double rate : climb_rates()) {
    const double p = rate < 0 ? 0.5 : rate;
    w.push_back(std::max(p * (1.0 - p), kFloor));
    total += w.back();
  }
  for (double& x : w) x /= total;
  return w;
}

ChainCurriculum::Pair ChainCurriculum::pair_at(const std::vector<double>& weights, double u) const {
  const std::size_t i = index_at(weights, u);
  const auto chains = static_cast<std::size_t>(chains_);
  return {heights_[i / chains], min_modules_ + static_cast<int>(i % chains)};
}

ChainCurriculum::Pair ChainCurriculum::draw(const std::vector<double>& weights, std::uint64_t seed) const {
  return pair_at(weights, uniform_from(seed));
}

}  // namespace comorph::coopt
