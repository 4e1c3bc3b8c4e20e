// glTF 2.0's metallic-roughness BRDF (Appendix B), with KHR_materials_ior and
// KHR_materials_specular, its metal/dielectric mix expanded (surface.h's gltfBsdf fills it):
//   f = kd / pi (1 - Fd) + F D G / (4 |n.wo| |n.wi|),
//   F  = ks + (f90 - ks) (1 - |wo.h|)^5           (the mixed Fresnel term, per channel),
//   Fd = dielectricF0 + (dielectricF90 - dielectricF0) (1 - |wo.h|)^5   (its dielectric's largest
//        channel, which the diffuse base loses: KHR_materials_specular's max_value),
// kd = (1 - metallic) base colour, D the GGX distribution of roughness alpha, G Smith's
// masking-shadowing in the form `masking` names (ggx.h). With KHR_materials_transmission (thin-walled:
// a surface of two faces back to back) the share `transmission` of the diffuse base passes through
// instead, by the GGX lobe mirrored through the surface, tinted by the base colour:
//   f_t(wo, wi) = kd transmission (1 - Fd) D G / (4 |n.wo| |n.wi|) at the half vector of wo and wi
//   mirrored, (wi.x, wi.y, -wi.z) (the extension's H_T = normalize(V - 2 (N.L) N + L)),
// and kd (1 - transmission) / pi (1 - Fd) remains diffuse. With KHR_materials_sheen (a sheen colour
// other than black) the sheen layer of sheen.h lies on top, the above its base. With
// KHR_materials_clearcoat (coat > 0) a clear coat lies on top of both, as the extension layers it:
//   f_coated(V, L) = (1 - Wc(V)) f(V, L) + Wc(V) D_c G_c / (4 |V.nc| |L.nc|),
//   Wc(V) = coat (0.04 + 0.96 (1 - |V.nc|)^5),
// D_c and G_c the GGX terms of alpha coatAlpha about the coat's own normal nc (its normal texture's,
// or the surface's without the base's normal texture). V is the viewer's side: the weight uses
// V.nc where a microfacet Fresnel term would use V.h, so the coated BRDF is not reciprocal
// (f(wo, wi) != f(wi, wo)) and importance transport takes its adjoint f(wi, wo).
// The sheen and the coat reflect only; light they pass goes on to the base, reflected or transmitted.
// Sampling: the coat (its GGX visible normals about nc) with probability Wc(wo) where wo is above
// the coat; else the sheen layer (uniformly over the hemisphere, as its fibres reflect most at
// grazing angles) with probability max3(sheenColour) E(n.wo), else the base's GGX visible normals,
// cosine lobe or mirrored visible normals, chosen by their weights at n.wo; every sample is weighed
// by the whole mixture. A reflection drawn below the surface, or a transmission above it, is no
// sample.
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
  float transmission = 0;      // KHR_materials_transmission's; 0: opaque
  static constexpr LobeField fields[] = {{"kd", true, 3},    {"ks", true, 3},  {"alpha", true, 1},
                                         {"f90", true, 1},   {"dielectric_f0", true, 1},
                                         {"dielectric_f90", true, 1}, {"masking", false, 1},
                                         {"sheen_colour", true, 3},   {"sheen_roughness", true, 1},
                                         {"coat", true, 1},           {"coat_alpha", true, 1},
                                         {"coat_normal", true, 3},    {"transmission", true, 1}};

  // What the kind may do; instanceFlags what this lobe does (it transmits where transmission > 0).
  static constexpr BsdfFlags flags = BsdfFlags::Reflection | BsdfFlags::Transmission | BsdfFlags::Diffuse |
                                     BsdfFlags::Glossy | BsdfFlags::TwoSided;
  BsdfFlags instanceFlags() const {
    return transmission > 0 ? flags : BsdfFlags::Reflection | BsdfFlags::Diffuse | BsdfFlags::Glossy | BsdfFlags::TwoSided;
  }

  // The share of the diffuse base that the dielectric's Fresnel term leaves, at Schlick weight w.
  float diffuseWeight(float w) const { return 1.0f - (dielectricF0 + (dielectricF90 - dielectricF0) * w); }

  // Probabilities of choosing the base's GGX reflection and its transmission (the rest: its cosine
  // lobe): the shares of the terms' weights at the Fresnel term of n.wo, the visible-normal
  // distribution's centre.
  struct BaseChoice {
    float specular = 0, transmitted = 0;
  };
  BaseChoice baseChoice(float woZ) const {
    const float w = schlickWeight(woZ);
    const float specular = (ks + (Rgb(f90) - ks) * w).average();
    const float under = kd.average() * diffuseWeight(w);
    const float sum = specular + under;
    if (!(sum > 0)) return {};
    return {specular / sum, under * transmission / sum};
  }
  float specularChoice(float woZ) const { return baseChoice(woZ).specular; }

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
    const BsdfValue layer = wi.z > 0 ? coatLayer(wo, wi) : BsdfValue{Rgb(0.0f), 0.0f};
    const float w = coatWeight(wo), pc = coatChoice(wo);
    return {under.f * (1.0f - w) + layer.f * w, pc * layer.pdf + (1.0f - pc) * under.pdf};
  }

  // f(wi, wo): what importance transport, carrying light from wo to wi, takes. The layers beneath the
  // coat are reciprocal; the coat's weight reads wi.
  Rgb adjointValue(Vec3 wo, Vec3 wi) const {
    const Rgb under = evaluateUnderCoat(wo, wi).f;
    if (!hasCoat()) return under;
    const float w = coatWeight(wi);
    return wi.z > 0 ? under * (1.0f - w) + coatLayer(wo, wi).f * w : under * (1.0f - w);
  }

  // Below the coat: the sheen layer over the base, or the base alone.
  BsdfValue evaluateUnderCoat(Vec3 wo, Vec3 wi) const {
    const BsdfValue base = evaluateBase(wo, wi);
    if (!hasSheen()) return base;
    // sheenChoice and sheenScaling, with E(n.wo) looked up once; the sheen reflects only.
    const SheenAlbedoTable& e = SheenAlbedoTable::get();
    const float m = sheenColour.maxComponent(), eo = e.at(wo.z, sheenRoughness);
    const float scaling = std::min(1.0f - m * eo, 1.0f - m * e.at(std::abs(wi.z), sheenRoughness));
    const float ps = m * eo;
    if (!(wi.z > 0)) return {base.f * scaling, (1.0f - ps) * base.pdf};
    const float sheen = sheenValue(sheenRoughness * sheenRoughness, wo.z, wi.z, normalize(wo + wi).z);
    return {sheenColour * sheen + base.f * scaling, ps * (0.5f * kInvPi) + (1.0f - ps) * base.pdf};
  }

  // The base: Appendix B's BRDF with the thin-walled transmission, and the density of its sampling.
  BsdfValue evaluateBase(Vec3 wo, Vec3 wi) const {
    const BaseChoice choice = baseChoice(wo.z);
    if (!(wi.z > 0)) {
      // Through the surface: the reflection lobe about the mirrored direction.
      const Vec3 mirrored{wi.x, wi.y, -wi.z};
      if (!(transmission > 0 && mirrored.z > 0)) return {Rgb(0.0f), 0.0f};
      const Vec3 h = normalize(wo + mirrored);
      const float lobe = ggxD(alpha, h) * smithMasking(masking, alpha, wo.z, mirrored.z) / (4.0f * wo.z * mirrored.z);
      return {kd * (transmission * diffuseWeight(schlickWeight(dot(wo, h))) * lobe),
              choice.transmitted * ggxReflectionPdf(alpha, wo, mirrored)};
    }
    const Vec3 h = normalize(wo + wi);
    const float w = schlickWeight(dot(wo, h));
    const Rgb F = ks + (Rgb(f90) - ks) * w;
    const float specular = ggxD(alpha, h) * smithMasking(masking, alpha, wo.z, wi.z) / (4.0f * wo.z * wi.z);
    return {kd * (kInvPi * diffuseWeight(w) * (1.0f - transmission)) + F * specular,
            choice.specular * ggxReflectionPdf(alpha, wo, wi) +
                (1.0f - choice.specular - choice.transmitted) * cosineHemispherePdf(wi.z)};
  }

  BsdfSample sample(Vec3 wo, float u, Vec2 u2, Transport transport) const {
    if (wo.z <= 0) return {};
    bool through = false;
    const Vec3 wi = sampleDirection(wo, u, u2, through);
    BsdfSample s = mixtureSample(*this, wo, wi, through);
    // Importance flows from L to V: the adjoint f(wi, wo), which only the coat's weight makes differ.
    if (s.valid && hasCoat() && transport == Transport::Importance)
      s.weight = adjointValue(wo, s.wi) * (std::abs(s.wi.z) / s.pdf);
    return s;
  }

  // A direction from one of the mixture's terms, `u` choosing the term; `through` says whether the
  // term transmits.
  Vec3 sampleDirection(Vec3 wo, float u, Vec2 u2, bool& through) const {
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
    const BaseChoice choice = baseChoice(wo.z);
    if (u < choice.specular) return reflect(wo, sampleGgxVisibleNormal(alpha, wo, u2));
    if (u < choice.specular + choice.transmitted) {
      through = true;
      const Vec3 r = reflect(wo, sampleGgxVisibleNormal(alpha, wo, u2));
      return {r.x, r.y, -r.z};
    }
    return sampleCosineHemisphere(u2);
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
  // The Lambertian term, under the sheen and the coat at normal incidence, less what transmits.
  Rgb diffuse() const {
    return (hasSheen() ? kd * sheenScaling(1.0f, 1.0f) : kd) * ((1.0f - coat * 0.04f) * (1.0f - transmission));
  }

  Rgb diffuseShare(Vec3 wo, Vec3 wi) const {
    if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
    const Rgb f = evaluate(wo, wi).f;
    if (f.isBlack()) return Rgb(0.0f);
    const float w = schlickWeight(dot(wo, normalize(wo + wi)));
    const float scaling = (hasSheen() ? sheenScaling(wo.z, wi.z) : 1.0f) * (hasCoat() ? 1.0f - coatWeight(wo) : 1.0f);
    return channelShare(lambertianValue(kd, wo.z, wi.z).f * (diffuseWeight(w) * scaling * (1.0f - transmission)), f);
  }
};
static_assert(sizeof(GltfMetalRoughLobe) == lobeFieldBytes<GltfMetalRoughLobe>(), "a lobe is a plain record of its fields");

}  // namespace lucent
