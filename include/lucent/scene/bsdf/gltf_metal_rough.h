// glTF 2.0's metallic-roughness BRDF (Appendix B), with KHR_materials_ior and
// KHR_materials_specular, its metal/dielectric mix expanded (surface.h's gltfBsdf fills it):
//   f = kd / pi (1 - Fd) + F D G / (4 |n.wo| |n.wi|),
//   F  = ks + (f90 - ks) (1 - |wo.h|)^5           (the mixed Fresnel term, per channel),
//   Fd = dielectricF0 + (dielectricF90 - dielectricF0) (1 - |wo.h|)^5   (its dielectric's largest
//        channel, which the diffuse base loses: KHR_materials_specular's max_value),
// kd = (1 - metallic) base colour, D the GGX distribution of roughness alpha, G Smith's
// masking-shadowing in the form `masking` names (ggx.h). With KHR_materials_sheen (a sheen colour
// other than black) the sheen layer of sheen.h lies on top, the above its base. With
// KHR_materials_clearcoat (coat > 0) a clear coat lies on top of both, as the extension layers it:
//   f_coated(V, L) = (1 - Wc(V)) f(V, L) + Wc(V) D_c G_c / (4 |V.nc| |L.nc|),
//   Wc(V) = coat (0.04 + 0.96 (1 - |V.nc|)^5),
// D_c and G_c the GGX terms of alpha coatAlpha about the coat's own normal nc (its normal texture's,
// or the surface's without the base's normal texture). V is the viewer's side: the weight uses
// V.nc where a microfacet Fresnel term would use V.h, so the coated BRDF is not reciprocal
// (f(wo, wi) != f(wi, wo)) and importance transport takes its adjoint f(wi, wo).
// Sampling: the coat (its GGX visible normals about nc) with probability Wc(wo) where wo is above
// the coat; else the sheen layer (uniformly over the hemisphere, as its fibres reflect most at
// grazing angles) with probability max3(sheenColour) E(n.wo), else the base's GGX visible normals
// or cosine lobe, chosen by their weights at n.wo; every sample is weighed by the whole mixture.
#pragma once
#include <algorithm>
#include <cmath>

#include "lucent/scene/bsdf/lambertian.h"
#include "lucent/scene/bsdf/sheen.h"
#include "lucent/scene/ggx.h"

namespace lucent {

// glTF's Schlick weight (1 - |wo.h|)^5, the share of the way from F0 to F90.
inline float schlickWeight(float cosWoH) {
  const float x = 1.0f - std::min(1.0f, std::abs(cosWoH));
  const float x2 = x * x;
  return x2 * x2 * x;
}

struct GltfMetalRoughLobe {
  Rgb kd, ks;
  float alpha = 1, f90 = 1, dielectricF0 = 0, dielectricF90 = 0;
  GgxMasking masking = GgxMasking::Separable;
  Rgb sheenColour;             // KHR_materials_sheen's; black: no sheen layer
  float sheenRoughness = 0;    // at least kMinSheenRoughness where there is a sheen layer
  float coat = 0;              // KHR_materials_clearcoat's clearcoat; 0: no coat
  float coatAlpha = 0;         // the coat's GGX alpha, at least kMinGgxAlpha where there is a coat
  // The coat's normal, in the shading frame: bsdfAt gives it in world space, and the lobe is taken
  // into the frame where one is made (SurfaceBsdf::inFrame).
  Vec3 coatNormal{0, 0, 1};
  static constexpr LobeField fields[] = {{"kd", true, 3},    {"ks", true, 3},  {"alpha", true, 1},
                                         {"f90", true, 1},   {"dielectric_f0", true, 1},
                                         {"dielectric_f90", true, 1}, {"masking", false, 1},
                                         {"sheen_colour", true, 3},   {"sheen_roughness", true, 1},
                                         {"coat", true, 1},           {"coat_alpha", true, 1},
                                         {"coat_normal", true, 3}};

  static constexpr BsdfFlags flags =
      BsdfFlags::Reflection | BsdfFlags::Diffuse | BsdfFlags::Glossy | BsdfFlags::TwoSided;

