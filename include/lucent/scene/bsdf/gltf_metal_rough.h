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
// and kd (1 - transmission) / pi (1 - Fd) remains diffuse. With KHR_materials_volume (volumeIor > 0:
// the surface bounds a medium of that index on its winding's inside, and the lobe is not two-sided)
// the transmitted share refracts instead, through the microfacets as Walter et al. 2007 give it:
//   f_t(wo, wi) = kd transmission (1 - Fd) |wo.h| |wi.h| / (|n.wo| |n.wi|)
//                 eta_o^2 D(h) G / (eta_o wo.h + eta_i wi.h)^2,
// h the generalized half vector along eta_o wo + eta_i wi (eta_o the index on wo's side, eta_i on
// wi's), scaled by eta_o^2 as radiance is (importance by eta_i^2: the adjoint f(wi, wo)). The
// Schlick weight reads the cosine outside, as the extension's three cases say: |wo.h| from outside;
// from inside that of the direction refracted out, and F = Fd = 1 where there is none (total
// internal reflection). From inside, the surface reflects F D G / (4 |n.wo| |n.wi|) and passes out
// f_t as above (times the sheen's scaling and 1 - Wc of the outer direction, as light entering
// has); the diffuse base and the metal absorb what reaches them from inside. An index within
// kIndexMatched of 1 bends nothing: its transmission is a Dirac delta straight through, of weight
// kd transmission (1 - Fd) at n.wo times the sheen's scaling and 1 - Wc of the outer direction. With KHR_materials_sheen (a sheen colour
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
  // KHR_materials_volume: the index of refraction of the medium the surface bounds (on its winding's
  // inside, the frame's -z); 0: a thin wall.
  float volumeIor = 0;
  static constexpr LobeField fields[] = {{"kd", true, 3},    {"ks", true, 3},  {"alpha", true, 1},
                                         {"f90", true, 1},   {"dielectric_f0", true, 1},
                                         {"dielectric_f90", true, 1}, {"masking", false, 1},
                                         {"sheen_colour", true, 3},   {"sheen_roughness", true, 1},
                                         {"coat", true, 1},           {"coat_alpha", true, 1},
                                         {"coat_normal", true, 3},    {"transmission", true, 1},
                                         {"volume_ior", true, 1}};

  // What the kind may do; instanceFlags what this lobe does: it transmits where transmission > 0,
  // specularly too where its GGX lobe is at most kSmoothAlpha wide (or an index-matched volume's
  // delta passes light straight), and keeps its inside where it bounds a volume.
  static constexpr BsdfFlags flags = BsdfFlags::Reflection | BsdfFlags::Transmission | BsdfFlags::Diffuse |
                                     BsdfFlags::Glossy | BsdfFlags::Specular | BsdfFlags::TwoSided;
  BsdfFlags instanceFlags() const {
    const BsdfFlags reflecting = BsdfFlags::Reflection | BsdfFlags::Diffuse | BsdfFlags::Glossy;
    if (!(transmission > 0) && !boundsVolume()) return reflecting | BsdfFlags::TwoSided;
    const bool specular = alpha <= kSmoothAlpha || (boundsVolume() && indexMatched());
    return reflecting | BsdfFlags::Transmission | (specular ? BsdfFlags::Specular : BsdfFlags::None) |
           (boundsVolume() ? BsdfFlags::None : BsdfFlags::TwoSided);
  }
  // A GGX lobe this narrow spreads light over about a degree: the photon methods follow the light it
  // passes as they follow glass (a specular chain), not estimating from photons' directions under it.
  static constexpr float kSmoothAlpha = 0.01f;

  // Indices this close to 1 refract by less than 0.25 degrees (at 80 degrees' incidence), and
  // Walter's half vector, from eta_o wo + eta_i wi, loses its digits to cancellation there.
  static constexpr float kIndexMatched = 1e-3f;
  bool boundsVolume() const { return volumeIor > 0; }
  bool indexMatched() const { return std::abs(volumeIor - 1.0f) < kIndexMatched; }

  // The share of the diffuse base that the dielectric's Fresnel term leaves, at Schlick weight w.
  float diffuseWeight(float w) const { return 1.0f - (dielectricF0 + (dielectricF90 - dielectricF0) * w); }

  // Probabilities of choosing the base's GGX reflection and its transmission (the rest: its cosine
  // lobe): the shares of the terms' weights at the Fresnel term of n.wo, the visible-normal
  // distribution's centre.
  struct BaseChoice {
    float specular = 0, transmitted = 0;
  };
  [[gnu::always_inline]] BaseChoice baseChoice(float woZ) const {
    const float w = schlickWeight(woZ);
    const float specular = (ks + (Rgb(f90) - ks) * w).average();
    const float under = kd.average() * diffuseWeight(w);
    const float sum = specular + under;
    return {sum > 0 ? specular / sum : 0.0f, sum > 0 ? under * transmission / sum : 0.0f};
  }
  float specularChoice(float woZ) const { return baseChoice(woZ).specular; }

  // The Schlick weight at a microfacet normal h (h.z > 0) for the viewer wo, read outside: from
  // |wo.h| outside, from the direction refracted out inside; -1 where none is (total internal
  // reflection).
  float interfaceWeight(Vec3 wo, Vec3 h) const {
    const float c = std::abs(dot(wo, h));
    if (wo.z > 0) return schlickWeight(c);
    const float sin2 = volumeIor * volumeIor * (1.0f - c * c);
    return sin2 < 1.0f ? schlickWeight(std::sqrt(1.0f - sin2)) : -1.0f;
  }
  // The Fresnel term F and the share 1 - Fd that the base passes, at Schlick weight w (-1: total
  // internal reflection).
  Rgb fresnelAt(float w) const { return w < 0 ? Rgb(1.0f) : ks + (Rgb(f90) - ks) * w; }
  float passedAt(float w) const { return w < 0 ? 0.0f : diffuseWeight(w); }
  // Probability of reflecting rather than refracting from inside, at Schlick weight w: their
  // weights' shares, reflecting where the two are 0.
  float insideReflectionChoice(float w) const {
    const float reflected = fresnelAt(w).average(), passed = kd.average() * transmission * passedAt(w);
    return reflected + passed > 0 ? reflected / (reflected + passed) : 1.0f;
  }

  // One microfacet interaction of the volume's boundary: its half vector (h.z > 0), the scalar
  // part of its value (without tint and Fresnel term), the density of sampling wi by the visible
  // normals of wo (before the choice of term) and its Schlick weight; none where wo and wi are not
  // on their sides of h.
  struct Microfacet {
    Vec3 h;
    float lobe = 0, density = 0, w = 0;
    bool valid = false;
  };
  // Walter et al. 2007's refraction, for wo and wi on opposite sides.
  Microfacet refraction(Vec3 wo, Vec3 wi) const {
    const bool outside = wo.z > 0;
    const float etaO = outside ? 1.0f : volumeIor, etaI = outside ? volumeIor : 1.0f;
    Microfacet m;
    const Vec3 sum = wo * etaO + wi * etaI;
    const float len = length(sum);
    if (!(len > 0)) return m;
    m.h = sum.z < 0 ? -sum / len : sum / len;
    const float oh = dot(wo, m.h), ih = dot(wi, m.h);
    if (!(oh * wo.z > 0) || !(ih * wi.z > 0)) return m;
    m.w = interfaceWeight(wo, m.h);
    if (m.w < 0) return m;
    const float denominator = (etaO * oh + etaI * ih) * (etaO * oh + etaI * ih);
    const float cosO = std::abs(wo.z), cosI = std::abs(wi.z);
    m.lobe = std::abs(oh * ih) / (cosO * cosI) * etaO * etaO * ggxD(alpha, m.h) *
             smithMasking(masking, alpha, cosO, cosI) / denominator;
    m.density = ggxVisibleNormalPdf(alpha, outside ? wo : -wo, m.h) * std::abs(ih) * etaI * etaI / denominator;
    m.valid = true;
    return m;
  }
  // Reflection inside, wo and wi below the surface.
  Microfacet internalReflection(Vec3 wo, Vec3 wi) const {
    Microfacet m;
    const Vec3 sum = -(wo + wi);
    const float len = length(sum);
    if (!(len > 0)) return m;
    m.h = sum / len;
    m.w = interfaceWeight(wo, m.h);
    const float cosO = -wo.z, cosI = -wi.z;
    m.lobe = ggxD(alpha, m.h) * smithMasking(masking, alpha, cosO, cosI) / (4.0f * cosO * cosI);
    m.density = ggxReflectionPdf(alpha, -wo, -wi);
    m.valid = true;
    return m;
  }
  // What lies outside scales light passing in or out along the outer direction `out` (wo or wi):
  // the sheen's scaling of the two cosines and the coat's 1 - Wc(out).
  float outerScaling(float cosO, float cosI, Vec3 out) const {
    return (hasSheen() ? sheenScaling(cosO, cosI) : 1.0f) * (hasCoat() ? 1.0f - coatWeight(out) : 1.0f);
  }

  // From inside a volume (wo.z < 0): the reflection and the light refracted out.
  BsdfValue evaluateFromInside(Vec3 wo, Vec3 wi) const {
    if (wi.z < 0) {
      const Microfacet m = internalReflection(wo, wi);
      if (!m.valid) return {Rgb(0.0f), 0.0f};
      const float choice = insideReflectionChoice(indexMatched() ? interfaceWeight(wo, {0, 0, 1}) : m.w);
      return {fresnelAt(m.w) * m.lobe, choice * m.density};
    }
    if (!(wi.z > 0) || indexMatched()) return {Rgb(0.0f), 0.0f};
    const Microfacet m = refraction(wo, wi);
    if (!m.valid) return {Rgb(0.0f), 0.0f};
    const float passed = transmission * passedAt(m.w) * m.lobe * outerScaling(-wo.z, wi.z, wi);
    return {kd * passed, (1.0f - insideReflectionChoice(m.w)) * m.density};
  }

  // Light passing an index-matched boundary straight through, wo to -wo: the Dirac delta's weight.
  Rgb straightThrough(Vec3 wo) const {
    const float c = std::abs(wo.z);
    return kd * (transmission * passedAt(interfaceWeight(wo, {0, 0, 1})) * outerScaling(c, c, wo.z > 0 ? wo : -wo));
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
    if (!(wo.z > 0)) return boundsVolume() && wo.z < 0 ? evaluateFromInside(wo, wi) : BsdfValue{Rgb(0.0f), 0.0f};
    const BsdfValue under = evaluateUnderCoat(wo, wi);
    if (!hasCoat()) return under;
    const BsdfValue layer = wi.z > 0 ? coatLayer(wo, wi) : BsdfValue{Rgb(0.0f), 0.0f};
    const float w = coatWeight(wo), pc = coatChoice(wo);
    return {under.f * (1.0f - w) + layer.f * w, pc * layer.pdf + (1.0f - pc) * under.pdf};
  }

  // f(wi, wo): what importance transport, carrying light from wo to wi, takes. The layers beneath the
  // coat are reciprocal; the coat's weight reads wi; a volume's boundary evaluates from either side.
  Rgb adjointValue(Vec3 wo, Vec3 wi) const {
    if (boundsVolume()) return evaluate(wi, wo).f;
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
      if (boundsVolume()) {
        const Microfacet m = indexMatched() ? Microfacet{} : refraction(wo, wi);
        if (!m.valid) return {Rgb(0.0f), 0.0f};
        return {kd * (transmission * passedAt(m.w) * m.lobe), choice.transmitted * m.density};
      }
      // Through a thin wall: the reflection lobe about the mirrored direction.
      const Vec3 mirrored{wi.x, wi.y, -wi.z};
      if (!(transmission > 0 && mirrored.z > 0)) return {Rgb(0.0f), 0.0f};
      const Vec3 h = normalize(wo + mirrored);
      const float lobe = ggxD(alpha, h) * smithMasking(masking, alpha, wo.z, mirrored.z) / (4.0f * wo.z * mirrored.z);
      return {kd * (transmission * diffuseWeight(schlickWeight(dot(wo, h))) * lobe),
              choice.transmitted * ggxReflectionPdf(alpha, wo, mirrored)};
    }
    return reflection(wo, wi, choice);
  }

  // The base's reflection, wo and wi above the surface (zero where either is not), and the density
  // of sampling wi by `choice`. Selects only: the path tracer's lane loop (shadeGltfLanes)
  // vectorizes this very function.
  [[gnu::always_inline]] BsdfValue reflection(Vec3 wo, Vec3 wi, BaseChoice choice) const {
    const Vec3 h = normalize(wo + wi);
    const float w = schlickWeight(dot(wo, h));
    const Rgb F = ks + (Rgb(f90) - ks) * w;
    const float specular = ggxD(alpha, h) * smithMasking(masking, alpha, wo.z, wi.z) / (4.0f * wo.z * wi.z);
    const Rgb f = kd * (kInvPi * diffuseWeight(w) * (1.0f - transmission)) + F * specular;
    const float pdf = choice.specular * ggxReflectionPdf(alpha, wo, wi) +
                      (1.0f - choice.specular - choice.transmitted) * cosineHemispherePdf(wi.z);
    const bool above = wo.z > 0 ? wi.z > 0 : false;
    return {{above ? f.r : 0.0f, above ? f.g : 0.0f, above ? f.b : 0.0f}, above ? pdf : 0.0f};
  }

  BsdfSample sample(Vec3 wo, float u, Vec2 u2, Transport transport) const {
    BsdfSample s;
    if (wo.z > 0) {
      bool through = false;
      const Vec3 wi = sampleDirection(wo, u, u2, through);
      if (through && indexMatched()) return straightSample(wo);
      s = mixtureSample(*this, wo, wi, through);
    } else if (boundsVolume() && wo.z < 0) {
      s = sampleFromInside(wo, u, u2);
    }
    // Importance flows from L to V: the adjoint f(wi, wo), which the coat's weight and refraction's
    // scaling make differ.
    if (s.valid && !s.delta && (hasCoat() || boundsVolume()) && transport == Transport::Importance)
      s.weight = adjointValue(wo, s.wi) * (std::abs(s.wi.z) / s.pdf);
    return s;
  }

  // From inside: a visible normal of the surface seen from below, then reflection or refraction
  // out by their weights there (at the normal for an index-matched boundary, whose refraction is the
  // delta straight out).
  BsdfSample sampleFromInside(Vec3 wo, float u, Vec2 u2) const {
    const Vec3 h = sampleGgxVisibleNormal(alpha, -wo, u2);
    const float w = interfaceWeight(wo, indexMatched() ? Vec3{0, 0, 1} : h);
    const float reflects = insideReflectionChoice(w);
    if (u >= reflects && indexMatched()) {
      BsdfSample s;
      s.wi = -wo, s.delta = s.valid = true, s.pdf = 1.0f - reflects;
      s.weight = straightThrough(wo) / s.pdf;
      return s;
    }
    Vec3 wi = reflect(wo, h);
    if (u >= reflects) {
      // Refracted out about the facet -h that faces wo, by eta = volumeIor / 1 (no total internal
      // reflection: its choice of reflecting is 1).
      const float cosI = -dot(wo, h), sin2 = volumeIor * volumeIor * (1.0f - cosI * cosI);
      if (!(sin2 < 1.0f)) return {};
      wi = wo * -volumeIor - h * (volumeIor * cosI - std::sqrt(1.0f - sin2));
    }
    BsdfSample s;
    s.wi = wi;
    if (u < reflects ? !(wi.z < 0) : !(wi.z > 0)) return s;
    const BsdfValue v = evaluateFromInside(wo, wi);
    s.pdf = v.pdf;
    if (!(s.pdf > 0)) return s;
    s.weight = v.f * (std::abs(wi.z) / s.pdf);
    s.valid = true;
    return s;
  }

  // The index-matched boundary's delta from outside, `u` having chosen its term in sampleDirection:
  // the chain of choices that leads there is its probability.
  BsdfSample straightSample(Vec3 wo) const {
    BsdfSample s;
    float p = baseChoice(wo.z).transmitted;
    if (hasSheen()) p *= 1.0f - sheenChoice(wo.z);
    if (hasCoat()) p *= 1.0f - coatChoice(wo);
    if (!(p > 0)) return s;
    s.wi = -wo, s.delta = s.valid = true, s.pdf = p;
    s.weight = straightThrough(wo) / p;
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
      const Vec3 h = sampleGgxVisibleNormal(alpha, wo, u2);
      if (boundsVolume()) {
        // Refracted in about h by eta = 1 / volumeIor (never totally reflected).
        const float eta = 1.0f / volumeIor, cosI = dot(wo, h);
        const float cosT = std::sqrt(std::max(0.0f, 1.0f - eta * eta * (1.0f - cosI * cosI)));
        return wo * -eta + h * (eta * cosI - cosT);
      }
      const Vec3 r = reflect(wo, h);
      return {r.x, r.y, -r.z};
    }
    return sampleCosineHemisphere(u2);
  }

  // At normal incidence (the base's scaling and the sheen's albedo there), under the coat's weight
  // there, the coat reflecting all it takes. The transmitted share counts with the diffuse one:
  // KHR_materials_transmission tints what passes by the base colour, so kd is the base's colour
  // whether it scatters or passes (a denoiser's albedo of glass is its tint, not black).
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
