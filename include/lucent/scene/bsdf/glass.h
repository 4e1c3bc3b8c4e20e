// A smooth dielectric of index ni against index 1 on the +z side: Fresnel reflection and refraction,
// each a Dirac delta. The +z side is the outside, so wo.z < 0 means the path is inside.
#pragma once
#include <algorithm>
#include <cmath>

#include "lucent/scene/bsdf/lobe.h"

namespace lucent {

// Fresnel reflectance of a smooth dielectric for unpolarised light; cosI > 0 on the side of eta_i.
inline float fresnelDielectric(float cosI, float etaI, float etaT) {
  const float sinT = etaI / etaT * std::sqrt(std::max(0.0f, 1.0f - cosI * cosI));
  if (sinT >= 1.0f) return 1.0f;
  const float cosT = std::sqrt(std::max(0.0f, 1.0f - sinT * sinT));
  const float rs = (etaI * cosI - etaT * cosT) / (etaI * cosI + etaT * cosT);
  const float rp = (etaT * cosI - etaI * cosT) / (etaT * cosI + etaI * cosT);
  return 0.5f * (rs * rs + rp * rp);
}

struct GlassLobe {
  float ni = 1.5f;
  static constexpr LobeField fields[] = {{"ni", true, 1}};

  static constexpr BsdfFlags flags = BsdfFlags::Reflection | BsdfFlags::Transmission | BsdfFlags::Specular;
  BsdfValue evaluate(Vec3, Vec3) const { return {}; }
  // Reflects with probability F, else refracts; `u` chooses.
  BsdfSample sample(Vec3 wo, float u, Vec2, Transport transport) const {
    BsdfSample s;
    const bool entering = wo.z > 0;
    const float etaI = entering ? 1.0f : ni, etaT = entering ? ni : 1.0f;
    const float cosI = std::abs(wo.z);
    const float F = fresnelDielectric(cosI, etaI, etaT);
    s.delta = s.valid = true;
    if (u < F) {
      s.wi = {-wo.x, -wo.y, wo.z};
      s.weight = Rgb(1.0f);
      s.pdf = F;
    } else {
      const float eta = etaI / etaT;
      const float cosT = std::sqrt(std::max(0.0f, 1.0f - eta * eta * (1.0f - cosI * cosI)));
      const float sign = entering ? -1.0f : 1.0f;
      s.wi = {-eta * wo.x, -eta * wo.y, sign * cosT};
      // Radiance is compressed into the denser medium: scale by (eta_i / eta_t)^2.
      s.weight = Rgb(transport == Transport::Radiance ? eta * eta : 1.0f);
      s.pdf = 1.0f - F;
    }
    return s;
  }
  Rgb albedo() const { return Rgb(1.0f); }
  Rgb bound() const { return Rgb(1.0f); }
  Rgb diffuse() const { return Rgb(0.0f); }
  Rgb diffuseShare(Vec3, Vec3) const { return Rgb(0.0f); }
};
static_assert(sizeof(GlassLobe) == lobeFieldBytes<GlassLobe>(), "a lobe is a plain record of its fields");

}  // namespace lucent
