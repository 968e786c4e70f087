#include "colmap_ext/mat_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "colmap_ext/test_util.h"
#include "src/core/file_util.h"
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

// An infinite depth or a NaN normal is refused, naming the file, the pixel and the channel.
TEST(MatIo, NonFiniteValuesAreRefused) {
  for (const float bad : {std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity(),
                          std::numeric_limits<float>::quiet_NaN()}) {
    FloatMap map(3, 2, 2, 0.5f);
    map.At(1, 2, 1) = bad;  // row 1, column 2, channel 1
    std::stringstream ss;
    WriteMat(ss, map);
    const std::string error = testing_util::ErrorOf([&] { ReadMat(ss, "n.bin"); });
    EXPECT_NE(error.find("n.bin: Mat file holds a non-finite value"), std::string::npos) << error;
    EXPECT_NE(error.find("at pixel (2, 1), channel 1"), std::string::npos) << error;
  }
}

// ReadMatShape reads the header alone and fails, as ReadMat does, on a file of the wrong size.
TEST(MatIo, ShapeFromTheHeaderCheckedAgainstTheFileSize) {
  const std::string dir = testing_util::MakeTestDir("mat_shape");
  const std::string path = JoinPaths(dir, "o.bin");
  WriteMat(path, FloatMap(5, 3, 2, 0.5f));
  const MatShape shape = ReadMatShape(path);
  EXPECT_EQ(shape.width, 5);
  EXPECT_EQ(shape.height, 3);
  EXPECT_EQ(shape.channels, 2);
  const std::string bytes = ReadTextFile(path);
  for (const std::string& bad : {bytes.substr(0, bytes.size() - 1), bytes + "x"}) {
    WriteFileAtomically(path, [&](std::ostream& out) { out << bad; });
    const std::string shape_error = testing_util::ErrorOf([&] { ReadMatShape(path); });
    EXPECT_EQ(shape_error, testing_util::ErrorOf([&] { ReadMat(path); }));
    EXPECT_NE(shape_error, "(no error)");
  }
  EXPECT_NE(testing_util::ErrorOf([] { ReadMatShape("/nonexistent/o.bin"); }), "(no error)");
}

// A corrupt header in a short file is a truncated file named by its path, found from the file's
// size before the 57.6 TB the header announces are allocated.
TEST(MatIo, ShortFileWithAHugeHeaderIsTruncated) {
  const std::string dir = testing_util::MakeTestDir("mat_huge_header");
  const std::string path = JoinPaths(dir, "d.bin");
  const std::string bytes = "60000&60000&4000&" + std::string(13, '\0');
  ASSERT_EQ(bytes.size(), 30u);
  WriteFileAtomically(path, [&](std::ostream& out) { out << bytes; });
  const std::string message = testing_util::ErrorOf([&] { ReadMat(path); });
  EXPECT_EQ(message.rfind(path + ": truncated Mat file", 0), 0u) << message;
  EXPECT_NE(message.find("found 13"), std::string::npos) << message;
}

// The Mat and its depths are one unit: depths that cannot be written (the disk full) leave the
// old Mat, not a new one beside depths of another number of labels.
TEST(MatIo, FailedDepthsLeaveTheOldCostVolume) {
  const std::string dir = testing_util::MakeTestDir("cost_volume_unit");
  const std::string path = JoinPaths(dir, "v.coarse.bin");
  const std::string depths = JoinPaths(dir, "v.coarse.depths.txt");
  CostVolume old_volume;
  old_volume.cost = FloatMap(1, 1, 2, 1.0f);
  old_volume.label_depths = {0.5, 0.6};
  WriteCostVolume(path, depths, old_volume);
  const std::string old_mat = ReadTextFile(path), old_depths = ReadTextFile(depths);
  // 400 labels: a Mat of 1.6 kB and depths of 11 bytes each, 4.5 kB.
  CostVolume volume;
  volume.cost = FloatMap(1, 1, 400, 0.5f);
  for (int k = 0; k < 400; ++k) volume.label_depths.push_back(1 + std::sqrt(k + 2.0) / 100);
  {
    const testing_util::FileSizeLimit disk_full(3000);
    const std::string message =
        testing_util::ErrorOf([&] { WriteCostVolume(path, depths, volume); });
    EXPECT_NE(message.find(depths), std::string::npos) << message;
  }
  EXPECT_TRUE(ReadTextFile(path) == old_mat) << "the Mat was replaced";
  EXPECT_EQ(ReadTextFile(depths), old_depths);
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 2);
}

TEST(MatIo, CostVolumeRoundTripAndBadDepths) {
  const std::string dir = testing_util::MakeTestDir("cost_volume_io");
  CostVolume volume;
  volume.cost = FloatMap(4, 3, 200);  // more labels than image channels ever have
  for (size_t i = 0; i < volume.cost.Data().size(); ++i) volume.cost.Data()[i] = 0.25f * i;
  for (int k = 0; k < 200; ++k) volume.label_depths.push_back(0.4 + 0.001 * k);
  const std::string path = JoinPaths(dir, "v.coarse.bin");
  const std::string depths = JoinPaths(dir, "v.coarse.depths.txt");
  WriteCostVolume(path, depths, volume);
  const CostVolume read = ReadCostVolume(path, depths);
  EXPECT_EQ(read.cost.Channels(), 200);
  EXPECT_EQ(read.cost.Data(), volume.cost.Data());
  ASSERT_EQ(read.label_depths.size(), 200u);
  for (int k = 0; k < 200; ++k) EXPECT_NEAR(read.label_depths[k], volume.label_depths[k], 1e-9);

  auto expect_error = [&](const std::string& text, const std::string& what) {
    std::ofstream(depths) << text;
    try {
      ReadCostVolume(path, depths);
      ADD_FAILURE() << "no error for " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(depths), std::string::npos) << e.what();
    }
  };
  expect_error("0.5\n0.6\n", "too few depths");
  expect_error("0.5\nfar\n", "a word");
  expect_error("-0.5\n", "a negative depth");
  std::string labels;
  for (int k = 0; k < 199; ++k) labels += std::to_string(0.4 + 0.001 * k) + "\n";
  expect_error(labels + "inf\n", "an infinite depth");
  expect_error(labels + std::to_string(0.4 + 0.001 * 198) + "\n", "a repeated depth");
  expect_error(labels + "0.5\n", "a depth against the order");
  std::filesystem::remove(depths);
  EXPECT_THROW(ReadCostVolume(path, depths), Error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hairmvs
