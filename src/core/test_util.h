#pragma once
// Test helpers of the lowest layer (header-only): what every layer's tests use.
// colmap_ext/test_util.h adds the workspace and model helpers on top.

#include <string>

#include "src/core/logging.h"

namespace hairmvs {
namespace testing_util {

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

}  // namespace testing_util
}  // namespace hairmvs
