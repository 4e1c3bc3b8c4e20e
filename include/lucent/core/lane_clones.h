// Loops over lanes that GCC vectorizes are compiled in three versions, and the one for the CPU is
// picked at run time: AVX-512 (x86-64-v4: sixteen floats per instruction, and 64-bit multiplies),
// AVX2, and the baseline. All three compute the same IEEE operations (no FMA contraction:
// -ffp-contract=off in CMakeLists.txt), so results do not depend on the CPU. (GCC 12 takes arch=
// in target_clones; Debian bookworm's compiler is GCC 12.)
#pragma once

// A build for one of the two clones that this machine would not pick (CMake's LUCENT_LANE_TARGET,
// scripts/check-lane-clones.sh) compiles that clone alone.
#if defined(LUCENT_LANES_AVX2_ONLY)
#define LUCENT_LANE_CLONES __attribute__((target("avx2")))
#elif defined(LUCENT_LANES_BASELINE_ONLY)
#define LUCENT_LANE_CLONES
#else
#define LUCENT_LANE_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#endif
