#include "lucent/core/stats.h"

#include "lucent/core/stop.h"

namespace lucent {

namespace {
std::function<void(const std::string&)>& stageObserver() {
  static std::function<void(const std::string&)> observer;
  return observer;
}
}  // namespace

void setStageObserver(std::function<void(const std::string& stage)> observer) { stageObserver() = std::move(observer); }

void beginStage(const std::string& stage) {
  stopPoint();
  if (stageObserver()) stageObserver()(stage);
}

StageTimer::StageTimer(RenderStats& stats, std::string name) : stats_(stats), name_(std::move(name)) {
  beginStage(name_);
  clock_ = Stopwatch();
}

}  // namespace lucent
