// Loops over lanes that GCC vectorizes are compiled in three versions: AVX-512 (x86-64-v4: sixteen
// floats per instruction, and 64-bit multiplies), AVX2, and the baseline. All three compute the
// same IEEE operations (no FMA contraction: -ffp-contract=off), so results do not depend on the
// CPU. The version that runs is the best this CPU supports, or the one setLaneIsa chose: a test or
// a render (--isa) can run every version this CPU can, and so check that they agree.
#pragma once
#include <string>
#include <vector>

namespace lucent {

enum class LaneIsa { Baseline, Avx2, Avx512 };

// The versions of the lane loops that run now.
LaneIsa laneIsa();
// Runs `isa`'s versions from now on, in every thread; throws std::invalid_argument when this CPU
// cannot run them.
void setLaneIsa(LaneIsa isa);
// The versions this CPU runs, baseline first.
std::vector<LaneIsa> supportedLaneIsas();
const char* laneIsaName(LaneIsa isa);

}  // namespace lucent

// A lane loop in three versions, selected by laneIsa() at each call: the body, then the versions.
//
//   LUCENT_LANE_LOOP(void, shadeDiffuseLanes, (SurfaceLanes& l)) {
//     for (uint32_t k = 0; k < l.count; ++k) ...
//   }
//   LUCENT_LANE_VERSIONS(void, shadeDiffuseLanes, (SurfaceLanes& l), (l))
//
// The body is name##Loop, forced inline into a function per instruction set (a baseline function
// may be inlined into an AVX2 or AVX-512 one, which then vectorizes it for its target); `name`
// calls the one laneIsa() names. The versions are kept out of interprocedural analysis (noipa):
// GCC 12's modref summarized a target-attributed version as free of side effects and dropped the
// calls to it. Clang has no noipa; noinline keeps its versions apart.
#if defined(__clang__)
#define LUCENT_LANE_NO_IPA noinline
#else
#define LUCENT_LANE_NO_IPA noipa
#endif
#define LUCENT_LANE_LOOP(ret, name, params) [[gnu::always_inline]] inline ret name##Loop params

#define LUCENT_LANE_VERSIONS(ret, name, params, args)                                                          \
  __attribute__((target("arch=x86-64-v4"), LUCENT_LANE_NO_IPA)) static ret name##Avx512 params {               \
    return name##Loop args;                                                                                    \
  }                                                                                                            \
  __attribute__((target("avx2"), LUCENT_LANE_NO_IPA)) static ret name##Avx2 params { return name##Loop args; } \
  __attribute__((LUCENT_LANE_NO_IPA)) static ret name##Baseline params { return name##Loop args; }             \
  ret name params {                                                                                            \
    switch (::lucent::laneIsa()) {                                                                             \
      case ::lucent::LaneIsa::Avx512: return name##Avx512 args;                                                \
      case ::lucent::LaneIsa::Avx2: return name##Avx2 args;                                                    \
      default: return name##Baseline args;                                                                     \
    }                                                                                                          \
  }
