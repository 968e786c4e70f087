#include "src/core/float_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace hairmvs {
namespace {

// A 2-channel map whose value names its row, column and channel.
FloatMap NumberedMap(int width, int height) {
  FloatMap map(width, height, 2);
  for (int c = 0; c < 2; ++c) {
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) map.At(row, col, c) = 1000 * c + 100 * row + col;
    }
  }
  return map;
}

TEST(FloatMap, CropAndPasteKeepEveryChannelInPlace) {
  const FloatMap map = NumberedMap(7, 5);
  const FloatMap part = CropFloatMap(map, 2, 1, 4, 3);
  ASSERT_EQ(part.Width(), 4);
  ASSERT_EQ(part.Height(), 3);
  ASSERT_EQ(part.Channels(), 2);
  for (int c = 0; c < 2; ++c) {
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) {
        EXPECT_EQ(part.At(row, col, c), map.At(row + 1, col + 2, c));
      }
    }
  }
  FloatMap whole(7, 5, 2, -1.0f);
  PasteFloatMap(part, 2, 1, &whole);
  for (int c = 0; c < 2; ++c) {
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 7; ++col) {
        const bool inside = row >= 1 && row < 4 && col >= 2 && col < 6;
        EXPECT_EQ(whole.At(row, col, c), inside ? map.At(row, col, c) : -1.0f) << row << col;
      }
    }
  }
}

TEST(FloatMap, BoundingBoxAboveHoldsExactlyThePixelsAboveTheThreshold) {
  FloatMap mask(9, 6, 1, 0.0f);
  mask.At(1, 3) = 1.0f;
  mask.At(4, 7) = 0.6f;
  mask.At(2, 1) = 0.4f;  // above 0 but not above 0.5
  const PixelBox half = BoundingBoxAbove(mask, 0.5f);
  EXPECT_EQ(half.x0, 3);
  EXPECT_EQ(half.y0, 1);
  EXPECT_EQ(half.width, 5);
  EXPECT_EQ(half.height, 4);
  const PixelBox any = BoundingBoxAbove(mask, 0.0f);
  EXPECT_EQ(any.x0, 1);
  EXPECT_EQ(any.y0, 1);
  EXPECT_EQ(any.width, 7);
  EXPECT_EQ(any.height, 4);
  EXPECT_TRUE(BoundingBoxAbove(mask, 1.0f).Empty());
  EXPECT_TRUE(BoundingBoxAbove(FloatMap(), 0.0f).Empty());
}

// A map held as the box of its positive values comes back whole: the box's values as they
// were, +0 elsewhere (where the map held 0, -0 or negative values); one without positive
// values comes back as zeros of its size.
TEST(FloatMap, CroppedMapComesBackWholeWithZerosAround) {
  FloatMap map(8, 6, 1, 0.0f);
  map.At(1, 2) = 3.0f;
  map.At(4, 5) = 0.5f;
  map.At(2, 3) = -2.0f;  // inside the box: kept
  map.At(5, 7) = -1.0f;  // outside: +0
  map.At(0, 0) = -0.0f;
  const CroppedFloatMap cropped = CroppedFloatMap::AbovePositive(map);
  EXPECT_EQ(cropped.box.x0, 2);
  EXPECT_EQ(cropped.box.y0, 1);
  EXPECT_EQ(cropped.part.Width(), 4);
  EXPECT_EQ(cropped.part.Height(), 4);
  const FloatMap whole = cropped.Whole();
  ASSERT_EQ(whole.Width(), 8);
  ASSERT_EQ(whole.Height(), 6);
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 8; ++col) {
      const bool inside = row >= 1 && row < 5 && col >= 2 && col < 6;
      const float expected = inside ? map.At(row, col) : 0.0f;
      EXPECT_EQ(whole.At(row, col), expected) << row << " " << col;
      EXPECT_FALSE(std::signbit(whole.At(row, col)) && expected == 0.0f) << row << " " << col;
    }
  }
  const CroppedFloatMap none = CroppedFloatMap::AbovePositive(FloatMap(5, 3, 1, -1.0f));
  EXPECT_TRUE(none.box.Empty());
  EXPECT_EQ(none.Whole().Data(), std::vector<float>(15, 0.0f));
}

}  // namespace
}  // namespace hairmvs
