// Replay buffers in checkpoints as segments (rl/replay_segments.hpp): each
// checkpoint writes only the transitions added since the previous one, links
// the previous segments that still hold transitions, drops the overwritten
// ones, and reading them back gives the buffer slot for slot.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "rl/replay_buffer.hpp"
#include "rl/replay_segments.hpp"
#include "support/test_support.hpp"

namespace rl = comorph::rl;
namespace fs = std::filesystem;

namespace {

const rl::ObservationSpec kSpec{1, 2, 2, 3};  // a 2x2 image and 3 floats
constexpr std::int64_t kCapacity = 5;

rl::ReplayBuffer make_buffer() { return rl::ReplayBuffer(kSpec, {rl::ActionKind::kContinuous, 2}, kCapacity); }

// Transition i: every field a function of i (targets on every other one).
void add(rl::ReplayBuffer& buffer, int i) {
  rl::Observation o, n;
  rl::allocate(kSpec, o);
  rl::allocate(kSpec, n);
  for (int k = 0; k < 4; ++k) o.image[k] = static_cast<float>((i * 4 + k) % 256) / 255.0f;
  for (int k = 0; k < 3; ++k) o.vector[k] = static_cast<float>(i * 10 + k), n.vector[k] = -o.vector[k];
  rl::Action a;
  a.continuous = {0.01f * i, -0.01f * i};
  if (i % 2 == 0) a.target = {0.5f, static_cast<float>(i)};
  buffer.add(o, a, static_cast<float>(i), n, i % 3 == 0, 0.99f);
}

// Transitions [from, to) added.
void add(rl::ReplayBuffer& buffer, int from, int to) {
  for (int i = from; i < to; ++i) add(buffer, i);
}

// Every slot and every count of two buffers agree.
void expect_same(const rl::ReplayBuffer& a, const rl::ReplayBuffer& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.next_slot(), b.next_slot());
  EXPECT_EQ(a.added(), b.added());
  const torch::Tensor slots = torch::arange(a.size());
  const rl::ReplayBatch x = a.gather(slots, torch::kCPU), y = b.gather(slots, torch::kCPU);
  EXPECT_TRUE(torch::equal(x.image, y.image));
  EXPECT_TRUE(torch::equal(x.next_image, y.next_image));
  EXPECT_TRUE(torch::equal(x.vector, y.vector));
  EXPECT_TRUE(torch::equal(x.next_vector, y.next_vector));
  EXPECT_TRUE(torch::equal(x.action, y.action));
  EXPECT_TRUE(torch::equal(x.reward, y.reward));
  EXPECT_TRUE(torch::equal(x.bootstrap, y.bootstrap));
  EXPECT_TRUE(torch::equal(x.target, y.target));
  EXPECT_TRUE(torch::equal(x.has_target, y.has_target));
}

// Reading `dir` back into a fresh buffer gives `buffer` slot for slot.
void expect_reads_back(const rl::ReplayBuffer& buffer, const std::string& dir) {
  rl::ReplayBuffer restored = make_buffer();
  rl::read_replay_segments(restored, "motion", dir);
  expect_same(buffer, restored);
}

// `s` is one segment of transitions [first, first + count).
void expect_one_segment(const rl::ReplaySegments& s, std::int64_t first, std::int64_t count) {
  ASSERT_EQ(s.segments.size(), 1u);
  EXPECT_EQ(s.segments[0].first, first);
  EXPECT_EQ(s.segments[0].count, count);
}

// One checkpoint of `buffer` into a fresh directory `dir`.
rl::ReplaySegments checkpoint(const rl::ReplayBuffer& buffer, const std::string& dir,
                              const rl::ReplaySegments& previous, std::vector<std::string>& files) {
  fs::create_directories(dir);
  std::map<std::string, std::string> sums;
  return rl::write_replay_segments(buffer, "motion", dir, previous, files, sums);
}

}  // namespace

