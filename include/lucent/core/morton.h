// 3-D Morton (Z-order) codes: points that are near in space get near codes, so that work sorted by
// them touches memory and the scene's BVH coherently.
#pragma once
#include <algorithm>
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

// 30-bit 3-D Morton code of a point in `bounds` (10 bits per axis).
inline uint32_t mortonCode(Vec3 p, const Bounds3& bounds) {
  auto spread = [](uint32_t v) {
    v = (v | (v << 16)) & 0x030000ffu;
    v = (v | (v << 8)) & 0x0300f00fu;
    v = (v | (v << 4)) & 0x030c30c3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
  };
  const Vec3 e = bounds.extent();
  uint32_t code = 0;
  for (int a = 0; a < 3; ++a) {
    const float t = e[a] > 0 ? (p[a] - bounds.lo[a]) / e[a] : 0.0f;
    // Outside the bounds, the nearest face; a NaN coordinate, the lowest.
    code |= spread(uint32_t((t >= 0.0f ? std::min(t, 1.0f) : 0.0f) * 1023.0f)) << a;
  }
  return code;
}

}  // namespace lucent
