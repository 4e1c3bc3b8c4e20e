// Warping functions from the unit square. Directions are in a local frame with the normal on +z;
// each sampler has a matching pdf (solid-angle measure unless said otherwise).
#pragma once
#include <bit>
#include <cmath>
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

// sin and cos of |x| <= pi/4 by their Taylor series to degree 9 and 10 (truncation below 2e-9,
// under half a float ulp): no library call, so that loops using it vectorize.
inline Vec2 sinCosQuarterPi(float x) {
  const float x2 = x * x;
  const float s = x * (1 + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880)))));
  const float c = 1 + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 - x2 * (1.0f / 3628800)))));
  return {s, c};
}

// sin and cos of 2 pi u for u in [0, 1]: the nearest quarter turn taken out exactly, the rest within
// pi/4 of 0 by sinCosQuarterPi.
inline Vec2 sinCos2Pi(float u) {
  const float quarter = std::floor(4.0f * u + 0.5f);
  const Vec2 sc = sinCosQuarterPi((2.0f * kPi) * (u - 0.25f * quarter));
  const int q = int(quarter) & 3;
  return {q == 0 ? sc.x : q == 1 ? sc.y : q == 2 ? -sc.x : -sc.y, q == 0 ? sc.y : q == 1 ? -sc.x : q == 2 ? -sc.y : sc.x};
}

// x^y for x in (0, 1] (a little above 1 is fine) and y > 0, as 2^(y log2 x): log2 of the mantissa
// scaled into [sqrt(1/2), sqrt(2)) by its atanh series, 2^f for the fraction by its Taylor series
// (both truncated below 1e-8). Relative error about 1e-7 (1 + |y log2 x|); results below 2^-126
// are 0. No library call and no branch, so that loops using it vectorize.
inline float powUnitInterval(float x, float y) {
  const auto bits = std::bit_cast<uint32_t>(x);
  const float mantissa = std::bit_cast<float>((bits & 0x007fffffu) | 0x3f800000u);  // [1, 2)
  const bool above = mantissa > 1.41421356f;
  const float m = above ? 0.5f * mantissa : mantissa;
  const float e = float(int32_t(bits >> 23) - (above ? 126 : 127));
  const float t = (m - 1.0f) / (m + 1.0f), t2 = t * t;
  const float log2m =
      t * (2.88539008f + t2 * (0.961796694f + t2 * (0.577078016f + t2 * (0.412198583f + t2 * 0.320598898f))));
  const float z = std::max(y * (e + log2m), -127.0f);
  const auto whole = int32_t(z);  // towards zero: f in (-1, 1)
  const float f = (z - float(whole)) * 0.693147181f;
  const float twoToF =
      1 + f * (1 + f * (1.0f / 2 + f * (1.0f / 6 + f * (1.0f / 24 + f * (1.0f / 120 + f * (1.0f / 720 + f * (1.0f / 5040 + f * (1.0f / 40320 + f * (1.0f / 362880)))))))));
  return twoToF * std::bit_cast<float>(uint32_t(whole + 127) << 23);
}

// Shirley and Chiu's concentric map. Where |y| > |x| the angle is pi/2 - phi with phi within pi/4
// of 0, so one sine and cosine of |phi| <= pi/4 serve all four sectors, chosen by selects.
inline Vec2 sampleConcentricDisk(Vec2 u) {
  const float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
  const bool xMajor = std::abs(ox) > std::abs(oy);
  const float major = xMajor ? ox : oy, minor = xMajor ? oy : ox;
  const Vec2 sc = sinCosQuarterPi((kPi / 4) * (minor / (major != 0 ? major : 1.0f)));
  const float along = major * sc.y, across = major * sc.x;  // r cos(phi), r sin(phi)
  return {xMajor ? along : across, xMajor ? across : along};
}

