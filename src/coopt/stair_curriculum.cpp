#include "coopt/stair_curriculum.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

namespace comorph::coopt {

StairCurriculum::StairCurriculum(std::vector<double> heights_m, int window)
    : heights_(std::move(heights_m)), window_(window), outcomes_(heights_.size()) {
  if (heights_.empty() || window_ < 1) throw std::invalid_argument("StairCurriculum: no heights or an empty window");
}

void StairCurriculum::record(double height_m, bool success) {
  std::size_t nearest = 0;
  for (std::size_t i = 1; i < heights_.size(); ++i)
    if (std::abs(heights_[i] - height_m) < std::abs(heights_[nearest] - height_m)) nearest = i;
  std::string& o = outcomes_[nearest];
  o.push_back(success ? '1' : '0');
  if (static_cast<int>(o.size()) > window_) o.erase(o.begin());
}

std::vector<double> StairCurriculum::failure_rates() const {
  std::vector<double> rates;
  for (const std::string& o : outcomes_) {
    if (o.empty()) {
      rates.push_back(1.0);
      continue;
    }
    int failures = 0;
    for (const char c : o) failures += c == '0';
    rates.push_back(static_cast<double>(failures) / static_cast<double>(o.size()));
  }
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
  double cumulative = 0;
  for (std::size_t i = 0; i < heights_.size(); ++i) {
    cumulative += weights[i];
    if (u < cumulative) return heights_[i];
  }
  return heights_.back();  // u within rounding of 1
}

double StairCurriculum::draw(const std::vector<double>& weights, std::uint64_t seed) const {
  std::mt19937_64 rng(seed);
  return height_at(weights, std::uniform_real_distribution<double>(0.0, 1.0)(rng));
}

std::string StairCurriculum::outcomes_text() const {
  std::string text;
  for (std::size_t i = 0; i < outcomes_.size(); ++i) text += (i > 0 ? "," : "") + outcomes_[i];
  return text;
}

void StairCurriculum::set_outcomes_text(const std::string& text) {
  std::vector<std::string> parts(1);
  for (const char c : text) {
    if (c == ',') {
      parts.emplace_back();
    } else if (c == '0' || c == '1') {
      parts.back().push_back(c);
    } else {
      throw std::runtime_error("stair curriculum outcomes '" + text + "': only 0, 1 and ',' expected");
    }
  }
  if (parts.size() != heights_.size())
    throw std::runtime_error("stair curriculum outcomes '" + text + "': " + std::to_string(parts.size()) +
                             " heights, the run has " + std::to_string(heights_.size()));
  for (const std::string& p : parts)
    if (static_cast<int>(p.size()) > window_)
      throw std::runtime_error("stair curriculum outcomes '" + text + "': more than trainer.stair_curriculum_window (" +
                               std::to_string(window_) + ") at one height");
  outcomes_ = std::move(parts);
}

}  // namespace comorph::coopt
