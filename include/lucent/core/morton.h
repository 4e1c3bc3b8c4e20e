// 3-D Morton (Z-order) codes: points that are near in space get near codes, so that work sorted by
// them touches memory and the scene's BVH coherently.
#pragma once
#include <algorithm>
#include <cmath>
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

// Where a point facing `normal` goes in an order of work: first the axis and side its normal faces
// most (six classes), then the Morton code of its position (33 bits). Neighbours facing alike share
// more of the scene they see than neighbours across an edge (a column's side and the floor in
// front of it).
inline uint64_t facingMortonKey(Vec3 position, Vec3 normal, const Bounds3& bounds) {
  const Vec3 a{std::abs(normal.x), std::abs(normal.y), std::abs(normal.z)};
  const int axis = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
  const uint64_t facing = uint64_t(2 * axis + (normal[axis] < 0 ? 1 : 0));
  return facing << 30 | mortonCode(position, bounds);
}

}  // namespace lucent