TEST(ReplaySegments, EachCheckpointWritesTheNewTransitionsAndReadsBackSlotForSlot) {
  const std::string root = comorph::test_support::fresh_temp_dir("rl_segments");
  rl::ReplayBuffer buffer = make_buffer();
  add(buffer, 0, 3);
  std::vector<std::string> files;
  const rl::ReplaySegments first = checkpoint(buffer, root + "/a", {}, files);
  expect_one_segment(first, 0, 3);
  EXPECT_EQ(files, (std::vector<std::string>{"motion-replay-000000000000.pt", "motion-replay.yaml"}));

  // 4 more (7 added, slots hold 2..6): the first segment still holds 2, so it
  // is linked, not written again; the new one holds 3..6.
  add(buffer, 3, 7);
  files.clear();
  const rl::ReplaySegments second = checkpoint(buffer, root + "/b", first, files);
  ASSERT_EQ(second.segments.size(), 2u);
  EXPECT_EQ(second.segments[1].first, 3);
  EXPECT_EQ(second.segments[1].count, 4);
  EXPECT_TRUE(fs::equivalent(root + "/a/motion-replay-000000000000.pt", root + "/b/motion-replay-000000000000.pt"));
  EXPECT_EQ(fs::hard_link_count(root + "/b/motion-replay-000000000000.pt"), 2u);
  // Removing the older checkpoint takes nothing from the newer one.
  fs::remove_all(root + "/a");
  rl::ReplayBuffer restored = make_buffer();
  const rl::ReplaySegments read = rl::read_replay_segments(restored, "motion", root + "/b");
  EXPECT_EQ(read.added, 7);
  expect_same(buffer, restored);

  // 6 more (13 added, slots hold 8..12): both old segments are overwritten
  // and dropped; the new segment starts at 8, not at 7.
  add(buffer, 7, 13);
  files.clear();
  const rl::ReplaySegments third = checkpoint(buffer, root + "/c", read, files);
  expect_one_segment(third, 8, 5);
  expect_reads_back(buffer, root + "/c");
  // Nothing new: no new segment, the same index.
  files.clear();
  const rl::ReplaySegments fourth = checkpoint(buffer, root + "/d", third, files);
  ASSERT_EQ(fourth.segments.size(), 1u);
  EXPECT_EQ(fourth.segments[0].file, third.segments[0].file);
  // The previous checkpoint's files gone: the whole buffer is written again.
  add(buffer, 13, 15);
  fs::remove_all(root + "/d");
  files.clear();
  const rl::ReplaySegments fifth = checkpoint(buffer, root + "/e", fourth, files);
  expect_one_segment(fifth, 10, 5);
  expect_reads_back(buffer, root + "/e");
  fs::remove_all(root);
}

TEST(ReplaySegments, AnIndexWithAGapOrAnotherCapacityIsRefusedNamingTheFile) {
  const std::string root = comorph::test_support::fresh_temp_dir("rl_segments_bad");
  rl::ReplayBuffer buffer = make_buffer();
  add(buffer, 0, 4);
  std::vector<std::string> files;
  const rl::ReplaySegments first = checkpoint(buffer, root + "/a", {}, files);
  add(buffer, 4, 5);
  const rl::ReplaySegments second = checkpoint(buffer, root + "/b", first, files);
  ASSERT_EQ(second.segments.size(), 2u);
  const std::string index = root + "/b/motion-replay.yaml";

  // A segment left out of the index: the transitions it held are missing.
  std::string text = comorph::test_support::read_text(index);
  const auto at = text.find("- file: motion-replay-000000000000.pt");
  ASSERT_NE(at, std::string::npos) << text;
  std::ofstream(index, std::ios::trunc) << text.substr(0, at) + text.substr(text.find("- file:", at + 1));
  rl::ReplayBuffer restored = make_buffer();
  std::string e = comorph::test_support::error_of([&] { rl::read_replay_segments(restored, "motion", root + "/b"); });
  EXPECT_NE(e.find(index + ": transitions [0, 4) are in no segment"), std::string::npos) << e;

  rl::ReplayBuffer bigger(kSpec, {rl::ActionKind::kContinuous, 2}, kCapacity + 1);
  e = comorph::test_support::error_of([&] { rl::read_replay_segments(bigger, "motion", root + "/a"); });
  EXPECT_NE(e.find(root + "/a/motion-replay.yaml: capacity 5, the replay buffer's is 6"), std::string::npos) << e;
  fs::remove_all(root);
}
