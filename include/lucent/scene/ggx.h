// The GGX (Trowbridge-Reitz) microfacet distribution that glTF's metallic-roughness material uses
// (glTF 2.0 specification, Appendix B), in the local shading frame (normal on +z), with alpha =
// roughness^2: the distribution D, Smith's masking function in both forms a backend may implement
// (the height-correlated form that Appendix B gives since its revision of January 2026, and the
// separable product it gave before), and the sampling of visible normals (Heitz 2018, "Sampling the GGX Distribution of
// Visible Normals", JCGT 7(4)) with its density. The functions the path tracer's lane loop calls
// are written with selects only (no early return), so that it vectorizes.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lucent/core/math.h"
#include "lucent/core/sampling.h"

namespace lucent {

// D(m) for a microfacet normal at cosM = n.m from the normal; 0 below the surface.
inline float ggxD(float alpha, float cosM) {
  if (!(cosM > 0)) return 0.0f;
  const float a2 = alpha * alpha;
  const float d = cosM * cosM * (a2 - 1.0f) + 1.0f;
  return a2 / (kPi * d * d);
}

// D(m) from the unit normal's components, the same function written as 1 / (pi alpha^2 (x^2 /
// alpha^2 + y^2 / alpha^2 + z^2)^2): exact to float rounding for small alpha, where 1 - cos^2 in
// the form above loses every digit (alpha 1e-3: alpha^2 is below float's epsilon).
[[gnu::always_inline]] inline float ggxD(float alpha, Vec3 m) {
  const float x = m.x / alpha, y = m.y / alpha;
  const float d = x * x + y * y + m.z * m.z;
  return m.z > 0 ? 1.0f / (kPi * alpha * alpha * d * d) : 0.0f;
}

// Smith's Lambda for a direction at cosW = n.w (|cosW| taken): the microsurface's shadowed share.
[[gnu::always_inline]] inline float smithLambda(float alpha, float cosW) {
  const float c2 = cosW * cosW;
  const float tan2 = std::max(0.0f, 1.0f - c2) / c2;
  return c2 > 0 ? 0.5f * (std::sqrt(1.0f + alpha * alpha * tan2) - 1.0f) : kInf;
}

// G1 = 1 / (1 + Lambda), written as Appendix B writes it: 2 |n.w| / (|n.w| + sqrt(alpha^2 + (1 -
// alpha^2) (n.w)^2)).
[[gnu::always_inline]] inline float smithG1(float alpha, float cosW) {
  const float c = std::abs(cosW);
  return 2.0f * c / (c + std::sqrt(alpha * alpha + (1.0f - alpha * alpha) * c * c));
}

// Masking-shadowing of the pair of directions: the separable product G1(o) G1(i) (glTF's Appendix B
// before 2026), or the height-correlated 1 / (1 + Lambda(o) + Lambda(i)) (Appendix B now), never smaller.
[[gnu::always_inline]]
inline float smithSeparable(float alpha, float cosO, float cosI) { return smithG1(alpha, cosO) * smithG1(alpha, cosI); }
[[gnu::always_inline]] inline float smithHeightCorrelated(float alpha, float cosO, float cosI) {
  return 1.0f / (1.0f + smithLambda(alpha, cosO) + smithLambda(alpha, cosI));
}
// Which of the two a material uses: a parameter of its lobe, not a kind of its own.
enum class GgxMasking : uint32_t { Separable = 0, HeightCorrelated = 1 };
[[gnu::always_inline]] inline float smithMasking(GgxMasking form, float alpha, float cosO, float cosI) {
  return form == GgxMasking::Separable ? smithSeparable(alpha, cosO, cosI) : smithHeightCorrelated(alpha, cosO, cosI);
}

// A microfacet normal visible from wo (wo.z > 0), with density D_wo(m) = G1(wo) max(0, wo.m) D(m) /
// wo.z (ggxVisibleNormalPdf): the hemisphere seen from wo is stretched to the unit roughness
// configuration, a point is sampled on the projected half-disc, and the normal is stretched back.
// The point on the disc comes from the concentric map, uniform like Heitz's polar one and free of
// library calls, so that the path tracer's lane loop vectorizes with it.
[[gnu::always_inline]] inline Vec3 sampleGgxVisibleNormal(float alpha, Vec3 wo, Vec2 u) {
  const Vec3 vh = normalize(Vec3{alpha * wo.x, alpha * wo.y, wo.z});
  const float lensq = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = select(lensq > 0, Vec3{-vh.y, vh.x, 0.0f} / std::sqrt(lensq), {1, 0, 0});
  const Vec3 t2 = cross(vh, t1);
  const Vec2 disc = sampleConcentricDisk(u);
  const float p1 = disc.x;
  const float s = 0.5f * (1.0f + vh.z);
  const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * disc.y;
  const Vec3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2));
  return normalize(Vec3{alpha * nh.x, alpha * nh.y, std::max(1e-7f, nh.z)});
}

[[gnu::always_inline]] inline float ggxVisibleNormalPdf(float alpha, Vec3 wo, Vec3 m) {
  return wo.z > 0 ? smithG1(alpha, wo.z) * std::max(0.0f, dot(wo, m)) * ggxD(alpha, m) / wo.z : 0.0f;
}

// The density of wi = wo reflected about a visible normal: D_wo(h) / (4 wo.h), h = normalize(wo +
// wi).
[[gnu::always_inline]] inline float ggxReflectionPdf(float alpha, Vec3 wo, Vec3 wi) {
  const Vec3 sum = wo + wi;
  const float len = length(sum);
  const Vec3 h = sum / len;
  const float woh = dot(wo, h);
  return len > 0 && woh > 0 ? ggxVisibleNormalPdf(alpha, wo, h) / (4.0f * woh) : 0.0f;
}

}  // namespace lucent
