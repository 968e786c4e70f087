#include "src/core/file_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "src/core/logging.h"

namespace hairmvs {
namespace {

std::string TestDir(const std::string& name) {
  const std::string dir = JoinPaths(::testing::TempDir(), "hairmvs_core_" + name);
  std::filesystem::remove_all(dir);
  CreateDirs(dir);
  return dir;
}

TEST(FileUtil, AtomicWriteReplacesOnlyWhenComplete) {
  const std::string dir = TestDir("atomic");
  const std::string path = JoinPaths(dir, "sub", "file.txt");
  WriteFileAtomically(path, [](std::ostream& out) { out << "first"; });
  EXPECT_EQ(ReadTextFile(path), "first");
  // A writer that fails half-way leaves the old content and no temporary file behind.
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](std::ostream& out) {
                                     out << "half";
                                     throw std::runtime_error("interrupted");
                                   }),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(path), "first");
  int num_files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(ParentPath(path))) {
    (void)entry;
    ++num_files;
  }
  EXPECT_EQ(num_files, 1);
}

TEST(FileUtil, MissingFileErrorNamesThePath) {
  try {
    RequireFile("/nonexistent/hairmvs/cameras.bin", "camera file");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/hairmvs/cameras.bin"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("camera file"), std::string::npos);
  }
}

TEST(FileUtil, SplitAndStrip) {
  EXPECT_EQ(StripWhitespace("  a b \r\n"), "a b");
  const auto parts = SplitString("a, b;c", ",;");
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_EQ(StripWhitespace(parts[1]), "b");
  EXPECT_EQ(parts[2], "c");
}

}  // namespace
}  // namespace hairmvs
