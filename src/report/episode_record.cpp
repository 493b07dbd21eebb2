#include "report/episode_record.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include "common/file_io.hpp"
#include "common/gzip.hpp"

namespace comorph::report {
namespace {

// The format is our own and unquoted (text fields are identifiers), so a
// record is split at commas; each field is then converted and checked.
struct Field {
  std::string_view text;
  int column;  // 1-based character position of the field's first character
};

std::vector<Field> split(std::string_view line) {
  std::vector<Field> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    const size_t end = comma == std::string_view::npos ? line.size() : comma;
    out.push_back({line.substr(start, end - start), static_cast<int>(start) + 1});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

class FieldError : public std::runtime_error {
 public:
  FieldError(int column, const std::string& message) : std::runtime_error(message), column(column) {}
  int column;
};

template <typename T>
T parse_number(const Field& f, const char* name) {
  T value{};
  const char* begin = f.text.data();
  const char* end = begin + f.text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (f.text.empty() || ec != std::errc() || ptr != end)
    throw FieldError(f.column, fmt::format("column '{}': '{}' is not a valid {}", name, f.text,
                                           std::is_floating_point_v<T> ? "number" : "integer"));
  if constexpr (std::is_floating_point_v<T>)
    if (!std::isfinite(value))
      throw FieldError(f.column, fmt::format("column '{}': '{}' is not a finite number", name, f.text));
  return value;
}

std::vector<int> parse_configurations(const Field& f) {
  std::vector<int> out;
  if (f.text.empty()) return out;
  size_t start = 0;
  while (true) {
    const size_t sep = f.text.find(';', start);
    const size_t end = sep == std::string_view::npos ? f.text.size() : sep;
    Field part{f.text.substr(start, end - start), f.column + static_cast<int>(start)};
    const int modules = parse_number<int>(part, "configurations");
    if (modules < 1) throw FieldError(part.column, fmt::format("column 'configurations': {} modules is not >= 1", modules));
    out.push_back(modules);
    if (sep == std::string_view::npos) break;
    start = sep + 1;
  }
  return out;
}

void check_text(const std::string& text, const char* name) {
  if (text.find_first_of(",\"\n\r") != std::string::npos)
    throw std::invalid_argument(fmt::format("episode CSV: {} '{}' holds a comma, quote or line break", name, text));
}

}  // namespace

const std::vector<std::string>& episode_csv_columns() {
  static const std::vector<std::string> columns = {
      "episode", "seed", "scenario", "stair_height_m", "obstacles", "success", "termination", "time_s",
      "energy_J", "distance_fraction", "return_R1", "configurations", "modules_total", "action_saturation", "stairs_climbed"};
  return columns;
}

void write_episodes_csv(std::ostream& out, const std::vector<EpisodeRecord>& records) {
  out << fmt::format("{}\n", fmt::join(episode_csv_columns(), ","));
  for (const auto& r : records) {
    check_text(r.scenario, "scenario");
    check_text(r.termination, "termination");
    // fmt's "{}" for a double is the shortest text that reads back exactly.
    out << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.episode, r.seed, r.scenario,
                       r.stair_height_m, r.obstacles, r.success ? 1 : 0, r.termination, r.time_s, r.energy_J,
                       r.distance_fraction, r.return_R1, fmt::join(r.configurations, ";"), r.modules_total,
                       r.action_saturation, r.stairs_climbed ? 1 : 0);
  }
}

void write_episodes_csv(const std::string& path, const std::vector<EpisodeRecord>& records) {
  std::ostringstream out;
  write_episodes_csv(out, records);
  write_file_atomic(path, out.str());
}

std::vector<EpisodeRecord> read_episodes_csv(std::istream& in, const std::string& source) {
  std::string line;
  int line_no = 0;
  auto fail = [&](int column, const std::string& message) {
    return std::runtime_error(fmt::format("{}:{}:{}: {}", source, line_no, column, message));
  };
  if (!std::getline(in, line)) throw std::runtime_error(fmt::format("{}:1:1: empty file, expected a header row", source));
  line_no = 1;
  if (!line.empty() && line.back() == '\r') line.pop_back();

  // Header: the index of every column we need.
  std::map<std::string, size_t> index;
  const auto header = split(line);
  for (size_t i = 0; i < header.size(); ++i) {
    const std::string name(header[i].text);
    if (index.count(name)) throw fail(header[i].column, fmt::format("column '{}' appears twice in the header", name));
    index[name] = i;
  }
  std::vector<size_t> at;
  for (const auto& name : episode_csv_columns()) {
    auto it = index.find(name);
    // Logs written before these columns existed read as 0.
    if (it == index.end() && (name == "action_saturation" || name == "stairs_climbed")) {
      at.push_back(header.size());
      continue;
    }
    if (it == index.end())
      throw fail(1, fmt::format("header lacks column '{}' (expected: {})", name, fmt::join(episode_csv_columns(), ",")));
    at.push_back(it->second);
  }

  std::vector<EpisodeRecord> records;
  std::map<int, int> line_of_episode;  // an episode's row may appear once
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto fields = split(line);
    if (fields.size() != header.size())
      throw fail(fields.back().column, fmt::format("{} fields, the header has {}", fields.size(), header.size()));
    try {
      auto f = [&](int k) -> const Field& { return fields[at[k]]; };
      EpisodeRecord r;
      r.episode = parse_number<int>(f(0), "episode");
      if (const auto [it, fresh] = line_of_episode.emplace(r.episode, line_no); !fresh)
        throw FieldError(f(0).column, fmt::format("episode {} appears twice (also on line {})", r.episode, it->second));
      r.seed = parse_number<std::uint64_t>(f(1), "seed");
      r.scenario = std::string(f(2).text);
      r.stair_height_m = parse_number<double>(f(3), "stair_height_m");
      r.obstacles = parse_number<int>(f(4), "obstacles");
      if (f(5).text != "0" && f(5).text != "1")
        throw FieldError(f(5).column, fmt::format("column 'success': '{}' is not 0 or 1", f(5).text));
      r.success = f(5).text == "1";
      r.termination = std::string(f(6).text);
      if (r.termination.empty()) throw FieldError(f(6).column, "column 'termination' is empty");
      r.time_s = parse_number<double>(f(7), "time_s");
      r.energy_J = parse_number<double>(f(8), "energy_J");
      r.distance_fraction = parse_number<double>(f(9), "distance_fraction");
      r.return_R1 = parse_number<double>(f(10), "return_R1");
      r.configurations = parse_configurations(f(11));
      r.modules_total = parse_number<int>(f(12), "modules_total");
      if (at[13] < fields.size()) r.action_saturation = parse_number<double>(f(13), "action_saturation");
      if (at[14] < fields.size()) r.stairs_climbed = parse_number<int>(f(14), "stairs_climbed") != 0;
      records.push_back(std::move(r));
    } catch (const FieldError& e) {
      throw fail(e.column, e.what());
    }
  }
  return records;
}

std::vector<EpisodeRecord> read_episodes_csv(const std::string& path) {
  if (has_gzip_suffix(path)) {
    // An exported run's log (`comorph export`).
    std::istringstream text(gzip_decompress(read_text_file(path, kMaxRunLogBytes), path, kMaxRunLogBytes));
    return read_episodes_csv(text, path);
  }
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("cannot open episode log {}", path));
  return read_episodes_csv(in, path);
}

}  // namespace comorph::report