inline Vec3 sampleCosineHemisphere(Vec2 u) {
  const Vec2 d = sampleConcentricDisk(u);
  const float z = std::sqrt(std::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}
inline float cosineHemispherePdf(float cosTheta) { return cosTheta > 0 ? cosTheta * kInvPi : 0.0f; }

inline Vec3 sampleUniformSphere(Vec2 u) {
  const float z = 1.0f - 2.0f * u.x;
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
inline constexpr float kUniformSpherePdf = 1.0f / (4.0f * kPi);

// Uniform over the cone of directions within acos(cosMax) of +z.
inline Vec3 sampleUniformCone(Vec2 u, float cosMax) {
  const float z = 1.0f - u.x * (1.0f - cosMax);
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
inline float uniformConePdf(float cosMax) { return 1.0f / (2.0f * kPi * (1.0f - cosMax)); }

// Barycentrics (b1, b2) uniform over a triangle's area; b0 = 1 - b1 - b2 (square-root warp).
inline Vec2 sampleUniformTriangle(Vec2 u) {
  const float su = std::sqrt(u.x);
  return {1.0f - su, u.y * su};
}

// Directions distributed as cos^n of the angle to +z (the normalized Phong lobe's shape).
inline Vec3 samplePhongLobe(Vec2 u, float exponent) {
  const float cosA = powUnitInterval(1.0f - u.x, 1.0f / (exponent + 1.0f));
  const float sinA = std::sqrt(std::max(0.0f, 1.0f - cosA * cosA));
  const Vec2 sc = sinCos2Pi(u.y);
  return {sinA * sc.y, sinA * sc.x, cosA};
}
// The density of samplePhongLobe given cos^n of the angle, for callers that have the power already.
inline float phongLobePdfOfPower(float power, float exponent) { return (exponent + 1.0f) * (0.5f * kInvPi) * power; }
inline float phongLobePdf(float cosAlpha, float exponent) {
  return cosAlpha > 0 ? phongLobePdfOfPower(powUnitInterval(cosAlpha, exponent), exponent) : 0.0f;
}

// Sample i of n over the unit square, stratified: the first nx * ny samples (nx = floor(sqrt(n)),
// ny = floor(n / nx)) take one cell each of an nx x ny grid, jittered by `u` within it; the rest, if
// any, are `u` itself. Every sample's average over the n is unbiased: each stratified sample is
// uniform in a cell of equal area and the remaining ones are uniform over the square.
inline Vec2 stratifiedSample2D(uint32_t i, uint32_t n, Vec2 u) {
  const auto nx = static_cast<uint32_t>(std::sqrt(double(n)));
  if (nx == 0) return u;
  const uint32_t ny = n / nx;
  if (i >= nx * ny) return u;
  // The product can round to 1 for the last cell; keep samples in [0, 1).
  return {std::min((float(i % nx) + u.x) / float(nx), 0x1.fffffep-1f),
          std::min((float(i / nx) + u.y) / float(ny), 0x1.fffffep-1f)};
}

// Multiple importance sampling weight, power heuristic with beta = 2 (Veach 1997).
inline float powerHeuristic(float pdfA, float pdfB) {
  const float a = pdfA * pdfA, b = pdfB * pdfB;
  return a + b > 0 ? a / (a + b) : 0.0f;
}

// Direction <-> (u, v) in [0,1)^2 for latitude-longitude maps: u along phi, v from +y down.
inline Vec3 latLongToDirection(Vec2 uv) {
  const float phi = 2.0f * kPi * uv.x;
  const float theta = kPi * uv.y;
  const float st = std::sin(theta);
  return {st * std::sin(phi), std::cos(theta), -st * std::cos(phi)};
}
inline Vec2 directionToLatLong(Vec3 d) {
  float phi = std::atan2(d.x, -d.z);
  if (phi < 0) phi += 2.0f * kPi;
  // Not acos(d.y), which loses a few 1e-5 of v near the poles.
  const float theta = std::atan2(std::sqrt(d.x * d.x + d.z * d.z), d.y);
  return {std::min(phi * (0.5f * kInvPi), 0x1.fffffep-1f), std::min(theta * kInvPi, 0x1.fffffep-1f)};
}

}  // namespace lucent
