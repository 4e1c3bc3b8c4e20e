// Unit vectors by the octahedral mapping: in 32 bits (two 16-bit coordinates), or in 20 (two
// 10-bit coordinates, within half a degree) where a record has fewer bits to spare.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

// The octahedral coordinates of v, in [-1, 1] each.
inline Vec2 octahedralCoordinates(Vec3 v) {
  const float l1 = std::abs(v.x) + std::abs(v.y) + std::abs(v.z);
  float x = v.x / l1, y = v.y / l1;
  if (v.z < 0) {
    const float ox = (1 - std::abs(y)) * std::copysign(1.0f, x);
    const float oy = (1 - std::abs(x)) * std::copysign(1.0f, y);
    x = ox;
    y = oy;
  }
  return {x, y};
}

// The octahedral coordinates quantized to Bits bits each: x in the low bits, y above.
template <int Bits = 16>
uint32_t encodeOctahedral(Vec3 v) {
  constexpr float kSteps = float((1u << Bits) - 1);
  const Vec2 c = octahedralCoordinates(v);
  auto quantize = [&](float f) { return uint32_t(std::lround((std::clamp(f, -1.0f, 1.0f) * 0.5f + 0.5f) * kSteps)); };
  return quantize(c.x) | quantize(c.y) << Bits;
}

// The encoded direction, not normalized (its sign against any vector is the unit vector's).
template <int Bits = 16>
Vec3 octahedralDirection(uint32_t e) {
  constexpr uint32_t kMask = (1u << Bits) - 1;
  constexpr float kScale = 2.0f / float(kMask);
  const float x = float(e & kMask) * kScale - 1, y = float((e >> Bits) & kMask) * kScale - 1;
  // The lower hemisphere is folded over the diagonals: x -> sign(x) (1 - |y|), written without a
  // branch (a photon map's search decodes photons arriving from either side, in random order).
  const float z = 1 - std::abs(x) - std::abs(y), fold = std::max(-z, 0.0f);
  return {x - std::copysign(fold, x), y - std::copysign(fold, y), z};
}

template <int Bits = 16>
Vec3 decodeOctahedral(uint32_t e) {
  return normalize(octahedralDirection<Bits>(e));
}

}  // namespace lucent
