#include "rl/replay_segments.hpp"

#include <torch/torch.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "common/checksum.hpp"
#include "common/file_io.hpp"
#include "common/torch_archive.hpp"
#include "common/yaml_fields.hpp"

namespace comorph::rl {
namespace fs = std::filesystem;

std::string replay_index_name(const std::string& name) { return name + "-replay.yaml"; }

namespace {

// Named by the global index of its first transition, zero-padded so that the
// files sort in order.
std::string segment_name(const std::string& name, std::int64_t first) {
  char digits[32];
  std::snprintf(digits, sizeof(digits), "%012lld", static_cast<long long>(first));
  return name + "-replay-" + digits + ".pt";
}

void write_index(const std::string& path, const ReplaySegments& s) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "capacity" << YAML::Value << s.capacity;
  e << YAML::Key << "added" << YAML::Value << s.added;
  e << YAML::Key << "segments" << YAML::Value << YAML::BeginSeq;
  for (const ReplaySegment& g : s.segments) {
    e << YAML::BeginMap;
    e << YAML::Key << "file" << YAML::Value << g.file;
    e << YAML::Key << "first" << YAML::Value << g.first;
    e << YAML::Key << "count" << YAML::Value << g.count;
    e << YAML::Key << "checksum" << YAML::Value << g.checksum;
    e << YAML::EndMap;
  }
  e << YAML::EndSeq << YAML::EndMap;
  write_file_atomic(path, std::string(e.c_str()) + "\n");
}

}  // namespace

ReplaySegments write_replay_segments(const ReplayBuffer& buffer, const std::string& name, const std::string& dir,
                                     const ReplaySegments& previous, std::vector<std::string>& files,
                                     std::map<std::string, std::string>& sums) {
  ReplaySegments next;
  next.directory = dir;
  next.capacity = buffer.capacity();
  next.added = buffer.added();
  const std::int64_t held_from = buffer.added() - buffer.size();
  // The previous segments are of this buffer's history only if it has not
  // gone back since (a resume always starts from the state they describe).
  // If one of their files has gone (a checkpoint directory removed by hand),
  // the whole buffer is written again rather than the checkpoint failing.
  bool continues = !previous.directory.empty() && previous.capacity == buffer.capacity() &&
                   previous.added <= buffer.added();
  for (const ReplaySegment& g : previous.segments)
    continues = continues && fs::is_regular_file(fs::path(previous.directory) / g.file);
  std::int64_t new_from = held_from;
  if (continues) {
    for (const ReplaySegment& g : previous.segments) {
      if (g.first + g.count <= held_from) continue;  // every transition in it was overwritten
      const fs::path from = fs::path(previous.directory) / g.file, to = fs::path(dir) / g.file;
      std::error_code linked;
      fs::create_hard_link(from, to, linked);
      if (linked) fs::copy_file(from, to);  // no hard links on this file system: the bytes again
      next.segments.push_back(g);
    }
    new_from = std::max(held_from, previous.added);
  }
  if (next.added > new_from) {
    ReplaySegment g;
    g.file = segment_name(name, new_from);
    g.first = new_from;
    g.count = next.added - new_from;
    const std::string path = (fs::path(dir) / g.file).string();
    torch::serialize::OutputArchive a;
    buffer.save_segment(a, g.first, g.count);
    save_archive(a, path);
    g.checksum = file_checksum(path);
    next.segments.push_back(g);
  }
  for (const ReplaySegment& g : next.segments) {
    files.push_back(g.file);
    sums[g.file] = g.checksum;
  }
  write_index((fs::path(dir) / replay_index_name(name)).string(), next);
  files.push_back(replay_index_name(name));
  return next;
}

ReplaySegments read_replay_segments(ReplayBuffer& buffer, const std::string& name, const std::string& dir) {
  ReplaySegments s;
  const std::string index = (fs::path(dir) / replay_index_name(name)).string();
  if (!fs::exists(index)) throw std::runtime_error(index + ": missing (the checkpoint is incomplete)");
  try {
    const YAML::Node n = load_yaml_file(index);
    s.capacity = n["capacity"].as<std::int64_t>();
    s.added = n["added"].as<std::int64_t>();
    for (const YAML::Node& g : n["segments"]) {
      ReplaySegment segment;
      segment.file = g["file"].as<std::string>();
      segment.first = g["first"].as<std::int64_t>();
      segment.count = g["count"].as<std::int64_t>();
      segment.checksum = g["checksum"].as<std::string>();
      s.segments.push_back(segment);
    }
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(index + ": unreadable replay index: " + e.msg);
  }
  if (s.capacity != buffer.capacity())
    throw std::runtime_error(index + ": capacity " + std::to_string(s.capacity) + ", the replay buffer's is " +
                             std::to_string(buffer.capacity()));
  // The segments must follow each other without a gap, from at or before
  // the oldest transition still held up to the last one added.
  const std::int64_t held_from = s.added - std::min(s.added, s.capacity);
  std::int64_t covered = s.segments.empty() ? s.added : s.segments.front().first;
  if (covered > held_from || s.added < 0)
    throw std::runtime_error(index + ": transitions [" + std::to_string(held_from) + ", " +
                             std::to_string(covered) + ") are in no segment");
  for (const ReplaySegment& g : s.segments) {
    if (g.first != covered || g.count <= 0)
      throw std::runtime_error(index + ": segment " + g.file + " holds [" + std::to_string(g.first) + ", " +
                               std::to_string(g.first + g.count) + "), expected one from " + std::to_string(covered));
    covered += g.count;
  }
  if (covered != s.added)
    throw std::runtime_error(index + ": the segments end at transition " + std::to_string(covered) +
                             ", the index counts " + std::to_string(s.added));
  buffer.begin_segments(s.added);
  for (const ReplaySegment& g : s.segments) {
    const std::string path = (fs::path(dir) / g.file).string();
    try {
      torch::serialize::InputArchive a;
      a.load_from(path);
      buffer.load_segment(a, g.first, g.count);
    } catch (const c10::Error& e) {
      const std::string what = e.what_without_backtrace();
      throw std::runtime_error(path + ": cannot load: " + quote_value(what.substr(0, what.find('\n')), 200));
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
  }
  s.directory = dir;
  return s;
}

}  // namespace comorph::rl
