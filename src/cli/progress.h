// A progress bar on stderr, shown only when stderr is a terminal; safe to call from any thread.
#pragma once
#include <unistd.h>

#include <cstdio>
#include <mutex>

#include "lucent/core/stats.h"

namespace lucent::cli {

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}
  ~ProgressBar() { finish(); }
  void update(double fraction) {
    if (!enabled_) return;
    std::lock_guard lock(mutex_);
    const double now = clock_.seconds();
    if (now - lastDraw_ < 0.1 && fraction < 1.0) return;
    lastDraw_ = now;
    const int width = 40, filled = static_cast<int>(fraction * width);
    std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  %.1f s", filled, "========================================",
                 width - filled, "", 100.0 * fraction, now);
    std::fflush(stderr);
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  std::mutex mutex_;
  Stopwatch clock_;
  double lastDraw_ = -1;
};

}  // namespace lucent::cli
