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
// is drawn, and the result is the BSDF sample unchanged. A rough lobe with an inside (a volume's
// boundary) keeps its winding's normals and scatters to both sides: its wedge, of the same
// probability, is the two wedges of the sphere, one face's cosine lobe about the geometric normal
// picked at random.
//
// A mirror sends the particle to every viewer direction that the path tracer would reflect into its
// arrival: reflect(wo, ns) where that lies above both normals (weight Ks |cos(wi, ng)| /
// |cos(wo, ng)|) and reflect(wo, ng) where that lies in the wedge (weight Ks); where both exist,
// to one of them at random with twice the weight. Glass refracts and reflects about the shading
// normal alone (its wedge directions, where the path tracer would use the geometric normal, are
// left out), with the cosine ratios above; a particle arriving on one side of the shading normal
// and the other of the true surface goes no further there.
//
// Where the shading normal is the geometric one (a face without vertex normals) nothing of this is
// computed and no number drawn: the weight is the BSDF sample's, bit for bit.
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

// The shading normal on the particle's side of the surface (a lobe that is not two-sided, glass,
// keeps the winding's).
inline Vec3 particleShadingNormal(const SurfaceBsdf& bsdf, const SurfacePoint& sp, Vec3 wo) {
  const bool front = dot(wo, sp.geometricNormal) > 0;
  return twoSidedShading(bsdf) && !front ? -sp.shadingNormal : sp.shadingNormal;
}

inline bool hasShadingNormal(const SurfacePoint& sp) { return !(sp.shadingNormal == sp.geometricNormal); }

// The ratio of the shading to the geometric cosine of a particle's arrival from wo (n: the shading
// normal on its side), zero where wo lies on one side of the shading normal and the other of the
// true surface; what it stores for viewers above its shading normal.
inline float particleArrivalRatio(const SurfacePoint& sp, Vec3 n, Vec3 wo) {
  if (!hasShadingNormal(sp)) return 1.0f;
  const float cosGeometric = dot(wo, sp.geometricNormal), cosShading = dot(wo, n);
  const bool sameSide = (cosShading > 0) == (dot(n, sp.geometricNormal) * cosGeometric > 0);
  return cosGeometric != 0 && cosShading != 0 && sameSide ? std::abs(cosShading / cosGeometric) : 0.0f;
}

// Scatters a particle arriving from wo off bsdfAt's lobe (in world space); uLobe and u2 are the BSDF
// sample's numbers, rng gives the strategy's where the surface has a wedge.
inline ParticleScatter scatterParticle(const SurfaceBsdf& bsdf, const SurfacePoint& sp, Vec3 wo, float uLobe,
                                       Vec2 u2, Rng& rng) {
  ParticleScatter out;
  const Vec3 ng = sp.geometricNormal;
  const Vec3 n = particleShadingNormal(bsdf, sp, wo);
  if (!(std::abs(dot(wo, ng)) > 0)) return out;
  const bool shaded = hasShadingNormal(sp);
  const float arrival = particleArrivalRatio(sp, n, wo);

  // The wedge's probability (non-specular surfaces only); no number is drawn where it is empty. A
  // two-sided lobe's wedge lies on the particle's side; a lobe with an inside (a volume's boundary)
  // keeps its winding's normal, as glass does, and has a wedge on each side of its surface.
  const Vec3 ngSide = dot(wo, ng) > 0 ? ng : -ng;
  const bool twoSided = twoSidedShading(bsdf);
  const float wedge = shaded && !bsdf.isDelta()
                          ? 0.5f * (1.0f - std::min(1.0f, twoSided ? dot(n, ngSide) : dot(n, ng)))
                          : 0.0f;
  if (wedge > 0 && rng.uniform() < wedge) {
    // The wedge: the path tracer's viewer there takes the geometric normal (the winding's, for a
    // lobe with an inside), for the BSDF and the cosine of wo (whose ratio to the geometric one is
    // then 1). Two-sided: cosine-distributed about ngSide; else about either face's normal, each
    // with probability 1/2.
    const Vec3 axis = twoSided || rng.uniform() < 0.5f ? ngSide : -ngSide;
    const Vec3 shadingOnAxisSide = twoSided || dot(axis, ng) > 0 ? n : -n;
    const Frame sampling(axis);
    const Vec3 local = sampleCosineHemisphere(u2);
    const Vec3 wi = sampling.toWorld(local);
    if (dot(wi, shadingOnAxisSide) > 0 || !(local.z > 0)) return out;  // the other strategy's region
    // f * cos / (wedge * cos / pi), and the half for a lobe with an inside.
    if (twoSided) {
      out.weight = evalBsdf(bsdf.inFrame(sampling), local, sampling.toLocal(wo)) * (kPi / wedge);
    } else {
      const Frame winding(ng);
      out.weight = evalBsdf(bsdf.inFrame(winding), winding.toLocal(wi), winding.toLocal(wo)) * (2 * kPi / wedge);
    }
    out.wi = wi;
    out.valid = !out.weight.isBlack();
    return out;
  }
  // A specular reflector (a mirror) whose shading normal differs from the surface's.
  if (shaded && bsdf.isDelta() && !has(bsdf.flags(), BsdfFlags::Transmission)) {
    const Vec3 aboutShading = reflect(wo, n), aboutGeometric = reflect(wo, ngSide);
    const bool viaShading = arrival > 0 && dot(aboutShading, ngSide) > 0;
    const bool viaGeometric = dot(aboutGeometric, n) <= 0;
    if (!viaShading && !viaGeometric) return out;
    const bool both = viaShading && viaGeometric;
    const bool pickShading = viaShading && (!both || rng.uniform() < 0.5f);
    out.wi = pickShading ? aboutShading : aboutGeometric;
    out.weight = layerAlbedo(bsdf) * ((both ? 2.0f : 1.0f) *
                            (pickShading ? std::abs(dot(aboutShading, ng)) / std::abs(dot(wo, ng)) : 1.0f));
    out.delta = out.valid = true;
    return out;
  }
  if (!(arrival > 0)) return out;
  const Frame frame(n);
  const Vec3 woLocal = frame.toLocal(wo);
  const BsdfSample bs = sampleBsdf(bsdf.inFrame(frame), woLocal, uLobe, u2, Transport::Importance);
  if (!bs.valid) return out;
  const Vec3 wi = frame.toWorld(bs.wi);
  // Leaving on the other side of the true surface than the BSDF means (a shading-normal leak): none.
  if (leaksThroughSurface(wo, wi, ng, bs.wi.z * woLocal.z < 0)) return out;
  out.wi = wi;
  out.weight = bs.weight;
  if (shaded) {
    if (!(std::abs(bs.wi.z) > 0)) return out;
    out.weight = out.weight * (arrival * std::abs(dot(wi, ng)) / std::abs(bs.wi.z) / (1.0f - wedge));
  }
  out.delta = bs.delta;
  out.valid = true;
  return out;
}

}  // namespace lucent
