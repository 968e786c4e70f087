#pragma once
// Progress lines for long work: which stage, which item of how many, time spent.
//   [orientation_stereo] view 3/32 g0_b.png: cost volume (12.4 s elapsed)

#include <string>

#include "src/core/timer.h"

namespace hairmvs {

class Progress {
 public:
  Progress(std::string task, int total);
  // Starts item `index` (0-based) and prints a line naming it.
  void Start(int index, const std::string& item);
  // A stage within the current item.
  void Stage(const std::string& stage);
  void Finish();
  double ElapsedSeconds() const { return timer_.ElapsedSeconds(); }
  // The current item and stage, "g0_b.png: cost volume", for an error raised within them.
  std::string Where() const { return stage_.empty() ? item_ : item_ + ": " + stage_; }

 private:
  std::string task_;
  int total_ = 0;
  int index_ = 0;
  std::string item_;
  std::string stage_;
  Timer timer_;
};

}  // namespace hairmvs
