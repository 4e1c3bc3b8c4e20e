// The Lambertian lobe: f = kd / pi above the surface. The pattern every lobe follows (kinds.h).
#pragma once
#include "lucent/core/sampling.h"
#include "lucent/scene/bsdf/lobe.h"

namespace lucent {

// kd / pi and the cosine-weighted density, from local directions' cosines: both zero unless both
// directions are above the surface. Selects only: the path tracer's lane loop vectorizes it
// (shadeDiffuseLanes); conditions chained on one comparison each, not boolean algebra, which the
// vectorizer does not take.
inline BsdfValue lambertianValue(Rgb kd, float woZ, float wiZ) {
  const float bothAbove = woZ <= 0 ? 0.0f : wiZ <= 0 ? 0.0f : 1.0f;
  return {{bothAbove == 0 ? 0.0f : kd.r * kInvPi, bothAbove == 0 ? 0.0f : kd.g * kInvPi,
           bothAbove == 0 ? 0.0f : kd.b * kInvPi},
          bothAbove == 0 ? 0.0f : cosineHemispherePdf(wiZ)};
}

// A cosine-distributed direction, its density and weight; valid (pdf > 0) only where both
// directions are above the surface. Selects only, as above.
inline BsdfSample sampleLambertian(Rgb kd, float woZ, Vec2 u) {
  BsdfSample s;
  s.wi = sampleCosineHemisphere(u);
  s.pdf = woZ <= 0 ? 0.0f : s.wi.z <= 0 ? 0.0f : cosineHemispherePdf(s.wi.z);
  s.weight = kd * kInvPi * (s.wi.z / s.pdf);
  s.valid = s.pdf > 0;
  return s;
}

// Every lobe is a plain parameter struct with:
//   flags         what it does to light (lobe.h);
//   evaluate      f(wo, wi) and the density of `sample`, for wo and wi above the surface (the
//                 dispatch, evalBsdfAndPdf, returns zero otherwise and for specular lobes);
//   sample        wi given wo, `u` choosing among its terms, `u2` the direction;
//   albedo        the reflectance a first hit records in the albedo layer;
//   bound         an upper bound of the light it reflects, per channel (Russian roulette);
//   diffuse       its Lambertian term's albedo (the point-based methods' share; 0 for none);
//   diffuseShare  the share of f(wo, wi) that is the Lambertian term's (1 for a lobe of only it);
//   fields        its members as dumps name them (LobeField).
struct LambertianLobe {
  Rgb kd;
  static constexpr LobeField fields[] = {{"kd", true, 3}};

  static constexpr BsdfFlags flags = BsdfFlags::Reflection | BsdfFlags::Diffuse | BsdfFlags::TwoSided;
  BsdfValue evaluate(Vec3 wo, Vec3 wi) const { return lambertianValue(kd, wo.z, wi.z); }
  BsdfSample sample(Vec3 wo, float, Vec2 u2, Transport) const { return sampleLambertian(kd, wo.z, u2); }
  Rgb albedo() const { return kd; }
  Rgb bound() const { return kd; }
  Rgb diffuse() const { return kd; }
  Rgb diffuseShare(Vec3, Vec3) const { return Rgb(1.0f); }
};
static_assert(sizeof(LambertianLobe) == lobeFieldBytes<LambertianLobe>(), "a lobe is a plain record of its fields");

}  // namespace lucent
