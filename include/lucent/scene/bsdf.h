// The four materials' scattering functions, in the local shading frame (normal on +z, wo and wi
// pointing away from the surface). Shared by every method.
#pragma once
#include <algorithm>
#include <cmath>

#include "lucent/core/sampling.h"
#include "lucent/scene/ggx.h"
#include "lucent/scene/scene.h"

namespace lucent {

// A material at a surface point, with its textures looked up. For glTF's metallic-roughness
// material (isGltf) the fields hold Appendix B's BRDF with the metal/dielectric mix expanded:
//   f = kd / pi (1 - Fd) + F D G / (4 |n.wo| |n.wi|),
//   F  = ks + (f90 - ks) (1 - |wo.h|)^5           (the mixed Fresnel term, per channel),
//   Fd = dielectricF0 + (dielectricF90 - dielectricF0) (1 - |wo.h|)^5   (its dielectric's largest
//        channel, which the diffuse base loses: KHR_materials_specular's max_value),
// kd = (1 - metallic) base colour, D the GGX distribution of roughness alpha, G Smith's
// masking-shadowing in the type's form (ggx.h).
struct SurfaceBsdf {
  MaterialType type = MaterialType::Diffuse;
  Rgb kd, ks;
  float ns = 1, ni = 1.5f;
  float alpha = 1, f90 = 1, dielectricF0 = 0, dielectricF90 = 0;  // glTF only

