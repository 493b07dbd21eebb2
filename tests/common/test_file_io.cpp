// Checked writes fail loudly and leave no half file; reads refuse directories
// and oversized files; YAML refuses duplicate keys; checksums find changed bytes.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <functional>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/checksum.hpp"
#include "common/file_io.hpp"
#include "common/yaml_fields.hpp"
#include "support/test_support.hpp"

namespace comorph {
namespace {
namespace fs = std::filesystem;

using test_support::error_of;

TEST(FileIo, WriteToAFullDeviceNamesThePathAndTheReason) {
  const std::string e = error_of([] { write_file_atomic("/dev/full", std::string(100, 'x')); });
  EXPECT_NE(e.find("cannot write /dev/full: No space left on device"), std::string::npos) << e;
  const std::string a = error_of([] { append_file("/dev/full", "row\n"); });
  EXPECT_NE(a.find("cannot write /dev/full: No space left on device"), std::string::npos) << a;
}

TEST(FileIo, WriteIntoAMissingDirectoryIsAnError) {
  const std::string e = error_of([] { write_file_atomic("/nonexistent-dir/x.json", "{}"); });
  EXPECT_NE(e.find("cannot write /nonexistent-dir/x.json: No such file or directory"), std::string::npos) << e;
}

// A file-size limit makes write() fail on a regular file as a full disk does
// (EFBIG instead of ENOSPC): the old file must stay whole and no temporary
// file may be left.
TEST(FileIo, AFailedWriteKeepsTheOldFileAndLeavesNoTemporary) {
  const std::string dir = test_support::fresh_temp_dir("file_io_limit");
  const std::string path = dir + "/eval.json";
  write_file_atomic(path, "old contents\n");
  std::signal(SIGXFSZ, SIG_IGN);  // write() returns EFBIG instead of killing the process
  rlimit saved{};
  getrlimit(RLIMIT_FSIZE, &saved);
  rlimit small = saved;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string e = error_of([&] { write_file_atomic(path, std::string(100000, 'y')); });
  setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, SIG_DFL);
  EXPECT_NE(e.find("cannot write " + path + ": File too large"), std::string::npos) << e;
  EXPECT_EQ(test_support::read_text(path), "old contents\n");
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) files += entry.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1) << "a temporary file was left behind";
}

TEST(FileIo, WriteReplacesTheWholeFile) {
  const std::string dir = test_support::fresh_temp_dir("file_io_replace");
  write_file_atomic(dir + "/a.txt", "a much longer first text\n");
  write_file_atomic(dir + "/a.txt", "short\n");
  append_file(dir + "/a.txt", "more\n");
  EXPECT_EQ(test_support::read_text(dir + "/a.txt"), "short\nmore\n");
}

TEST(FileIo, FlushStdoutReportsAFailedWrite) {
  // stdout itself is gtest's; a FILE on /dev/full stands in for it here.
  FILE* saved = stdout;
  stdout = std::fopen("/dev/full", "w");
  ASSERT_NE(stdout, nullptr);
  std::fputs("some output\n", stdout);
  const std::string e = error_of([] { flush_stdout(); });
  std::fclose(stdout);
  stdout = saved;
  EXPECT_NE(e.find("cannot write standard output: No space left on device"), std::string::npos) << e;
}

TEST(FileIo, ReadRefusesDirectoriesMissingAndOversizedFiles) {
  const std::string dir = test_support::fresh_temp_dir("file_io_read");
  EXPECT_NE(error_of([&] { read_text_file(dir); }).find("is a directory, expected a file"), std::string::npos);
  EXPECT_NE(error_of([&] { read_text_file(dir + "/none.yaml"); }).find("no such file"), std::string::npos);
  const std::string big = dir + "/big.yaml";
  std::ofstream(big) << "a: 1\n";
  fs::resize_file(big, kMaxConfigFileBytes + 1);  // sparse: costs no disk
  const std::string e = error_of([&] { read_text_file(big); });
  EXPECT_NE(e.find(std::to_string(kMaxConfigFileBytes + 1) + " bytes, more than the 1048576-byte limit"),
            std::string::npos)
      << e;
  EXPECT_EQ(read_text_file(dir + "/big.yaml", 2 * kMaxConfigFileBytes).size(), kMaxConfigFileBytes + 1);
}

