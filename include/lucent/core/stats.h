// Per-stage timings and counters that every method reports (DESIGN.md "Kernels and data layout").
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace lucent {

struct RenderStats {
  std::vector<std::pair<std::string, double>> stageSeconds;
  std::vector<std::pair<std::string, uint64_t>> counters;
  // Values a method chose from the scene where an option left the choice to it (an option of 0
  // for "auto": the maximum search radius, the point count), so that a render can be repeated.
  std::vector<std::pair<std::string, double>> derived;
  void addStage(const std::string& name, double seconds) { stageSeconds.emplace_back(name, seconds); }
  void addCounter(const std::string& name, uint64_t value) { counters.emplace_back(name, value); }
  void addDerived(const std::string& name, double value) { derived.emplace_back(name, value); }
  // The stages of `parts` (a stage timed once per band of a frame, say), each name once, with the
  // seconds of its entries summed, in the order the names first appear.
  void addStagesSummed(const RenderStats& parts) {
    for (size_t i = 0; i < parts.stageSeconds.size(); ++i) {
      const std::string& name = parts.stageSeconds[i].first;
      bool seen = false;
      for (size_t j = 0; j < i && !seen; ++j) seen = parts.stageSeconds[j].first == name;
      if (seen) continue;
      double sum = 0;
      for (size_t j = i; j < parts.stageSeconds.size(); ++j)
        if (parts.stageSeconds[j].first == name) sum += parts.stageSeconds[j].second;
      addStage(name, sum);
    }
  }
  // A counter's value, 0 if there is none of that name.
  uint64_t counter(const std::string& name) const {
    for (const auto& [key, value] : counters)
      if (key == name) return value;
    return 0;
  }
  double totalSeconds() const {
    double s = 0;
    for (const auto& st : stageSeconds) s += st.second;
    return s;
  }
};

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Told of each stage as it starts (lucent render --log-stages), from the thread that starts it.
// Set once, before a render; null: nobody.
void setStageObserver(std::function<void(const std::string& stage)> observer);
// A stage starts: a point where the render may stop (stopPoint, core/stop.h), then announced.
void beginStage(const std::string& stage);

// A stage of a render from construction to destruction: begun (beginStage), and its seconds added
// to `stats` as `name` at the end (also when a stop unwinds it).
class StageTimer {
 public:
  StageTimer(RenderStats& stats, std::string name);
  ~StageTimer() { stats_.addStage(name_, clock_.seconds()); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  RenderStats& stats_;
  std::string name_;
  Stopwatch clock_;
};

}  // namespace lucent