  bool isDelta() const { return type == MaterialType::Mirror || type == MaterialType::Glass; }
  // Probability of choosing the diffuse lobe when sampling a Phong material.
  float diffuseChoice() const {
    const float d = kd.average(), s = ks.average();
    return d + s > 0 ? d / (d + s) : 1.0f;
  }
};

// The reflectance a first hit records in the albedo layer: the diffuse and specular albedos (a
// glTF material's at normal incidence), a mirror's tint, 1 for glass.
inline Rgb layerAlbedo(const SurfaceBsdf& b) {
  return b.type == MaterialType::Mirror ? b.ks : b.type == MaterialType::Glass ? Rgb(1.0f) : b.kd + b.ks;
}

// An upper bound of the light the surface reflects, per channel, for Russian roulette by
// reflectance; a glTF material's Fresnel term reaches f90 at grazing angles.
inline Rgb reflectanceBound(const SurfaceBsdf& b) {
  if (isGltf(b.type))
    return b.kd + Rgb(std::max(b.ks.r, b.f90), std::max(b.ks.g, b.f90), std::max(b.ks.b, b.f90));
  return layerAlbedo(b);
}

// Radiance is transported from the camera; importance (photon flux) from the lights. They differ in
// refraction, where radiance is scaled by (eta_i / eta_t)^2 and flux is not (Veach 1997, 5.2).
enum class Transport { Radiance, Importance };

struct BsdfSample {
  Vec3 wi;
  Rgb weight;       // f * |cos| / pdf (for delta lobes, the lobe's weight)
  float pdf = 0;    // solid angle; for delta lobes the discrete probability of the chosen lobe
  bool delta = false;
  bool valid = false;
};

// Fresnel reflectance of a smooth dielectric for unpolarised light; cosI > 0 on the side of eta_i.
inline float fresnelDielectric(float cosI, float etaI, float etaT) {
  const float sinT = etaI / etaT * std::sqrt(std::max(0.0f, 1.0f - cosI * cosI));
  if (sinT >= 1.0f) return 1.0f;
  const float cosT = std::sqrt(std::max(0.0f, 1.0f - sinT * sinT));
  const float rs = (etaI * cosI - etaT * cosT) / (etaI * cosI + etaT * cosT);
  const float rp = (etaT * cosI - etaI * cosT) / (etaT * cosI + etaI * cosT);
  return 0.5f * (rs * rs + rp * rp);
}

// BSDF value for non-delta materials (zero for mirror and glass, whose lobes are Dirac deltas), and
// the density with which sampleBsdf picks wi, computed together (the Phong lobe's power once).
struct BsdfValue {
  Rgb f;
  float pdf = 0;
};

// The Lambertian lobe of albedo kd, from local directions' cosines: kd / pi and the cosine-weighted
// density, both zero unless both directions are above the surface. Selects only: the path
// tracer's lane loop vectorizes it (shadeDiffuseLanes); conditions chained on one comparison each,
// not boolean algebra, which the vectorizer does not take.
inline BsdfValue lambertianValue(Rgb kd, float woZ, float wiZ) {
  const float bothAbove = woZ <= 0 ? 0.0f : wiZ <= 0 ? 0.0f : 1.0f;
  return {{bothAbove == 0 ? 0.0f : kd.r * kInvPi, bothAbove == 0 ? 0.0f : kd.g * kInvPi,
           bothAbove == 0 ? 0.0f : kd.b * kInvPi},
          bothAbove == 0 ? 0.0f : cosineHemispherePdf(wiZ)};
}

// A cosine-distributed direction for the Lambertian lobe of albedo kd, its density and weight;
// valid (pdf > 0) only where both directions are above the surface. Selects only, as above.
inline BsdfSample sampleLambertian(Rgb kd, float woZ, Vec2 u) {
  BsdfSample s;
  s.wi = sampleCosineHemisphere(u);
  s.pdf = woZ <= 0 ? 0.0f : s.wi.z <= 0 ? 0.0f : cosineHemispherePdf(s.wi.z);
  s.weight = kd * kInvPi * (s.wi.z / s.pdf);
  s.valid = s.pdf > 0;
  return s;
}

// glTF's Schlick weight (1 - |wo.h|)^5, the share of the way from F0 to F90.
inline float schlickWeight(float cosWoH) {
  const float x = 1.0f - std::min(1.0f, std::abs(cosWoH));
  const float x2 = x * x;
  return x2 * x2 * x;
}

// Probability of choosing the GGX lobe when sampling a glTF material: the share of its two lobes'
// weights at the Fresnel term of n.wo, the visible-normal distribution's centre.
inline float gltfSpecularChoice(const SurfaceBsdf& b, float woZ) {
  const float w = schlickWeight(woZ);
  const float specular = (b.ks + (Rgb(b.f90) - b.ks) * w).average();
  const float diffuse = b.kd.average() * (1.0f - (b.dielectricF0 + (b.dielectricF90 - b.dielectricF0) * w));
  return specular + diffuse > 0 ? specular / (specular + diffuse) : 0.0f;
}

inline BsdfValue gltfValue(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) {
  const Vec3 h = normalize(wo + wi);
  const float w = schlickWeight(dot(wo, h));
  const Rgb F = b.ks + (Rgb(b.f90) - b.ks) * w;
  const float diffuseWeight = 1.0f - (b.dielectricF0 + (b.dielectricF90 - b.dielectricF0) * w);
  const float G = b.type == MaterialType::Gltf ? smithSeparable(b.alpha, wo.z, wi.z)
                                               : smithHeightCorrelated(b.alpha, wo.z, wi.z);
  const float specular = ggxD(b.alpha, h) * G / (4.0f * wo.z * wi.z);
  const float ps = gltfSpecularChoice(b, wo.z);
  return {b.kd * (kInvPi * diffuseWeight) + F * specular,
          ps * ggxReflectionPdf(b.alpha, wo, wi) + (1.0f - ps) * cosineHemispherePdf(wi.z)};
}

inline BsdfValue evalBsdfAndPdf(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) {
  if (b.isDelta() || wo.z <= 0 || wi.z <= 0) return {Rgb(0.0f), 0.0f};
  if (isGltf(b.type)) return gltfValue(b, wo, wi);
  BsdfValue v = lambertianValue(b.kd, wo.z, wi.z);
  if (b.type == MaterialType::Phong) {
    // A cosine, rounded: above 1 by an ulp or two, its power overflowed for exponents of 1e8 and
    // more (f and pdf infinite, their ratio NaN).
    const float cosAlpha = std::min(dot(reflect(wo, {0, 0, 1}), wi), 1.0f);
    const float power = cosAlpha > 0 ? std::pow(cosAlpha, b.ns) : 0.0f;
    if (cosAlpha > 0) v.f += b.ks * ((b.ns + 2.0f) * 0.5f * kInvPi * power);
    const float pd = b.diffuseChoice();
    v.pdf = pd * v.pdf + (1.0f - pd) * (cosAlpha > 0 ? phongLobePdfOfPower(power, b.ns) : 0.0f);
  }
  return v;
}
inline Rgb evalBsdf(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) { return evalBsdfAndPdf(b, wo, wi).f; }
// The share of f(wo, wi) that is the diffuse lobe's, per channel (0 where f is): how light
// scattered from wo to wi splits into diffuse and glossy reflection. The diffuse lobe is the
// Lambertian term: kd / pi (Phong), kd (1 - F_dielectric) / pi (glTF).
inline Rgb diffuseShare(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) {
  if (b.type == MaterialType::Diffuse) return Rgb(1.0f);
  const Rgb f = evalBsdf(b, wo, wi);
  if (f.isBlack()) return Rgb(0.0f);
  Rgb diffuse = lambertianValue(b.kd, wo.z, wi.z).f;
  if (isGltf(b.type)) {
    const float w = schlickWeight(dot(wo, normalize(wo + wi)));
    diffuse = diffuse * (1.0f - (b.dielectricF0 + (b.dielectricF90 - b.dielectricF0) * w));
  }
  return {f.r > 0 ? std::min(1.0f, diffuse.r / f.r) : 0.0f, f.g > 0 ? std::min(1.0f, diffuse.g / f.g) : 0.0f,
          f.b > 0 ? std::min(1.0f, diffuse.b / f.b) : 0.0f};
}
inline float bsdfPdf(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) { return evalBsdfAndPdf(b, wo, wi).pdf; }

// A direction wi drawn from one lobe of a mixture (Phong's, a glTF material's), weighed by the whole
// mixture's value and density: valid where both are positive above the surface.
inline BsdfSample mixtureSample(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) {
  BsdfSample s;
  s.wi = wi;
  if (s.wi.z <= 0) return s;
  const BsdfValue v = evalBsdfAndPdf(b, wo, s.wi);
  s.pdf = v.pdf;
  if (!(s.pdf > 0)) return s;
  s.weight = v.f * (s.wi.z / s.pdf);
  s.valid = true;
  return s;
}

// Samples wi given wo; `u` picks the lobe, `u2` the direction. For glass the outside (index 1) is
// the +z side, so wo.z < 0 means the path is inside the dielectric.
inline BsdfSample sampleBsdf(const SurfaceBsdf& b, Vec3 wo, float u, Vec2 u2,
                             Transport transport = Transport::Radiance) {
  BsdfSample s;
  switch (b.type) {
    case MaterialType::Mirror:
      if (wo.z <= 0) return s;
      s.wi = {-wo.x, -wo.y, wo.z};
      s.weight = b.ks;
      s.pdf = 1;
      s.delta = s.valid = true;
      return s;
    case MaterialType::Glass: {
      const bool entering = wo.z > 0;
      const float etaI = entering ? 1.0f : b.ni, etaT = entering ? b.ni : 1.0f;
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
    case MaterialType::Diffuse: return sampleLambertian(b.kd, wo.z, u2);
    case MaterialType::Gltf:
    case MaterialType::GltfHeightCorrelated:
      if (wo.z <= 0) return s;
      return mixtureSample(b, wo, u < gltfSpecularChoice(b, wo.z) ? reflect(wo, sampleGgxVisibleNormal(b.alpha, wo, u2))
                                                                  : sampleCosineHemisphere(u2));
    case MaterialType::Phong:
      if (wo.z <= 0) return s;
      return mixtureSample(b, wo, u < b.diffuseChoice() ? sampleCosineHemisphere(u2)
                                                        : Frame(reflect(wo, {0, 0, 1})).toWorld(samplePhongLobe(u2, b.ns)));
  }
  return s;
}

}  // namespace lucent
