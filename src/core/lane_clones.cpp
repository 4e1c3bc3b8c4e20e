#include "lucent/core/lane_clones.h"

#include <atomic>
#include <stdexcept>

namespace lucent {

namespace {

// What GCC's x86-64-v4 level needs of AVX-512 (F, BW, CD, DQ, VL), and AVX2 with what the
// AVX2 versions may be compiled to use.
bool runs(LaneIsa isa) {
  __builtin_cpu_init();
  switch (isa) {
    case LaneIsa::Baseline: return true;
    case LaneIsa::Avx2: return __builtin_cpu_supports("avx2");
    case LaneIsa::Avx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
             __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl");
  }
  return false;
}

LaneIsa best() {
  for (LaneIsa isa : {LaneIsa::Avx512, LaneIsa::Avx2})
    if (runs(isa)) return isa;
  return LaneIsa::Baseline;
}

std::atomic<LaneIsa>& current() {
  static std::atomic<LaneIsa> isa{best()};
  return isa;
}

}  // namespace

LaneIsa laneIsa() { return current().load(std::memory_order_relaxed); }

void setLaneIsa(LaneIsa isa) {
  if (!runs(isa)) throw std::invalid_argument(std::string("this CPU does not run the ") + laneIsaName(isa) + " lane loops");
  current().store(isa, std::memory_order_relaxed);
}

std::vector<LaneIsa> supportedLaneIsas() {
  std::vector<LaneIsa> isas;
  for (LaneIsa isa : {LaneIsa::Baseline, LaneIsa::Avx2, LaneIsa::Avx512})
    if (runs(isa)) isas.push_back(isa);
  return isas;
}

const char* laneIsaName(LaneIsa isa) {
  switch (isa) {
    case LaneIsa::Baseline: return "baseline";
    case LaneIsa::Avx2: return "avx2";
    case LaneIsa::Avx512: return "avx512";
  }
  return "?";
}

}  // namespace lucent
