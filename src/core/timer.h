#pragma once
// Wall-clock timing of stages, and the per-stage summary that long commands end with.

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace hairmvs {

class Timer {
 public:
  Timer() { Restart(); }
  void Restart() { start_ = std::chrono::steady_clock::now(); }
  double ElapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Accumulates seconds per named stage, in first-seen order. Thread-safe.
class StageTimings {
 public:
  void Add(const std::string& stage, double seconds);
  void Merge(const StageTimings& other);
  double Total() const;
  double Get(const std::string& stage) const;
  const std::vector<std::string>& Stages() const { return order_; }
  // A table: stage, seconds, calls, share of the total.
  std::string Table(const std::string& title = "Timing per stage") const;

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> order_;
  std::map<std::string, double> seconds_;
  std::map<std::string, int> calls_;
};

// Adds the time from construction to destruction to a stage of `timings`.
class ScopedStageTimer {
 public:
  ScopedStageTimer(StageTimings* timings, std::string stage)
      : timings_(timings), stage_(std::move(stage)) {}
  ~ScopedStageTimer() {
    if (timings_ != nullptr) timings_->Add(stage_, timer_.ElapsedSeconds());
  }

 private:
  StageTimings* timings_;
  std::string stage_;
  Timer timer_;
};

// Splits consecutive stages' time among them: Lap("read") adds the seconds since the previous
// Lap (or construction) to stage "read" of `timings` (nothing when it is null).
class StageLaps {
 public:
  explicit StageLaps(StageTimings* timings) : timings_(timings) {}
  void Lap(const std::string& stage) {
    if (timings_ != nullptr) timings_->Add(stage, timer_.ElapsedSeconds());
    timer_.Restart();
  }

 private:
  StageTimings* timings_;
  Timer timer_;
};

// Peak resident memory of this process in MiB (from /proc/self/status VmHWM).
double PeakResidentMemoryMiB();
// How a long command ends: the table of `timings` under `title`, then the line
// "Peak resident memory: <MiB> MiB" (which scripts/evaluate_stereo.sh reads).
std::string RunSummary(const StageTimings& timings, const std::string& title = "Timing per stage");

}  // namespace hairmvs
