#pragma once
// A per-pixel map of float channels (depth, normals, orientation, confidence, cost).
// Stored planar (channel-major) exactly as COLMAP's dense Mat files: element (row, col,
// channel) is data[channel * width * height + row * width + col].

#include <algorithm>
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

// The width x height pixels of a map whose top-left pixel is (x0, y0).
struct PixelBox {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  bool Empty() const { return width <= 0 || height <= 0; }
};

// The smallest box holding every pixel whose channel 0 is above `threshold` (empty if none).
inline PixelBox BoundingBoxAbove(const FloatMap& map, float threshold) {
  int min_col = map.Width(), max_col = -1, min_row = map.Height(), max_row = -1;
  for (int row = 0; row < map.Height(); ++row) {
    const float* values = map.Channel(0) + static_cast<size_t>(row) * map.Width();
    for (int col = 0; col < map.Width(); ++col) {
      if (!(values[col] > threshold)) continue;
      min_col = std::min(min_col, col);
      max_col = std::max(max_col, col);
      min_row = std::min(min_row, row);
      max_row = row;
    }
  }
  if (max_col < 0) return PixelBox();
  return PixelBox{min_col, min_row, max_col - min_col + 1, max_row - min_row + 1};
}

// The width x height part of `map` whose top-left pixel is (x0, y0), all channels; it must lie
// inside `map`.
inline FloatMap CropFloatMap(const FloatMap& map, int x0, int y0, int width, int height) {
  FloatMap part(width, height, map.Channels());
  for (int c = 0; c < map.Channels(); ++c) {
    for (int row = 0; row < height; ++row) {
      const float* from = map.Channel(c) + static_cast<size_t>(y0 + row) * map.Width() + x0;
      std::copy(from, from + width, part.Channel(c) + static_cast<size_t>(row) * width);
    }
  }
  return part;
}

// `part` written into `whole` (same channels) with its top-left pixel at (x0, y0).
inline void PasteFloatMap(const FloatMap& part, int x0, int y0, FloatMap* whole) {
  for (int c = 0; c < part.Channels(); ++c) {
    for (int row = 0; row < part.Height(); ++row) {
      const float* from = part.Channel(c) + static_cast<size_t>(row) * part.Width();
      std::copy(from, from + part.Width(),
                whole->Channel(c) + static_cast<size_t>(y0 + row) * whole->Width() + x0);
    }
  }
}

// A whole_width x whole_height map of zeros with `part` written at (x0, y0): what
// CropFloatMap took, put back.
inline FloatMap UncropFloatMap(const FloatMap& part, int x0, int y0, int whole_width,
                               int whole_height) {
  FloatMap whole(whole_width, whole_height, part.Channels());
  PasteFloatMap(part, x0, y0, &whole);
  return whole;
}

// A map held as one box of it, zeros around: a depth map's depths, a confidence map's
// positive values (many such maps are held at once, and hair fills a fifth of a view).
struct CroppedFloatMap {
  FloatMap part;  // the whole map's pixels in `box`
  PixelBox box;
  int whole_width = 0, whole_height = 0;

  // `whole` cropped to the box of its pixels whose channel 0 is above 0 (an empty part if
  // none): what is not above 0 outside it comes back as +0.
  static CroppedFloatMap AbovePositive(const FloatMap& whole) {
    const PixelBox box = BoundingBoxAbove(whole, 0.0f);
    return {CropFloatMap(whole, box.x0, box.y0, box.width, box.height), box, whole.Width(),
            whole.Height()};
  }
  FloatMap Whole() const {
    return UncropFloatMap(part, box.x0, box.y0, whole_width, whole_height);
  }
};

}  // namespace hairmvs
