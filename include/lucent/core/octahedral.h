// Unit vectors in 32 bits by the octahedral mapping (two 16-bit coordinates).
#pragma once
#include <cmath>
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

inline uint32_t encodeOctahedral(Vec3 v) {
  const float l1 = std::abs(v.x) + std::abs(v.y) + std::abs(v.z);
  float x = v.x / l1, y = v.y / l1;
  if (v.z < 0) {
    const float ox = (1 - std::abs(y)) * std::copysign(1.0f, x);
    const float oy = (1 - std::abs(x)) * std::copysign(1.0f, y);
    x = ox;
    y = oy;
  }
  auto quantize = [](float f) { return uint32_t(std::lround((std::clamp(f, -1.0f, 1.0f) * 0.5f + 0.5f) * 65535.0f)); };
  return quantize(x) | quantize(y) << 16;
}

// The encoded direction, not normalized (its sign against any vector is the unit vector's).
inline Vec3 octahedralDirection(uint32_t e) {
  constexpr float kScale = 2.0f / 65535.0f;
  const float x = float(e & 0xffff) * kScale - 1, y = float(e >> 16) * kScale - 1;
  // The lower hemisphere is folded over the diagonals: x -> sign(x) (1 - |y|), written without a
  // branch (a photon map's search decodes photons arriving from either side, in random order).
  const float z = 1 - std::abs(x) - std::abs(y), fold = std::max(-z, 0.0f);
  return {x - std::copysign(fold, x), y - std::copysign(fold, y), z};
}

inline Vec3 decodeOctahedral(uint32_t e) { return normalize(octahedralDirection(e)); }

}  // namespace lucent
