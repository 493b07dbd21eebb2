// gzip in memory (common/gzip): what gzip_compress writes, gunzip reads, and
// the reverse; a cut, a foreign or an oversized input is refused naming the file.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "common/gzip.hpp"
#include "support/test_support.hpp"

namespace {

using comorph::gzip_compress;
using comorph::gzip_decompress;

std::string sample_log() {
  std::string text = "episode,seed,time_s\n";
  for (int i = 0; i < 20000; ++i) text += std::to_string(i) + ",100" + std::to_string(i) + ",12.345\n";
  return text;
}

TEST(Gzip, RoundTripsAndCompressesARepetitiveLog) {
  const std::string text = sample_log();
  const std::string packed = gzip_compress(text);
  EXPECT_LT(packed.size(), text.size() / 4);
  EXPECT_EQ(gzip_decompress(packed, "mem", text.size()), text);
  EXPECT_EQ(gzip_decompress(gzip_compress(""), "mem", 0), "");
}

TEST(Gzip, GunzipReadsWhatItWritesAndItReadsGzipsFile) {
  const std::string dir = comorph::test_support::fresh_temp_dir("gzip");
  const std::string text = sample_log();
  std::ofstream(dir + "/a.csv.gz", std::ios::binary) << gzip_compress(text);
  ASSERT_EQ(std::system(("gunzip -c " + dir + "/a.csv.gz > " + dir + "/a.csv").c_str()), 0);
  EXPECT_EQ(comorph::test_support::read_text(dir + "/a.csv"), text);
  std::ofstream(dir + "/b.csv", std::ios::binary) << text;
  ASSERT_EQ(std::system(("gzip -k " + dir + "/b.csv").c_str()), 0);
  std::ifstream in(dir + "/b.csv.gz", std::ios::binary);
  const std::string packed((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(gzip_decompress(packed, dir + "/b.csv.gz", text.size()), text);
}

TEST(Gzip, RefusesCutForeignAndOversizedDataNamingTheSource) {
  const std::string text = sample_log();
  const std::string packed = gzip_compress(text);
  auto message = [](const std::string& data, std::size_t limit) {
    return comorph::test_support::error_of([&] { gzip_decompress(data, "results/x/episodes.csv.gz", limit); });
  };
  EXPECT_EQ(message(packed.substr(0, packed.size() / 2), text.size()),
            "results/x/episodes.csv.gz: damaged gzip data (the file ends early)");
  EXPECT_EQ(message(text, text.size()), "results/x/episodes.csv.gz: not gzip data");
  std::string flipped = packed;
  flipped[flipped.size() - 6] ^= 0x55;  // inside the CRC-32 trailer
  EXPECT_NE(message(flipped, text.size()).find("results/x/episodes.csv.gz: damaged gzip data"), std::string::npos);
  EXPECT_NE(message(packed, 1000).find("more than the 1000-byte limit once decompressed"), std::string::npos);
}

}  // namespace
