// Dataset files: round trips, the streaming writer, corrupt files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "perception/dataset.hpp"
#include "perception/synthetic.hpp"

namespace cp = comorph::perception;
namespace fs = std::filesystem;

namespace {

std::string temp_path(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("comorph_test_perception_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return (dir / name).string();
}

std::vector<unsigned char> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::string load_error(const std::string& path) {
  try {
    cp::load_dataset(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// Removes this process's temporary directory after all tests.
class RemoveTempDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(fs::temp_directory_path() / ("comorph_test_perception_" + std::to_string(::getpid())), ec);
  }
};
[[maybe_unused]] ::testing::Environment* const remove_temp_dir =
    ::testing::AddGlobalTestEnvironment(new RemoveTempDir);

cp::Dataset small_dataset() {
  cp::SyntheticParams p;
  p.count = 30;
  p.seed = 7;
  return cp::make_synthetic_dataset(p);
}

}  // namespace

TEST(Half, RoundTripsEveryFiniteHalf) {
  for (std::uint32_t h = 0; h < 0x10000; ++h) {
    if ((h & 0x7c00u) == 0x7c00u) continue;  // inf / NaN
    const float f = cp::half_to_float(static_cast<std::uint16_t>(h));
    ASSERT_EQ(cp::float_to_half(f), h) << "half 0x" << std::hex << h << " = " << f;
  }
  EXPECT_EQ(cp::half_to_float(cp::float_to_half(1.0f)), 1.0f);
  EXPECT_EQ(cp::half_to_float(cp::float_to_half(0.5f)), 0.5f);
  EXPECT_EQ(cp::half_to_float(cp::float_to_half(65504.0f)), 65504.0f);
  EXPECT_TRUE(std::isinf(cp::half_to_float(cp::float_to_half(1e6f))));
  // Rounding: the nearest half of 0.1 is within half a unit (2^-14 / 2 * ...).
  EXPECT_NEAR(cp::half_to_float(cp::float_to_half(0.1f)), 0.1f, 0.1f * std::ldexp(1.0f, -11));
}

TEST(Dataset, RoundTripUint8AndFloat16) {
  const cp::Dataset d = small_dataset();
  for (const auto enc : {cp::DepthEncoding::kUint8, cp::DepthEncoding::kFloat16}) {
    const std::string path = temp_path(enc == cp::DepthEncoding::kUint8 ? "u8.bin" : "f16.bin");
    cp::save_dataset(path, d, enc);
    const std::size_t bpp = enc == cp::DepthEncoding::kUint8 ? 1 : 2;
    EXPECT_EQ(fs::file_size(path), 32 + d.size() * (d.pixels() * bpp + 1));
    const cp::Dataset r = cp::load_dataset(path);
    EXPECT_EQ(r.height, d.height);
    EXPECT_EQ(r.width, d.width);
    EXPECT_EQ(r.classes, d.classes);
    EXPECT_EQ(r.labels, d.labels);
    ASSERT_EQ(r.images.size(), d.images.size());
    // uint8: error <= half a step of 1/255; float16: relative error <= 2^-11.
    for (std::size_t i = 0; i < d.images.size(); ++i) {
      const float tol = bpp == 1 ? 0.5f / 255.0f + 1e-6f : d.images[i] * std::ldexp(1.0f, -11);
      ASSERT_NEAR(r.images[i], d.images[i], tol) << "pixel " << i;
    }
    EXPECT_FALSE(fs::exists(path + ".tmp"));
  }
}

TEST(Dataset, StreamingWriterMatchesSaveAndIsAtomic) {
  const cp::Dataset d = small_dataset();
  const std::string a = temp_path("whole.bin"), b = temp_path("stream.bin");
  cp::save_dataset(a, d);
  {
    cp::DatasetWriter w(b, d.height, d.width, d.classes);
    for (std::size_t i = 0; i < d.size(); ++i) {
      w.add(d.image(i), d.labels[i]);
      EXPECT_FALSE(fs::exists(b)) << "the file appears only at finish()";
    }
    EXPECT_EQ(w.count(), d.size());
    w.finish();
  }
  EXPECT_EQ(read_bytes(a), read_bytes(b));

  const std::string c = temp_path("abandoned.bin");
  {
    cp::DatasetWriter w(c, d.height, d.width, d.classes);
    w.add(d.image(0), 1);
  }  // no finish(): nothing is left behind
  EXPECT_FALSE(fs::exists(c));
  EXPECT_FALSE(fs::exists(c + ".tmp"));

  cp::DatasetWriter w(temp_path("bad_label.bin"), d.height, d.width, d.classes);
  EXPECT_THROW(w.add(d.image(0), 3), std::invalid_argument);
  EXPECT_THROW(w.add(d.image(0), -1), std::invalid_argument);
}

TEST(Dataset, CorruptFilesNameTheFileAndTheFault) {
  const std::string good = temp_path("good.bin");
  cp::save_dataset(good, small_dataset());
  const std::vector<unsigned char> bytes = read_bytes(good);

  struct Case {
    std::string name;
    std::vector<unsigned char> bytes;
    std::string fault;
  };
  std::vector<Case> cases;
  auto with = [&](std::size_t offset, unsigned char v) {
    auto b = bytes;
    b[offset] = v;
    return b;
  };
  cases.push_back({"magic.bin", with(0, 'X'), "bad magic"});
  cases.push_back({"version.bin", with(8, 9), "unsupported version 9"});
  cases.push_back({"count.bin", with(12, 31), "implies"});             // count 31 != 30
  cases.push_back({"size.bin", with(16, 0), "image size 0x16"});
  cases.push_back({"classes.bin", with(24, 0), "classes 0"});
  cases.push_back({"encoding.bin", with(28, 7), "unknown pixel encoding 7"});
  cases.push_back({"label.bin", with(bytes.size() - 1, 9), "label 9 of image 29"});
  cases.push_back({"truncated.bin", {bytes.begin(), bytes.end() - 5}, "truncated"});
  cases.push_back({"tiny.bin", {bytes.begin(), bytes.begin() + 10}, "shorter than the 32-byte header"});
  for (const Case& c : cases) {
    const std::string path = temp_path(c.name);
    write_bytes(path, c.bytes);
    const std::string err = load_error(path);
    EXPECT_NE(err.find(path), std::string::npos) << c.name << ": " << err;
    EXPECT_NE(err.find(c.fault), std::string::npos) << c.name << ": " << err;
  }
  const std::string missing = temp_path("does_not_exist.bin");
  EXPECT_NE(load_error(missing).find(missing), std::string::npos);
  EXPECT_NO_THROW(cp::load_dataset(good));
}

TEST(Dataset, AddSubsetAndCounts) {
  cp::Dataset d(8, 8, 3);
  std::vector<float> img(64, 0.5f);
  d.add(img.data(), 2);
  img[0] = 0.25f;
  d.add(img.data(), 0);
  EXPECT_THROW(d.add(img.data(), 3), std::invalid_argument);
  EXPECT_EQ(d.size(), 2u);
  EXPECT_EQ(d.class_counts(), (std::vector<std::size_t>{1, 0, 1}));
  const cp::Dataset s = d.subset({1});
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s.labels[0], 0);
  EXPECT_EQ(s.images[0], 0.25f);
}

TEST(Synthetic, SeededBalancedAndInRange) {
  cp::SyntheticParams p;
  p.count = 90;
  const cp::Dataset a = cp::make_synthetic_dataset(p), b = cp::make_synthetic_dataset(p);
  EXPECT_EQ(a.images, b.images);
  EXPECT_EQ(a.class_counts(), (std::vector<std::size_t>{30, 30, 30}));
  for (const float v : a.images) {
    ASSERT_GE(v, 0.01f);
    ASSERT_LE(v, 1.0f);
  }
  p.seed = 2;
  EXPECT_NE(cp::make_synthetic_dataset(p).images, a.images);
}
