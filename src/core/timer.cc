#include "src/core/timer.h"

#include <cstdio>
#include <fstream>
#include <sstream>

namespace hairmvs {

void StageTimings::Add(const std::string& stage, double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (seconds_.find(stage) == seconds_.end()) order_.push_back(stage);
  seconds_[stage] += seconds;
  calls_[stage] += 1;
}

void StageTimings::Merge(const StageTimings& other) {
  std::vector<std::string> stages;
  std::map<std::string, double> seconds;
  std::map<std::string, int> calls;
  {
    std::lock_guard<std::mutex> lock(other.mutex_);
    stages = other.order_;
    seconds = other.seconds_;
    calls = other.calls_;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  for (const std::string& stage : stages) {
    if (seconds_.find(stage) == seconds_.end()) order_.push_back(stage);
    seconds_[stage] += seconds[stage];
    calls_[stage] += calls[stage];
  }
}

double StageTimings::Total() const {
  std::lock_guard<std::mutex> lock(mutex_);
  double total = 0;
  for (const auto& kv : seconds_) total += kv.second;
  return total;
}

double StageTimings::Get(const std::string& stage) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = seconds_.find(stage);
  return it == seconds_.end() ? 0.0 : it->second;
}

std::string StageTimings::Table(const std::string& title) const {
  const double total = Total();
  std::lock_guard<std::mutex> lock(mutex_);
  std::ostringstream out;
  out << title << "\n";
  char line[256];
  std::snprintf(line, sizeof(line), "  %-28s %10s %7s %7s\n", "stage", "seconds", "calls", "share");
  out << line;
  for (const std::string& stage : order_) {
    const double s = seconds_.at(stage);
    std::snprintf(line, sizeof(line), "  %-28s %10.3f %7d %6.1f%%\n", stage.c_str(), s,
                  calls_.at(stage), total > 0 ? 100.0 * s / total : 0.0);
    out << line;
  }
  std::snprintf(line, sizeof(line), "  %-28s %10.3f\n", "total", total);
  out << line;
  return out.str();
}

std::string RunSummary(const StageTimings& timings, const std::string& title) {
  char line[64];
  std::snprintf(line, sizeof(line), "Peak resident memory: %.1f MiB\n", PeakResidentMemoryMiB());
  return timings.Table(title) + line;
}

double PeakResidentMemoryMiB() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmHWM:") {
      double kib = 0;
      status >> kib;
      return kib / 1024.0;
    }
    std::string rest;
    std::getline(status, rest);
  }
  return 0.0;
}

}  // namespace hairmvs
