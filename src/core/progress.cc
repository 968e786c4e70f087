#include "src/core/progress.h"

#include <cstdio>

namespace hairmvs {

Progress::Progress(std::string task, int total) : task_(std::move(task)), total_(total) {}

void Progress::Start(int index, const std::string& item) {
  index_ = index;
  item_ = item;
  stage_.clear();
  std::fprintf(stderr, "[%s] %d/%d %s (%.1f s elapsed)\n", task_.c_str(), index + 1, total_,
               item.c_str(), timer_.ElapsedSeconds());
}

void Progress::Stage(const std::string& stage) {
  stage_ = stage;
  std::fprintf(stderr, "[%s] %d/%d %s: %s (%.1f s elapsed)\n", task_.c_str(), index_ + 1,
               total_, item_.c_str(), stage.c_str(), timer_.ElapsedSeconds());
}

void Progress::Finish() {
  std::fprintf(stderr, "[%s] done: %d item(s) in %.1f s\n", task_.c_str(), total_,
               timer_.ElapsedSeconds());
}

}  // namespace hairmvs
