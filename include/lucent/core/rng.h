// Deterministic random numbers. Every work item seeds its own generator from a key such as
// (seed, pixel, sample) or (seed, photon index), so results do not depend on the thread schedule.
#pragma once
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

// SplitMix64 finaliser: a bijective 64-bit mix with full avalanche.
constexpr uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// A bijective 32-bit mix with full avalanche (Wellons's lowbias32): 32-bit multiplies, native in
// SIMD lanes where 64-bit ones are not.
constexpr uint32_t mix32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  return x ^ (x >> 16);
}

constexpr uint64_t hashKey(uint64_t a, uint64_t b = 0, uint64_t c = 0) {
  return mix64(a + 0x9e3779b97f4a7c15ull * mix64(b + 0x632be59bd9b4e019ull * mix64(c + 1)));
}

// Uniform integer in [0, n) from 32 random bits by Lemire's multiply-shift (bias below 2^-32 * n).
constexpr uint32_t uniformBelow(uint32_t bits, uint32_t n) { return static_cast<uint32_t>((uint64_t(bits) * n) >> 32); }

// PCG32 (O'Neill 2014, XSH-RR output) with the stream chosen by the key.
class Rng {
 public:
  Rng() = default;  // a placeholder until a keyed generator is assigned
  explicit Rng(uint64_t seed, uint64_t a = 0, uint64_t b = 0) {
    const uint64_t key = hashKey(seed, a, b);
    inc_ = (mix64(key ^ 0xda3e39cb94b95bdbull) << 1u) | 1u;
    state_ = 0;
    next();
    state_ += key;
    next();
  }
  uint32_t next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  // Uniform in [0, 1): 24 random mantissa bits, so 1 is never returned.
  float uniform() { return static_cast<float>(next() >> 8) * 0x1p-24f; }
  Vec2 uniform2() {
    const float a = uniform();
    return {a, uniform()};
  }
  uint32_t below(uint32_t n) { return uniformBelow(next(), n); }

 private:
  uint64_t state_ = 0;
  uint64_t inc_ = 1;
};

}  // namespace lucent
