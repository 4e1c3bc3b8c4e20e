// Radiance per node of the point hierarchy, in a separate array (Ritschel et al. 2009, 3.1): float
// RGB to compute with, half floats as the paper stores it next to the packed nodes. The pull step
// (Section 4, radiosity and photon-map lighting) fills interior nodes from their children.
#pragma once
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/techniques/technique_kinds.h"

namespace lucent {

struct PointHierarchy;

// IEEE 754 binary16, round to nearest even; beyond 65504 rounds to infinity.
inline uint16_t floatToHalf(float f) {
  const uint32_t x = std::bit_cast<uint32_t>(f);
  const uint32_t sign = (x >> 16) & 0x8000u;
  const uint32_t a = x & 0x7fffffffu;
  if (a >= 0x7f800000u) return uint16_t(sign | (a > 0x7f800000u ? 0x7e00u : 0x7c00u));  // NaN, inf
  if (a >= 0x477ff000u) return uint16_t(sign | 0x7c00u);  // >= 65520: the tie above 65504 is even at inf
  if (a < 0x38800000u)  // below 2^-14: a subnormal half, the value in units of 2^-24 (exact scaling)
    return uint16_t(sign | uint32_t(std::nearbyint(std::bit_cast<float>(a) * 0x1p24f)));
  uint32_t h = ((a >> 23) - 112u) << 10 | ((a >> 13) & 0x3ffu);
  const uint32_t rest = a & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // a carry into the exponent is right
  return uint16_t(sign | h);
}

inline float halfToFloat(uint16_t h) {
  const uint32_t sign = uint32_t(h & 0x8000u) << 16;
  const uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
  if (exponent == 0) {
    const float v = float(mantissa) * 0x1p-24f;
    return sign ? -v : v;
  }
  if (exponent == 31) return std::bit_cast<float>(sign | 0x7f800000u | mantissa << 13);
  return std::bit_cast<float>(sign | (exponent + 112u) << 23 | mantissa << 13);
}

struct HalfRgb {
  uint16_t r = 0, g = 0, b = 0;
};
static_assert(sizeof(HalfRgb) == 6, "half-float RGB radiance, 48 bits per node");

inline HalfRgb toHalf(Rgb c) { return {floatToHalf(c.r), floatToHalf(c.g), floatToHalf(c.b)}; }
inline Rgb toFloat(HalfRgb c) { return {halfToFloat(c.r), halfToFloat(c.g), halfToFloat(c.b)}; }


// A node's radiance by direction (a departure from the paper; micro-rendering README, "Directional
// node radiance"): seen from direction w, a leaf of area A and normal n shows A max(0, n . w), so the
// node's radiance towards w is sum(A L max(0, n . w)) / sum(A max(0, n . w)) over its leaves. Both
// sums are kept for the six axis directions (an ambient cube), where they add up exactly from
// child to parent; towards w they are blended with the weights |w_x|, |w_y|, |w_z| of the three
// axis directions on w's side, which gives sum(A max(0, n . w)) exactly for normals in w's octant.
// A flat node sends its mean every way; a node over a column's sunlit and shaded sides sends each
// side's radiance towards the receivers that side faces.
struct DirectionalRadiance {
  Rgb shown[6];   // sum of A L max(0, n . e_k), e_k = +x, -x, +y, -y, +z, -z
  float area[6];  // sum of A max(0, n . e_k)
};
static_assert(sizeof(DirectionalRadiance) == 96, "a node's directional radiance is 24 floats");

// Towards direction w (unit, world space); `none` where no leaf shows itself that way.
inline Rgb radianceTowards(const DirectionalRadiance& d, Vec3 w, Rgb none) {
  const int x = w.x >= 0 ? 0 : 1, y = w.y >= 0 ? 2 : 3, z = w.z >= 0 ? 4 : 5;
  const float wx = std::abs(w.x), wy = std::abs(w.y), wz = std::abs(w.z);
  const float area = d.area[x] * wx + d.area[y] * wy + d.area[z] * wz;
  if (!(area > 0)) return none;
  return (d.shown[x] * wx + d.shown[y] * wy + d.shown[z] * wz) * (1.0f / area);
}

// The interior nodes' (1 .. n - 1; entry 0 unused) from the leaves' radiance (nodes n .. 2n - 1 of
// `radiance`), normals (the leaf nodes' cone axes) and areas, bottom up.
std::vector<DirectionalRadiance> directionalRadiance(const PointHierarchy& hierarchy, std::span<const Rgb> radiance);

// Interior radiance from the leaves' (nodes n .. 2n-1 of `radiance`, which has nodeCount() entries):
// every interior node gets the area-weighted average of its two children (nodeAreas), level by level
// from the leaves up; children of zero total area average equally.
void pullRadiance(const PointHierarchy& hierarchy, std::span<Rgb> radiance);

// The half-float copy of a radiance array, as the paper stores it (3.1).
std::vector<HalfRgb> packRadiance(std::span<const Rgb> radiance);

}  // namespace lucent
