// Warping functions from the unit square. Directions are in a local frame with the normal on +z;
// each sampler has a matching pdf (solid-angle measure unless said otherwise).
#pragma once
#include <algorithm>
#include <cmath>

#include "lucent/core/math.h"

namespace lucent {

// sin and cos of |x| <= pi/4 by their Taylor series to degree 9 and 10: truncation below 2e-9, the
// float rounding in the products dominates (within 1.5e-7, tested); no library call, so that loops
// using it vectorize.
inline Vec2 sinCosQuarterPi(float x) {
  const float x2 = x * x;
  const float s = x * (1 + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 * (1.0f / 362880)))));
  const float c = 1 + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 * (1.0f / 40320 - x2 * (1.0f / 3628800)))));
  return {s, c};
}

// Shirley and Chiu's concentric map. Where |y| >= |x| the angle is pi/2 - phi with phi within pi/4
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
  const float cosA = std::pow(1.0f - u.x, 1.0f / (exponent + 1.0f));
  const float sinA = std::sqrt(std::max(0.0f, 1.0f - cosA * cosA));
  const float phi = 2.0f * kPi * u.y;
  return {sinA * std::cos(phi), sinA * std::sin(phi), cosA};
}
// The density of samplePhongLobe given cos^n of the angle, for callers that have the power already.
inline float phongLobePdfOfPower(float power, float exponent) { return (exponent + 1.0f) * (0.5f * kInvPi) * power; }
inline float phongLobePdf(float cosAlpha, float exponent) {
  return cosAlpha > 0 ? phongLobePdfOfPower(std::pow(std::min(cosAlpha, 1.0f), exponent), exponent) : 0.0f;
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

// Russian roulette: the path survives with probability min(1, the largest component of its
// throughput times `scale`), u uniform in [0, 1), and the survivor is scaled up by as much. Scale 1
// is roulette on the throughput alone; the path tracer's contribution roulette scales it by the
// pixel (RouletteScales).
inline bool survivesRussianRoulette(Rgb& beta, float u, Rgb scale = Rgb(1.0f)) {
  const float survive = std::min(1.0f, (beta * scale).maxComponent());
  if (u >= survive) return false;
  beta *= 1.0f / survive;
  return true;
}

// Multiple importance sampling weight, power heuristic with beta = 2 (Veach 1997): a^2 / (a^2 +
// b^2), from the ratio of the smaller density to the larger, whose square cannot overflow (a
// density's square does above 1.8e19, a near-mirror lobe's, and a^2 / (a^2 + b^2) is then NaN).
inline float powerHeuristic(float pdfA, float pdfB) {
  if (!(pdfA > 0)) return 0.0f;
  if (pdfA == pdfB) return 0.5f;  // infinite ones too
  if (pdfA > pdfB) {
    const float r = pdfB / pdfA;
    return 1.0f / (1.0f + r * r);
  }
  const float r = pdfA / pdfB;
  return r * r / (1.0f + r * r);
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