  // The share of the diffuse base that the dielectric's Fresnel term leaves, at Schlick weight w.
  float diffuseWeight(float w) const { return 1.0f - (dielectricF0 + (dielectricF90 - dielectricF0) * w); }

  // Probability of choosing the GGX lobe: the share of the two terms' weights at the Fresnel term
  // of n.wo, the visible-normal distribution's centre.
  float specularChoice(float woZ) const {
    const float w = schlickWeight(woZ);
    const float specular = (ks + (Rgb(f90) - ks) * w).average();
    const float diffuse = kd.average() * diffuseWeight(w);
    return specular + diffuse > 0 ? specular / (specular + diffuse) : 0.0f;
  }

  bool hasSheen() const { return !sheenColour.isBlack(); }
  // The base's scaling under the sheen layer, for directions of cosines woZ and wiZ.
  float sheenScaling(float woZ, float wiZ) const {
    const SheenAlbedoTable& e = SheenAlbedoTable::get();
    const float m = sheenColour.maxComponent();
    return std::min(1.0f - m * e.at(woZ, sheenRoughness), 1.0f - m * e.at(wiZ, sheenRoughness));
  }
  // Probability of sampling the sheen layer.
  float sheenChoice(float woZ) const {
    return sheenColour.maxComponent() * SheenAlbedoTable::get().at(woZ, sheenRoughness);
  }

  bool hasCoat() const { return coat > 0; }
  // The coat's weight Wc(V) for the viewer's direction v.
  float coatWeight(Vec3 v) const { return coat * (0.04f + 0.96f * schlickWeight(dot(v, coatNormal))); }
  // Probability of sampling the coat: its weight, where wo is above it (else it reflects nothing).
  float coatChoice(Vec3 wo) const { return dot(wo, coatNormal) > 0 ? coatWeight(wo) : 0.0f; }

  // The coat's layer D_c G_c / (4 |wo.nc| |wi.nc|) and the density of its sampling, in the coat's
  // frame: zero where either direction is below the coat, though its visible normals reflect some
  // directions from above to below it.
  BsdfValue coatLayer(Vec3 wo, Vec3 wi) const {
    const Frame f(coatNormal);
    const Vec3 o = f.toLocal(wo), i = f.toLocal(wi);
    if (!(o.z > 0)) return {Rgb(0.0f), 0.0f};
    const float pdf = ggxReflectionPdf(coatAlpha, o, i);
    if (!(i.z > 0)) return {Rgb(0.0f), pdf};
    const float d = ggxD(coatAlpha, normalize(o + i));
    return {Rgb(d * smithMasking(masking, coatAlpha, o.z, i.z) / (4.0f * o.z * i.z)), pdf};
  }

  // f(wo, wi) with wo the viewer's side, and the density of sampling wi from wo.
  BsdfValue evaluate(Vec3 wo, Vec3 wi) const {
    const BsdfValue under = evaluateUnderCoat(wo, wi);
    if (!hasCoat()) return under;
    const BsdfValue layer = coatLayer(wo, wi);
    const float w = coatWeight(wo), pc = coatChoice(wo);
    return {under.f * (1.0f - w) + layer.f * w, pc * layer.pdf + (1.0f - pc) * under.pdf};
  }

  // Below the coat: the sheen layer over the base, or the base alone.
  BsdfValue evaluateUnderCoat(Vec3 wo, Vec3 wi) const {
    const BsdfValue base = evaluateBase(wo, wi);
    if (!hasSheen()) return base;
    // sheenChoice and sheenScaling, with E(n.wo) looked up once.
    const SheenAlbedoTable& e = SheenAlbedoTable::get();
    const float m = sheenColour.maxComponent(), eo = e.at(wo.z, sheenRoughness);
    const float scaling = std::min(1.0f - m * eo, 1.0f - m * e.at(wi.z, sheenRoughness));
    const float ps = m * eo;
    const float sheen = sheenValue(sheenRoughness * sheenRoughness, wo.z, wi.z, normalize(wo + wi).z);
    return {sheenColour * sheen + base.f * scaling, ps * (0.5f * kInvPi) + (1.0f - ps) * base.pdf};
  }

