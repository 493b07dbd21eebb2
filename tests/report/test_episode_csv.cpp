// Episode CSV: exact round trip, and errors that point at line and column.
#include <gtest/gtest.h>

#include <sstream>

#include "report/episode_record.hpp"

namespace comorph::report {
namespace {

std::vector<EpisodeRecord> sample() {
  std::vector<EpisodeRecord> out;
  for (int i = 0; i < 5; ++i) {
    EpisodeRecord r;
    r.episode = i;
    r.seed = 18446744073709551615ull - static_cast<std::uint64_t>(i);  // the full 64-bit range survives
    r.scenario = i % 2 ? "obstacles7" : "default";
    r.stair_height_m = 0.04 + 0.02 * (i % 3);
    r.obstacles = 6 + i % 3;
    r.success = i % 2 == 0;
    r.termination = r.success ? "success" : "collision";
    r.time_s = 43.1 + i / 3.0;  // not exactly representable in few digits
    r.energy_J = 3090.0 * (1.0 + i / 7.0);
    r.distance_fraction = 1.0 / (i + 1.0);
    r.return_R1 = -12.5 + 0.1 * i;
    r.configurations = i == 3 ? std::vector<int>{} : std::vector<int>{4 + i, 2};
    r.modules_total = 4 + i;
    r.action_saturation = i / 9.0;
    r.stairs_climbed = i % 3 == 1;
    out.push_back(r);
  }
  return out;
}

TEST(EpisodeCsv, RoundTripIsExact) {
  std::stringstream s;
  write_episodes_csv(s, sample());
  const std::string text = s.str();
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "episode,seed,scenario,stair_height_m,obstacles,success,termination,time_s,energy_J,"
            "distance_fraction,return_R1,configurations,modules_total,action_saturation,stairs_climbed");
  EXPECT_NE(text.find(",4;2,"), std::string::npos) << text;
  const auto back = read_episodes_csv(s, "mem");
  const auto orig = sample();
  ASSERT_EQ(back.size(), orig.size());
  for (size_t i = 0; i < orig.size(); ++i) {
    EXPECT_EQ(back[i].episode, orig[i].episode);
    EXPECT_EQ(back[i].seed, orig[i].seed);
    EXPECT_EQ(back[i].scenario, orig[i].scenario);
    EXPECT_EQ(back[i].stair_height_m, orig[i].stair_height_m);
    EXPECT_EQ(back[i].obstacles, orig[i].obstacles);
    EXPECT_EQ(back[i].success, orig[i].success);
    EXPECT_EQ(back[i].termination, orig[i].termination);
    EXPECT_EQ(back[i].time_s, orig[i].time_s);
    EXPECT_EQ(back[i].energy_J, orig[i].energy_J);
    EXPECT_EQ(back[i].distance_fraction, orig[i].distance_fraction);
    EXPECT_EQ(back[i].return_R1, orig[i].return_R1);
    EXPECT_EQ(back[i].configurations, orig[i].configurations);
    EXPECT_EQ(back[i].modules_total, orig[i].modules_total);
    EXPECT_EQ(back[i].action_saturation, orig[i].action_saturation);
    EXPECT_EQ(back[i].stairs_climbed, orig[i].stairs_climbed);
  }
}

// Logs written before the action_saturation column existed still read (as 0).
TEST(EpisodeCsv, ALogWithoutTheSaturationColumnReadsAsZero) {
  std::stringstream s(
      "episode,seed,scenario,stair_height_m,obstacles,success,termination,time_s,energy_J,"
      "distance_fraction,return_R1,configurations,modules_total\n"
      "0,7,default,0.04,6,1,success,30,2900,0.95,800,4;2,4\n");
  const auto back = read_episodes_csv(s, "mem");
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].modules_total, 4);
  EXPECT_EQ(back[0].action_saturation, 0.0);
  EXPECT_FALSE(back[0].stairs_climbed);
}

std::string error_of(const std::string& csv) {
  std::istringstream in(csv);
  try {
    read_episodes_csv(in, "runs/a/episodes.csv");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

const char* kHeader =
    "episode,seed,scenario,stair_height_m,obstacles,success,termination,time_s,energy_J,"
    "distance_fraction,return_R1,configurations,modules_total\n";

TEST(EpisodeCsv, BadNumberNamesLineAndColumn) {
  const std::string good = "0,7,default,0.04,6,1,success,43.1,3090,1,12.5,4;2,4\n";
  const std::string bad = "1,8,default,0.06,6,0,collision,4x3.1,3090,1,12.5,4,4\n";
  const size_t column = bad.find("4x3.1") + 1;  // 1-based column where time_s starts
  const std::string msg = error_of(std::string(kHeader) + good + bad);
  EXPECT_NE(msg.find("runs/a/episodes.csv:3:" + std::to_string(column) + ":"), std::string::npos) << msg;
  EXPECT_NE(msg.find("time_s"), std::string::npos) << msg;
  EXPECT_NE(msg.find("4x3.1"), std::string::npos) << msg;
}

TEST(EpisodeCsv, BadConfigurationPointsInsideTheField) {
  // "4;x": the bad part starts 2 characters into the configurations field.
  const std::string row = "0,7,default,0.04,6,1,success,43.1,3090,1,12.5,4;x,4\n";
  const size_t field = std::string(row).find("4;x") + 1;  // 1-based column of the field
  const std::string msg = error_of(std::string(kHeader) + row);
  EXPECT_NE(msg.find(":2:" + std::to_string(field + 2) + ":"), std::string::npos) << msg;
}

TEST(EpisodeCsv, WrongFieldCountAndBadSuccessAndMissingColumn) {
  EXPECT_NE(error_of(std::string(kHeader) + "0,7,default\n").find(":2:"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHeader) + "0,7,default,0.04,6,yes,success,43.1,3090,1,12.5,4,4\n").find("success"),
            std::string::npos);
  const std::string msg = error_of("episode,seed\n0,1\n");
  EXPECT_NE(msg.find("runs/a/episodes.csv:1:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("scenario"), std::string::npos) << msg;
  EXPECT_NE(error_of("").find(":1:1:"), std::string::npos);
}

TEST(EpisodeCsv, RefusesTextThatWouldBreakTheFormat) {
  auto records = sample();
  records[2].termination = "hit, then fell";
  std::stringstream s;
  EXPECT_THROW(write_episodes_csv(s, records), std::invalid_argument);
}

}  // namespace
}  // namespace comorph::report
