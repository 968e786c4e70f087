#pragma once
// A per-pixel map of float channels (depth, normals, orientation, confidence, cost).
// Stored planar (channel-major) exactly as COLMAP's dense Mat files: element (row, col,
// channel) is data[channel * width * height + row * width + col].

#include <cstddef>
#include <vector>

namespace hairmvs {

class FloatMap {
 public:
  FloatMap() = default;
  FloatMap(int width, int height, int channels = 1, float fill = 0.0f)
      : width_(width), height_(height), channels_(channels),
        data_(static_cast<size_t>(width) * height * channels, fill) {}

  int Width() const { return width_; }
  int Height() const { return height_; }
  int Channels() const { return channels_; }
  size_t NumPixels() const { return static_cast<size_t>(width_) * height_; }
  bool Empty() const { return data_.empty(); }

  float& At(int row, int col, int channel = 0) { return data_[Index(row, col, channel)]; }
  float At(int row, int col, int channel = 0) const { return data_[Index(row, col, channel)]; }

  float* Channel(int channel) { return data_.data() + channel * NumPixels(); }
  const float* Channel(int channel) const { return data_.data() + channel * NumPixels(); }

  std::vector<float>& Data() { return data_; }
  const std::vector<float>& Data() const { return data_; }

 private:
  size_t Index(int row, int col, int channel) const {
    return static_cast<size_t>(channel) * NumPixels() + static_cast<size_t>(row) * width_ + col;
  }

  int width_ = 0;
  int height_ = 0;
  int channels_ = 0;
  std::vector<float> data_;
};

}  // namespace hairmvs
