#include "src/core/logging.h"

#include <mutex>

namespace hairmvs {

void InitLogging(const char* argv0) {
  static std::once_flag once;
  std::call_once(once, [argv0] {
    FLAGS_logtostderr = true;
    FLAGS_colorlogtostderr = false;
    google::InitGoogleLogging(argv0 ? argv0 : "hairmvs");
  });
}

}  // namespace hairmvs