  // The base: Appendix B's BRDF and the density of its sampling.
  BsdfValue evaluateBase(Vec3 wo, Vec3 wi) const {
    const Vec3 h = normalize(wo + wi);
    const float w = schlickWeight(dot(wo, h));
    const Rgb F = ks + (Rgb(f90) - ks) * w;
    const float specular = ggxD(alpha, h) * smithMasking(masking, alpha, wo.z, wi.z) / (4.0f * wo.z * wi.z);
    const float ps = specularChoice(wo.z);
    return {kd * (kInvPi * diffuseWeight(w)) + F * specular,
            ps * ggxReflectionPdf(alpha, wo, wi) + (1.0f - ps) * cosineHemispherePdf(wi.z)};
  }

  BsdfSample sample(Vec3 wo, float u, Vec2 u2, Transport transport) const {
    if (wo.z <= 0) return {};
    BsdfSample s = mixtureSample(*this, wo, sampleDirection(wo, u, u2));
    // Importance flows from L to V: the adjoint f(wi, wo), which only the coat's weight makes differ.
    if (s.valid && hasCoat() && transport == Transport::Importance) s.weight = evaluate(s.wi, wo).f * (s.wi.z / s.pdf);
    return s;
  }

  // A direction from one of the mixture's terms, `u` choosing the term.
  Vec3 sampleDirection(Vec3 wo, float u, Vec2 u2) const {
    if (hasCoat()) {
      const float pc = coatChoice(wo);
      if (u < pc) {
        const Frame f(coatNormal);
        const Vec3 o = f.toLocal(wo);
        return f.toWorld(reflect(o, sampleGgxVisibleNormal(coatAlpha, o, u2)));
      }
      u = (u - pc) / (1.0f - pc);
    }
    if (hasSheen()) {
      const float ps = sheenChoice(wo.z);
      if (u < ps) {
        const Vec3 w = sampleUniformSphere(u2);
        return {w.x, w.y, std::abs(w.z)};
      }
      u = (u - ps) / (1.0f - ps);
    }
    return u < specularChoice(wo.z) ? reflect(wo, sampleGgxVisibleNormal(alpha, wo, u2)) : sampleCosineHemisphere(u2);
  }

  // At normal incidence (the base's scaling and the sheen's albedo there), under the coat's weight
  // there, the coat reflecting all it takes.
  Rgb albedo() const {
    const Rgb under = hasSheen() ? (kd + ks) * sheenScaling(1.0f, 1.0f) +
                                       sheenColour * SheenAlbedoTable::get().at(1.0f, sheenRoughness)
                                 : kd + ks;
    const float w = coat * 0.04f;
    return under * (1.0f - w) + Rgb(w);
  }
  // The Fresnel term reaches f90 at grazing angles; the sheen's albedo is at most 1, the coat's too,
  // and the coat's weight mixes it with what lies under.
  Rgb bound() const {
    const Rgb base = kd + Rgb(std::max(ks.r, f90), std::max(ks.g, f90), std::max(ks.b, f90));
    const Rgb under = hasSheen() ? base + sheenColour : base;
    return hasCoat() ? Rgb(std::max(under.r, 1.0f), std::max(under.g, 1.0f), std::max(under.b, 1.0f)) : under;
  }
  // The Lambertian term, under the sheen and the coat at normal incidence.
  Rgb diffuse() const { return (hasSheen() ? kd * sheenScaling(1.0f, 1.0f) : kd) * (1.0f - coat * 0.04f); }

  Rgb diffuseShare(Vec3 wo, Vec3 wi) const {
    if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
    const Rgb f = evaluate(wo, wi).f;
    if (f.isBlack()) return Rgb(0.0f);
    const float w = schlickWeight(dot(wo, normalize(wo + wi)));
    const float scaling = (hasSheen() ? sheenScaling(wo.z, wi.z) : 1.0f) * (hasCoat() ? 1.0f - coatWeight(wo) : 1.0f);
    return channelShare(lambertianValue(kd, wo.z, wi.z).f * (diffuseWeight(w) * scaling), f);
  }
};
static_assert(sizeof(GltfMetalRoughLobe) == lobeFieldBytes<GltfMetalRoughLobe>(), "a lobe is a plain record of its fields");

}  // namespace lucent
