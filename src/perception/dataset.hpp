// Labelled depth images in memory and on disk (no torch here: the simulator
// writes datasets through this header).
//
// File format (little-endian), version 1:
//   offset  size  field
//   0       8     magic "CMDEPTH\0"
//   8       4     uint32 version (1)
//   12      4     uint32 count N (images)
//   16      4     uint32 height H (pixels)
//   20      4     uint32 width W (pixels)
//   24      4     uint32 classes K (labels are 0..K-1, K <= 255)
//   28      4     uint32 encoding: 0 = uint8 (q = round(d * 255), d = q / 255),
//                                 1 = float16 (IEEE half)
//   32      N*H*W*(1|2)  pixels, image after image, row-major
//   ...     N     uint8 labels
// The file size must match the header exactly. Depths are in [0, 1] (the
// simulator's depth images are in [0.01, 1]); values outside are clamped.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace comorph::perception {

enum class DepthEncoding : std::uint32_t {
  kUint8 = 0,    // 1 byte a pixel, step 1/255 (error <= 0.002)
  kFloat16 = 1,  // 2 bytes a pixel, relative error <= 0.05 %
};

struct Dataset {
  int height = 0;   // pixels
  int width = 0;    // pixels
  int classes = 0;  // labels are 0..classes-1
  std::vector<float> images;         // size() * height * width depths, row-major
  std::vector<std::uint8_t> labels;  // one per image

  Dataset() = default;
  Dataset(int height, int width, int classes);
  std::size_t size() const { return labels.size(); }
  std::size_t pixels() const { return static_cast<std::size_t>(height) * width; }
  const float* image(std::size_t i) const { return images.data() + i * pixels(); }
  // Append one image of height*width depths; throws on a bad label.
  void add(const float* depth, int label);
  // Images per class (size classes).
  std::vector<std::size_t> class_counts() const;
  // The images at `indices`, in that order.
  Dataset subset(const std::vector<std::size_t>& indices) const;
};

// Write a whole dataset (atomically: PATH.tmp, then rename).
void save_dataset(const std::string& path, const Dataset& data,
                  DepthEncoding encoding = DepthEncoding::kUint8);
// Read and validate; throws std::runtime_error naming the file and the fault.
Dataset load_dataset(const std::string& path);

// Streaming writer for the simulator: append images one at a time without
// keeping them in memory; finish() writes the labels, patches the count and
// renames PATH.tmp to PATH. If finish() is never called (exception, crash)
// PATH is not created; the destructor removes PATH.tmp.
class DatasetWriter {
 public:
  DatasetWriter(const std::string& path, int height, int width, int classes,
                DepthEncoding encoding = DepthEncoding::kUint8);
  ~DatasetWriter();
  DatasetWriter(const DatasetWriter&) = delete;
  DatasetWriter& operator=(const DatasetWriter&) = delete;

  void add(const float* depth, int label);  // height*width depths
  void finish();
  std::size_t count() const { return labels_.size(); }

 private:
  std::string path_, tmp_path_;
  int height_, width_, classes_;
  DepthEncoding encoding_;
  std::FILE* file_ = nullptr;
  std::vector<std::uint8_t> labels_;
  std::vector<std::uint8_t> row_;  // encoded pixels of one image (reused)
};

// IEEE half <-> float (round to nearest even), exposed for tests.
std::uint16_t float_to_half(float value);
float half_to_float(std::uint16_t half);

}  // namespace comorph::perception