TEST(FileIo, QuoteValueKeepsMessagesShort) {
  EXPECT_EQ(quote_value("short"), "short");
  const std::string q = quote_value(std::string(50000000, 'z'));
  EXPECT_LT(q.size(), 120u);
  EXPECT_NE(q.find("(50000000 characters)"), std::string::npos);
}

TEST(Yaml, DuplicateKeysAreAnErrorAtAnyDepth) {
  const std::string e = error_of([] { parse_yaml("a: 1\nb:\n  c: 2\n  c: 3\n", "x.yaml"); });
  EXPECT_NE(e.find("x.yaml: key 'c' appears twice in one mapping (line 4)"), std::string::npos) << e;
  EXPECT_NE(error_of([] { parse_yaml("a: 1\na: 1\n", "y.yaml"); }).find("key 'a' appears twice"), std::string::npos);
  EXPECT_EQ(error_of([] { parse_yaml("a: 1\nb: [{c: 1}, {c: 2}]\n", "z.yaml"); }), "");
  double v = 0;
  YamlFields f("w.yaml");
  f.add("v", &v, 0.0, 1.0, "a fraction");
  EXPECT_NE(error_of([&] { f.apply_text("v: 0.5\nv: 0.7\n"); }).find("appears twice"), std::string::npos);
}

TEST(Yaml, ABadValueIsQuotedShort) {
  int v = 0;
  YamlFields f("big.yaml");
  f.add("v", &v, "a count");
  const std::string e = error_of([&] { f.apply_text("v: " + std::string(100000, 'q') + "\n"); });
  EXPECT_LT(e.size(), 200u) << e.substr(0, 300);
  EXPECT_NE(e.find("big.yaml: field 'v': bad value 'qqq"), std::string::npos);
  const std::string key = error_of([&] { f.apply_text(std::string(1000, 'k') + ": 1\n"); });
  EXPECT_LT(key.size(), 200u) << key.substr(0, 300);
  EXPECT_NE(key.find("unknown field"), std::string::npos);
}

enum class Shade { light, dark };
constexpr auto enum_names(Shade) { return std::array{EnumName{Shade::light, "light"}, EnumName{Shade::dark, "dark"}}; }

TEST(Yaml, EnumFieldsAreReadAndWrittenByName) {
  Shade s = Shade::light;
  YamlFields f("s.yaml");
  f.add("paint.shade", &s, "how dark the paint is");
  f.apply_text("paint: {shade: dark}\n");
  EXPECT_EQ(s, Shade::dark);
  EXPECT_EQ(name_of(s), "dark");
  EXPECT_EQ(enum_name_list<Shade>(), "light | dark");
  EXPECT_EQ(error_of([&] { f.apply_text("paint: {shade: grey}\n"); }),
            "s.yaml: field 'paint.shade': 'grey' is not one of light | dark (line 1)");
  EXPECT_NE(error_of([&] { f.apply_text("paint: {shade: [dark]}\n"); }).find("is not one of"), std::string::npos);
  const std::string long_name = error_of([&] { f.apply_text("paint: {shade: " + std::string(5000, 'g') + "}\n"); });
  EXPECT_LT(long_name.size(), 200u) << long_name.substr(0, 300);
  EXPECT_EQ(s, Shade::dark);  // a refused value leaves the field as it was
}

