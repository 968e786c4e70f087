#pragma once
// Logging and the three kinds of failure (style.md):
//   - an internal invariant aborts: CHECK / CHECK_EQ ... from glog;
//   - bad input at the API throws hairmvs::Error with a message naming the file or option
//     (THROW_IF / HAIRMVS_THROW below);
//   - option validation returns a message (Options::Check(std::string*)).

#include <glog/logging.h>

#include <sstream>
#include <stdexcept>
#include <string>

namespace hairmvs {

// Bad input: a missing or malformed file, an unknown camera model, an empty mask...
// The CLI prints what() and exits non-zero.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Initialises glog once for a process (stderr, no log files).
void InitLogging(const char* argv0);

}  // namespace hairmvs

#define HAIRMVS_THROW(stream_expr)          \
  do {                                      \
    std::ostringstream hairmvs_throw_oss_;  \
    hairmvs_throw_oss_ << stream_expr;      \
    throw ::hairmvs::Error(hairmvs_throw_oss_.str()); \
  } while (0)

#define THROW_IF(condition, stream_expr) \
  do {                                   \
    if (condition) HAIRMVS_THROW(stream_expr); \
  } while (0)
