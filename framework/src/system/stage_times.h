// Mean wall time per call of each stage of the estimator (Odometry::stageMs(), report.json's stage_ms).
// Part of the run record (run_record.h); ScopedStage times one call of a stage.
#pragma once
#include <chrono>
#include <map>
#include <string>
#include <utility>

namespace rsvio {

class StageTimes {
 public:
  void add(const std::string& stage, double ms) {
    auto& s = stages_[stage];
    s.first += ms;
    s.second += 1;
  }
  std::map<std::string, double> means() const {
    std::map<std::string, double> out;
    for (const auto& [k, v] : stages_) out[k] = v.second > 0 ? v.first / static_cast<double>(v.second) : 0.0;
    return out;
  }

 private:
  std::map<std::string, std::pair<double, long>> stages_;  // total ms, calls
};

class ScopedStage {
 public:
  ScopedStage(StageTimes& t, const char* stage) : t_(t), stage_(stage), t0_(std::chrono::steady_clock::now()) {}
  ~ScopedStage() {
    t_.add(stage_, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count());
  }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageTimes& t_;
  const char* stage_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace rsvio
