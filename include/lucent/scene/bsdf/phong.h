// The modified Phong BRDF (Lafortune and Willems 1994): a Lambertian term kd / pi plus a normalized
// lobe ks (ns + 2) / (2 pi) cos^ns around the mirror direction; kd + ks <= 1 conserves energy.
#pragma once
#include <algorithm>
#include <cmath>

#include "lucent/scene/bsdf/lambertian.h"

namespace lucent {

struct PhongLobe {
  Rgb kd, ks;
  float ns = 1;
  static constexpr LobeField fields[] = {{"kd", true, 3}, {"ks", true, 3}, {"ns", true, 1}};

  static constexpr BsdfFlags flags =
      BsdfFlags::Reflection | BsdfFlags::Diffuse | BsdfFlags::Glossy | BsdfFlags::TwoSided;

  // Probability of sampling the Lambertian term rather than the lobe.
  float diffuseChoice() const {
    const float d = kd.average(), s = ks.average();
    return d + s > 0 ? d / (d + s) : 1.0f;
  }

  BsdfValue evaluate(Vec3 wo, Vec3 wi) const {
    BsdfValue v = lambertianValue(kd, wo.z, wi.z);
    // A cosine, rounded: above 1 by an ulp or two, its power overflowed for exponents of 1e8 and
    // more (f and pdf infinite, their ratio NaN).
    const float cosAlpha = std::min(dot(reflect(wo, {0, 0, 1}), wi), 1.0f);
    const float power = cosAlpha > 0 ? std::pow(cosAlpha, ns) : 0.0f;
    if (cosAlpha > 0) v.f += ks * ((ns + 2.0f) * 0.5f * kInvPi * power);
    const float pd = diffuseChoice();
    v.pdf = pd * v.pdf + (1.0f - pd) * (cosAlpha > 0 ? phongLobePdfOfPower(power, ns) : 0.0f);
    return v;
  }

  BsdfSample sample(Vec3 wo, float u, Vec2 u2, Transport) const {
    if (wo.z <= 0) return {};
    return mixtureSample(*this, wo, u < diffuseChoice() ? sampleCosineHemisphere(u2)
                                                        : Frame(reflect(wo, {0, 0, 1})).toWorld(samplePhongLobe(u2, ns)));
  }

  Rgb albedo() const { return kd + ks; }
  Rgb bound() const { return kd + ks; }
  Rgb diffuse() const { return kd; }

  Rgb diffuseShare(Vec3 wo, Vec3 wi) const {
    if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
    const Rgb f = evaluate(wo, wi).f;
    if (f.isBlack()) return Rgb(0.0f);
    return channelShare(lambertianValue(kd, wo.z, wi.z).f, f);
  }
};
static_assert(sizeof(PhongLobe) == lobeFieldBytes<PhongLobe>(), "a lobe is a plain record of its fields");

}  // namespace lucent
