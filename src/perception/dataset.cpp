// Binary dataset files of labelled depth images (format in dataset.hpp).
#include "perception/dataset.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace comorph::perception {
namespace {

constexpr char kMagic[8] = {'C', 'M', 'D', 'E', 'P', 'T', 'H', '\0'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 32;
constexpr int kMaxSide = 4096;     // pixels; guards against absurd headers
constexpr int kMaxClasses = 255;   // labels are stored as uint8

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error("dataset " + path + ": " + what);
}

void put_u32(std::uint8_t* out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint32_t get_u32(const std::uint8_t* in) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(in[i]) << (8 * i);
  return v;
}

std::size_t bytes_per_pixel(DepthEncoding e) { return e == DepthEncoding::kUint8 ? 1 : 2; }

void check_shape(const std::string& path, int height, int width, int classes) {
  if (height < 1 || height > kMaxSide || width < 1 || width > kMaxSide)
    fail(path, "image size " + std::to_string(height) + "x" + std::to_string(width) +
                   " is outside 1.." + std::to_string(kMaxSide) + " pixels");
  if (classes < 1 || classes > kMaxClasses)
    fail(path, "classes " + std::to_string(classes) + " is outside 1.." +
                   std::to_string(kMaxClasses));
}

void check_label(const std::string& where, int label, int classes) {
  if (label < 0 || label >= classes)
    throw std::invalid_argument(where + ": label " + std::to_string(label) + " is outside 0.." +
                                std::to_string(classes - 1));
}

// Encode one image into `out` (pixels * bytes_per_pixel bytes).
void encode(const float* depth, std::size_t pixels, DepthEncoding e, std::uint8_t* out) {
  for (std::size_t i = 0; i < pixels; ++i) {
    const float d = std::clamp(std::isfinite(depth[i]) ? depth[i] : 1.0f, 0.0f, 1.0f);
    if (e == DepthEncoding::kUint8) {
      out[i] = static_cast<std::uint8_t>(std::lround(d * 255.0f));
    } else {
      const std::uint16_t h = float_to_half(d);
      out[2 * i] = static_cast<std::uint8_t>(h & 0xff);
      out[2 * i + 1] = static_cast<std::uint8_t>(h >> 8);
    }
  }
}

void make_header(std::uint8_t* h, std::uint32_t count, int height, int width, int classes,
                 DepthEncoding e) {
  std::memcpy(h, kMagic, 8);
  put_u32(h + 8, kVersion);
  put_u32(h + 12, count);
  put_u32(h + 16, static_cast<std::uint32_t>(height));
  put_u32(h + 20, static_cast<std::uint32_t>(width));
  put_u32(h + 24, static_cast<std::uint32_t>(classes));
  put_u32(h + 28, static_cast<std::uint32_t>(e));
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

}  // namespace

std::uint16_t float_to_half(float value) {
  std::uint32_t f;
  std::memcpy(&f, &value, 4);
  const std::uint32_t sign = (f >> 16) & 0x8000u;
  const std::uint32_t exp = (f >> 23) & 0xffu;
  std::uint32_t mant = f & 0x7fffffu;
  if (exp == 0xff) return static_cast<std::uint16_t>(sign | 0x7c00u | (mant ? 0x200u : 0u));
  const int e = static_cast<int>(exp) - 127 + 15;
  if (e >= 0x1f) return static_cast<std::uint16_t>(sign | 0x7c00u);  // overflow -> inf
  if (e <= 0) {                                                        // half subnormal or 0
    if (e < -10) return static_cast<std::uint16_t>(sign);
    mant |= 0x800000u;
    const int shift = 14 - e;
    std::uint32_t m = mant >> shift;
    const std::uint32_t rem = mant & ((1u << shift) - 1u);
    const std::uint32_t halfway = 1u << (shift - 1);
    if (rem > halfway || (rem == halfway && (m & 1u))) ++m;
    return static_cast<std::uint16_t>(sign | m);
  }
  std::uint32_t h = sign | (static_cast<std::uint32_t>(e) << 10) | (mant >> 13);
  const std::uint32_t rem = mant & 0x1fffu;
  if (rem > 0x1000u || (rem == 0x1000u && (h & 1u))) ++h;  // a carry rounds up the exponent
  return static_cast<std::uint16_t>(h);
}

float half_to_float(std::uint16_t h) {
  const std::uint32_t sign = (static_cast<std::uint32_t>(h) & 0x8000u) << 16;
  const std::uint32_t exp = (h >> 10) & 0x1fu;
  const std::uint32_t mant = h & 0x3ffu;
  std::uint32_t f;
  if (exp == 0) {
    const float v = std::ldexp(static_cast<float>(mant), -24);
    return sign ? -v : v;
  } else if (exp == 0x1f) {
    f = sign | 0x7f800000u | (mant << 13);
  } else {
    f = sign | ((exp + 112u) << 23) | (mant << 13);
  }
  float out;
  std::memcpy(&out, &f, 4);
  return out;
}

Dataset::Dataset(int h, int w, int k) : height(h), width(w), classes(k) {
  check_shape("<memory>", h, w, k);
}

void Dataset::add(const float* depth, int label) {
  check_label("Dataset::add", label, classes);
  images.insert(images.end(), depth, depth + pixels());
  labels.push_back(static_cast<std::uint8_t>(label));
}

std::vector<std::size_t> Dataset::class_counts() const {
  std::vector<std::size_t> counts(static_cast<std::size_t>(std::max(classes, 0)), 0);
  for (const std::uint8_t l : labels) ++counts.at(l);
  return counts;
}

Dataset Dataset::subset(const std::vector<std::size_t>& indices) const {
  Dataset out;
  out.height = height;
  out.width = width;
  out.classes = classes;
  out.images.reserve(indices.size() * pixels());
  out.labels.reserve(indices.size());
  for (const std::size_t i : indices) {
    if (i >= size()) throw std::out_of_range("Dataset::subset: index out of range");
    out.images.insert(out.images.end(), image(i), image(i) + pixels());
    out.labels.push_back(labels[i]);
  }
  return out;
}

void save_dataset(const std::string& path, const Dataset& data, DepthEncoding encoding) {
  if (data.images.size() != data.size() * data.pixels())
    fail(path, "images hold " + std::to_string(data.images.size()) + " depths, expected " +
                   std::to_string(data.size() * data.pixels()));
  DatasetWriter writer(path, data.height, data.width, data.classes, encoding);
  for (std::size_t i = 0; i < data.size(); ++i) writer.add(data.image(i), data.labels[i]);
  writer.finish();
}

Dataset load_dataset(const std::string& path) {
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::fseek(file.get(), 0, SEEK_END);
  const long size = std::ftell(file.get());
  std::fseek(file.get(), 0, SEEK_SET);
  if (size < 0) fail(path, "cannot determine the file size");
  if (static_cast<std::size_t>(size) < kHeaderBytes)
    fail(path, "file is " + std::to_string(size) + " bytes, shorter than the " +
                   std::to_string(kHeaderBytes) + "-byte header");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (std::fread(bytes.data(), 1, bytes.size(), file.get()) != bytes.size())
    fail(path, "read error");
  const std::uint8_t* h = bytes.data();
  if (std::memcmp(h, kMagic, 8) != 0)
    fail(path, "bad magic (not a comorph depth dataset; expected \"CMDEPTH\")");
  const std::uint32_t version = get_u32(h + 8);
  if (version != kVersion)
    fail(path, "unsupported version " + std::to_string(version) + " (this build reads " +
                   std::to_string(kVersion) + ")");
  const std::uint32_t count = get_u32(h + 12);
  const std::uint32_t height = get_u32(h + 16), width = get_u32(h + 20);
  const std::uint32_t classes = get_u32(h + 24), enc = get_u32(h + 28);
  if (height < 1 || height > static_cast<std::uint32_t>(kMaxSide) || width < 1 ||
      width > static_cast<std::uint32_t>(kMaxSide))
    fail(path, "header image size " + std::to_string(height) + "x" + std::to_string(width) +
                   " is outside 1.." + std::to_string(kMaxSide) + " pixels");
  if (classes < 1 || classes > static_cast<std::uint32_t>(kMaxClasses))
    fail(path, "header classes " + std::to_string(classes) + " is outside 1.." +
                   std::to_string(kMaxClasses));
  if (enc > 1) fail(path, "unknown pixel encoding " + std::to_string(enc) + " (0 = uint8, 1 = float16)");
  const auto encoding = static_cast<DepthEncoding>(enc);
  const std::size_t pixels = static_cast<std::size_t>(height) * width;
  const std::size_t expected = kHeaderBytes + count * (pixels * bytes_per_pixel(encoding) + 1);
  if (bytes.size() != expected)
    fail(path, "file is " + std::to_string(bytes.size()) + " bytes but the header (" +
                   std::to_string(count) + " images of " + std::to_string(height) + "x" +
                   std::to_string(width) + ", " + (enc == 0 ? "uint8" : "float16") +
                   ") implies " + std::to_string(expected) + " (truncated or corrupt)");
  Dataset data(static_cast<int>(height), static_cast<int>(width), static_cast<int>(classes));
  data.images.resize(count * pixels);
  const std::uint8_t* px = h + kHeaderBytes;
  for (std::size_t i = 0; i < count * pixels; ++i) {
    data.images[i] = encoding == DepthEncoding::kUint8
                         ? px[i] / 255.0f
                         : half_to_float(static_cast<std::uint16_t>(px[2 * i] | (px[2 * i + 1] << 8)));
  }
  const std::uint8_t* lab = px + count * pixels * bytes_per_pixel(encoding);
  data.labels.assign(lab, lab + count);
  for (std::size_t i = 0; i < count; ++i)
    if (data.labels[i] >= classes)
      fail(path, "label " + std::to_string(data.labels[i]) + " of image " + std::to_string(i) +
                     " is not below classes " + std::to_string(classes));
  return data;
}

DatasetWriter::DatasetWriter(const std::string& path, int height, int width, int classes,
                             DepthEncoding encoding)
    : path_(path), tmp_path_(path + ".tmp"), height_(height), width_(width), classes_(classes),
      encoding_(encoding) {
  check_shape(path, height, width, classes);
  file_ = std::fopen(tmp_path_.c_str(), "wb");
  if (!file_) fail(path, "cannot create " + tmp_path_ + ": " + std::strerror(errno));
  std::uint8_t header[kHeaderBytes];
  make_header(header, 0, height, width, classes, encoding);  // count patched by finish()
  if (std::fwrite(header, 1, kHeaderBytes, file_) != kHeaderBytes) fail(path, std::string("write error: ") + std::strerror(errno));
  row_.resize(static_cast<std::size_t>(height) * width * bytes_per_pixel(encoding));
}

DatasetWriter::~DatasetWriter() {
  if (file_) {
    std::fclose(file_);
    std::remove(tmp_path_.c_str());
  }
}

void DatasetWriter::add(const float* depth, int label) {
  if (!file_) fail(path_, "add() after finish()");
  check_label("dataset " + path_, label, classes_);
  encode(depth, static_cast<std::size_t>(height_) * width_, encoding_, row_.data());
  if (std::fwrite(row_.data(), 1, row_.size(), file_) != row_.size())
    fail(path_, std::string("write error: ") + std::strerror(errno));
  labels_.push_back(static_cast<std::uint8_t>(label));
}

void DatasetWriter::finish() {
  if (!file_) fail(path_, "finish() called twice");
  if (labels_.size() > 0xffffffffu) fail(path_, "too many images for a version-1 file");
  bool ok = std::fwrite(labels_.data(), 1, labels_.size(), file_) == labels_.size();
  std::uint8_t count[4];
  put_u32(count, static_cast<std::uint32_t>(labels_.size()));
  ok = ok && std::fseek(file_, 12, SEEK_SET) == 0 && std::fwrite(count, 1, 4, file_) == 4;
  ok = ok && std::fflush(file_) == 0;
  const int err = errno;  // of the failed write, before fclose may change it
  ok = (std::fclose(file_) == 0) && ok;
  file_ = nullptr;
  if (!ok) {
    std::remove(tmp_path_.c_str());
    fail(path_, std::string("write error: ") + std::strerror(err != 0 ? err : errno));
  }
  if (std::rename(tmp_path_.c_str(), path_.c_str()) != 0) {
    std::remove(tmp_path_.c_str());
    fail(path_, std::string("cannot rename from ") + tmp_path_ + ": " + std::strerror(errno));
  }
}

}  // namespace comorph::perception
