#pragma once
// Test helpers of the lowest layer (header-only): what every layer's tests use: the message of
// an error, the entries of a folder, a file size limit that makes writes fail as on a full disk.
// colmap_ext/test_util.h adds the workspace and model helpers on top.

#include <sys/resource.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <string>

#include "src/core/logging.h"

namespace hairmvs {
namespace testing_util {

// A fresh, empty folder for a test, <build folder>/test_tmp/hairmvs_<name> (HAIRMVS_BINARY_DIR
// is defined for every hairmvs_add_test target): the tests' one way to make one. A test's next
// run replaces it, so runs leave one copy at most; two checkouts' suites run at once have their
// own build folders, so they do not share the folders.
inline std::string MakeTestDir(const std::string& name) {
  const std::filesystem::path root = std::filesystem::path(HAIRMVS_BINARY_DIR) / "test_tmp";
  const std::string dir = (root / ("hairmvs_" + name)).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The message of the hairmvs::Error that f() throws; "(no error)" when it throws none.
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// How many entries `dir` holds (files, folders, hidden temporaries): what an atomic write
// leaves behind.
inline int NumEntriesIn(const std::string& dir) {
  int num_entries = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    (void)entry;
    ++num_entries;
  }
  return num_entries;
}

// While it lives, a file that would grow past `max_bytes` fails to write (EFBIG), as on a full
// disk: the soft RLIMIT_FSIZE, with SIGXFSZ ignored so that the write fails instead of the
// signal ending the process. For tests of what a write failing half-way leaves behind.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t max_bytes) {
    getrlimit(RLIMIT_FSIZE, &previous_limit_);
    rlimit limit = previous_limit_;
    limit.rlim_cur = std::min(max_bytes, limit.rlim_max);  // RLIM_INFINITY is the largest
    previous_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &previous_limit_);
    std::signal(SIGXFSZ, previous_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit previous_limit_{};
  void (*previous_handler_)(int) = SIG_DFL;
};

}  // namespace testing_util
}  // namespace hairmvs
