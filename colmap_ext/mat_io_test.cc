#include "colmap_ext/mat_io.h"

#include <gtest/gtest.h>

#include <sstream>

#include "src/core/logging.h"

namespace hairmvs {
namespace {

TEST(MatIo, PlanarLayoutAndRoundTrip) {
  FloatMap map(3, 2, 2);
  for (size_t i = 0; i < map.Data().size(); ++i) map.Data()[i] = static_cast<float>(i) * 0.5f;
  std::stringstream ss;
  WriteMat(ss, map);
  const std::string bytes = ss.str();
  EXPECT_EQ(bytes.substr(0, 6), "3&2&2&");
  EXPECT_EQ(bytes.size(), 6u + 12 * 4);
  // Element (row 1, col 2, channel 1) sits at float index 1*6 + 1*3 + 2 = 11.
  float value = 0;
  std::memcpy(&value, bytes.data() + 6 + 11 * 4, 4);
  EXPECT_EQ(value, map.At(1, 2, 1));
  const FloatMap read = ReadMat(ss, "mem");
  EXPECT_EQ(read.Width(), 3);
  EXPECT_EQ(read.Height(), 2);
  EXPECT_EQ(read.Channels(), 2);
  EXPECT_EQ(read.Data(), map.Data());
}

TEST(MatIo, BadInput) {
  FloatMap map(4, 4, 1, 1.0f);
  std::stringstream ss;
  WriteMat(ss, map);
  const std::string bytes = ss.str();
  std::istringstream truncated(bytes.substr(0, bytes.size() - 1));
  EXPECT_THROW(ReadMat(truncated, "d.bin"), Error);
  std::istringstream oversized(bytes + "x");
  EXPECT_THROW(ReadMat(oversized, "d.bin"), Error);
  std::istringstream header("4&4&");
  EXPECT_THROW(ReadMat(header, "d.bin"), Error);
  std::istringstream zero("0&4&1&");
  EXPECT_THROW(ReadMat(zero, "d.bin"), Error);
  EXPECT_THROW(ReadMat("/nonexistent/d.bin"), Error);
}

}  // namespace
}  // namespace hairmvs
