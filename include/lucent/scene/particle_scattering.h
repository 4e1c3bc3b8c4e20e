// Scattering a particle (a photon, the light path of a virtual point light) so that particle tracing
// converges to what the path tracer computes under shading normals (Veach 1997, section 5.3).
//
// The path tracer reflects radiance towards a viewer with the shading normal's cosine of the light's
// direction, and counts nothing from directions below the shading normal or the true surface; where
// the viewer itself is on the other side of the shading normal than of the true surface it takes the
// geometric normal instead (eye_paths.cpp, pathtracer.cpp). A particle's flux arrives per unit of
// true area, with the geometric cosine. So a particle arriving from wo (towards where it came from)
// carries, for a viewer in direction wi, the BSDF in the frame the path tracer would use for that
// viewer times
//   cos(wo, normal used) / |cos(wo, geometric)|,
// and leaves towards wi with the geometric cosine |cos(wi, geometric)|. Directions wi come from two
// strategies over two disjoint regions: the BSDF's sampling about the shading normal where wi is
// above both normals, and cosine sampling about the geometric normal for the wedge above the true
// surface and below the shading normal (where the viewer would make the path tracer take the
// geometric normal). The wedge is chosen with the probability of its share of the cosine-weighted
// hemisphere, (1 - cos(shading, geometric)) / 2; without shading normals it is empty, nothing more
// is drawn, and the result is the BSDF sample unchanged.
//
// Mirror and glass reflect about the shading normal alone (their wedge directions, where the path
// tracer would reflect about the geometric normal, are left out), with the cosine ratios above.
#pragma once
#include <cmath>

#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/surface.h"

namespace lucent {

struct ParticleScatter {
  Vec3 wi;     // direction the particle leaves in
  Rgb weight;  // multiplies its power (before Russian roulette)
  bool delta = false;
  bool valid = false;
};

// The shading normal on the particle's side of the surface (glass keeps the winding's).
inline Vec3 particleShadingNormal(const SurfaceBsdf& bsdf, const SurfacePoint& sp, Vec3 wo) {
  const bool front = dot(wo, sp.geometricNormal) > 0;
  return bsdf.type != MaterialType::Glass && !front ? -sp.shadingNormal : sp.shadingNormal;
}

// What a particle arriving from wo stores for a viewer above its shading normal: the ratio of the
// shading to the geometric cosine of wo, zero where wo is below the shading normal.
inline float particleArrivalRatio(const SurfacePoint& sp, Vec3 n, Vec3 wo) {
  const float cosGeometric = std::abs(dot(wo, sp.geometricNormal)), cosShading = dot(wo, n);
  return cosGeometric > 0 && cosShading > 0 ? cosShading / cosGeometric : 0.0f;
}

// Scatters a particle arriving from wo; uLobe and u2 are the BSDF sample's numbers, rng gives the
// strategy's where the surface has a wedge.
inline ParticleScatter scatterParticle(const SurfaceBsdf& bsdf, const SurfacePoint& sp, Vec3 wo, float uLobe,
                                       Vec2 u2, Rng& rng) {
  ParticleScatter out;
  const Vec3 ng = sp.geometricNormal;
  const Vec3 n = particleShadingNormal(bsdf, sp, wo);
  const float cosInGeometric = std::abs(dot(wo, ng));
  const float cosInShading = bsdf.type == MaterialType::Glass ? std::abs(dot(wo, n)) : dot(wo, n);
  if (!(cosInGeometric > 0)) return out;
  const float arrival = cosInShading > 0 ? cosInShading / cosInGeometric : 0.0f;

  // The wedge's probability (non-specular surfaces only); no number is drawn where it is empty.
  const Vec3 ngSide = dot(wo, ng) > 0 ? ng : -ng;
  const float wedge = bsdf.isDelta() ? 0.0f : 0.5f * (1.0f - std::min(1.0f, dot(n, ngSide)));
  if (wedge > 0 && rng.uniform() < wedge) {
    // The wedge: the path tracer's viewer there takes the geometric normal, for the BSDF and the
    // cosine of wo (whose ratio to the geometric one is then 1).
    const Frame frame(ngSide);
    const Vec3 local = sampleCosineHemisphere(u2);
    const Vec3 wi = frame.toWorld(local);
    if (dot(wi, n) > 0 || !(local.z > 0)) return out;  // the other strategy's region
    // f * cos / (wedge * cos / pi)
    out.weight = evalBsdf(bsdf, local, frame.toLocal(wo)) * (kPi / wedge);
    out.wi = wi;
    out.valid = !out.weight.isBlack();
    return out;
  }
  if (!(arrival > 0)) return out;
  const Frame frame(n);
  const Vec3 woLocal = frame.toLocal(wo);
  const BsdfSample bs = sampleBsdf(bsdf, woLocal, uLobe, u2, Transport::Importance);
  if (!bs.valid || !(std::abs(bs.wi.z) > 0)) return out;
  const Vec3 wi = frame.toWorld(bs.wi);
  // Leaving on the other side of the true surface than the BSDF means (a shading-normal leak): none.
  const bool transmits = bs.wi.z * woLocal.z < 0;
  if ((dot(wi, ng) * dot(wo, ng) < 0) != transmits) return out;
  out.wi = wi;
  out.weight = bs.weight;
  // Where the normals agree the ratios are 1 (not computed: rounding would change flat scenes).
  if (!(n == ngSide)) out.weight = out.weight * (arrival * std::abs(dot(wi, ng)) / std::abs(bs.wi.z) / (1.0f - wedge));
  out.delta = bs.delta;
  out.valid = true;
  return out;
}

}  // namespace lucent