// One field list reads a file, lists its fields and writes their values back.
TEST(Yaml, AFieldListReadsListsAndWritesItsValues) {
  struct Params {
    double rate = 0.25;
    int count = 3;
    std::vector<int> sizes{8, 8};
    Shade shade = Shade::light;
    std::string name;
  } p;
  YamlFields f("p.yaml");
  f.set_prefix("net.");
  f.add("rate", &p.rate, 0.0, 1.0, "a fraction");
  f.add("count", &p.count, 1, 10, "how many");
  f.add("sizes", &p.sizes, "layer widths");
  f.add("look.shade", &p.shade, "how dark");
  f.add("name", &p.name, "what it is called");
  const std::vector<Setting> listed = f.settings();
  ASSERT_EQ(listed.size(), 5u);
  EXPECT_EQ(listed[0].key, "net.rate");
  EXPECT_EQ(listed[0].type, "number");
  EXPECT_EQ(listed[0].range, "[0, 1]");
  EXPECT_EQ(listed[0].value, "0.25");
  EXPECT_EQ(listed[0].meaning, "a fraction");
  EXPECT_EQ(listed[1].type, "integer");
  EXPECT_EQ(listed[2].type, "list of integer");
  EXPECT_EQ(listed[2].value, "[8, 8]");
  EXPECT_EQ(listed[3].key, "net.look.shade");
  EXPECT_EQ(listed[3].type, "light | dark");
  EXPECT_EQ(listed[4].value, "\"\"");

  f.apply_text("net:\n  rate: 0.1\n  sizes: [3]\n  look: {shade: dark}\n  name: x y\n");
  YAML::Emitter e;
  e << f.values();
  const std::string written = e.c_str();
  // The written values read back to the same values (0.1 stays 0.1, not 0.1000000000000000055).
  p = Params{};
  f.apply_text(written);
  EXPECT_EQ(p.rate, 0.1);
  EXPECT_EQ(p.sizes, std::vector<int>{3});
  EXPECT_EQ(p.shade, Shade::dark);
  EXPECT_EQ(p.name, "x y");
  EXPECT_NE(written.find("rate: 0.1\n"), std::string::npos) << written;

  // Errors name the file, the field and the line.
  EXPECT_EQ(error_of([&] { f.apply_text("net:\n  count: 11\n"); }),
            "p.yaml: field 'net.count': value 11 out of range [1, 10] (line 2)");
  EXPECT_EQ(error_of([&] { f.apply_text("net:\n\n  colour: 1\n"); }), "p.yaml: field 'net.colour': unknown field (line 3)");
}

// A key that is a list or a mapping is refused with the file and the line
// (yaml-cpp alone says "bad conversion" and names no file).
TEST(Yaml, AKeyThatIsNotANameIsRefusedWithFileAndLine) {
  EXPECT_EQ(error_of([] { parse_yaml("a: 1\n[b, c]: 2\n", "k.yaml"); }), "k.yaml: line 2: a key must be a name, not a list");
  EXPECT_EQ(error_of([] { parse_yaml("a:\n  {b: 1}: 2\n", "m.yaml"); }), "m.yaml: line 2: a key must be a name, not a mapping");
}

TEST(Checksum, FindsAFlippedByteATruncationAndAMissingFile) {
  const std::string dir = test_support::fresh_temp_dir("checksum");
  write_file_atomic(dir + "/a.pt", std::string(10000, 'a'));
  write_file_atomic(dir + "/b.yaml", "episodes: 4\n");
  EXPECT_NE(verify_checksums(dir).find("checksums.txt: missing"), std::string::npos);  // no checksum file yet
  write_checksums(dir, {"a.pt", "b.yaml"});
  EXPECT_EQ(verify_checksums(dir), "");
  {
    std::fstream f(dir + "/a.pt", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(5000);
    f.put('b');
  }
  const std::string flipped = verify_checksums(dir);
  EXPECT_NE(flipped.find(dir + "/a.pt: checksum mismatch"), std::string::npos) << flipped;
  write_checksums(dir, {"a.pt", "b.yaml"});
  fs::resize_file(dir + "/b.yaml", 3);
  EXPECT_NE(verify_checksums(dir).find(dir + "/b.yaml: checksum mismatch"), std::string::npos);
  fs::remove(dir + "/b.yaml");
  EXPECT_NE(verify_checksums(dir).find(dir + "/b.yaml: missing"), std::string::npos);
}

}  // namespace
}  // namespace comorph
