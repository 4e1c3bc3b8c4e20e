// The photon map radiance estimate (Jensen 1996; Jensen 2001, eq. 7.6; Purcell et al. 2003, 2.3):
// the radiance reflected towards wo at x is
//
//   L(x, wo) ~ sum over photons p near x of f(x, wo, wi_p) * Phi_p / (pi r^2),
//
// over the photons within radius r of x that light the viewer's side of its surface (photonLights:
// photons on the other side of a thin wall, or on another wall at a corner, do not), and where the
// surface transmits those on its other face that light it through (photonLightsThrough). r is the
// radius of the search: the k-th nearest photon's distance on the kd-tree; the maximum radius when
// fewer than k photons lie within it. Here the point, the settings, the sums and the kd-tree's
// estimate; Purcell's grid maps add theirs (src/methods/photonmap/radiance_estimate.h).
#pragma once
#include <cstdint>

#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/bsdf.h"
#include "lucent/techniques/photons/kd_tree.h"
#include "lucent/techniques/photons/photon.h"

namespace lucent {

// A diffuse or glossy surface point seen from direction wo.
struct EstimatePoint {
  Vec3 position;
  Frame frame;        // shading frame whose normal is on the viewer's side (but for a volume's boundary)
  Vec3 woLocal;       // towards the viewer, in `frame`
  SurfaceBsdf bsdf;   // not only specular
  Vec3 facingNormal;  // the geometric normal on the viewer's side
  // The frame of a lobe with an inside (a volume's boundary) keeps its winding's normal, which a
  // viewer inside sees from below.
  SurfaceSide side() const { return {woLocal.z < 0 ? -frame.n : frame.n, facingNormal}; }
};

inline EstimatePoint estimatePoint(const ShadingPoint& sp) {
  EstimatePoint q;
  q.position = sp.position;
  q.frame = Frame(sp.normal);
  q.woLocal = q.frame.toLocal(sp.wo);
  q.bsdf = sp.bsdf;
  q.facingNormal = dot(sp.wo, sp.geometricNormal) > 0 ? sp.geometricNormal : -sp.geometricNormal;
  return q;
}

struct EstimateSettings {
  uint32_t k = 50;
  float maxRadius = 1;
  uint32_t shells = 0;  // kNN-grid: stop after this many shells (the running estimate); 0: to the end
};

// Per-thread counters of the estimate stage, summed at the end.
struct EstimateCounters {
  uint64_t queries = 0;
  uint64_t photonsUsed = 0;      // photons within the radius that light the viewer's side
  uint64_t photonsExamined = 0;  // distances computed (grids) or nodes visited (kd-tree)
  uint64_t cellsVisited = 0;     // grids only
  uint64_t unfinished = 0;       // kNN-grid searches stopped by `shells` before their end
  EstimateCounters& operator+=(const EstimateCounters& o) {
    queries += o.queries, photonsUsed += o.photonsUsed, photonsExamined += o.photonsExamined;
    cellsVisited += o.cellsVisited, unfinished += o.unfinished;
    return *this;
  }
};

// The maximum search radius when none is given: 0.1 x the scene's bounding-box diagonal.
inline float defaultMaxRadius(const Scene& scene) { return 0.1f * length(scene.bounds.extent()); }

namespace estimate_detail {

// A Lambertian surface's estimate from the power `inside` the disc of squared radius radius2 (> 0).
inline Rgb diffuseRadiance(Rgb inside, Rgb kd, float radius2) { return inside * (kd * kInvPi) * (1.0f / (kPi * radius2)); }

// Sums f * Phi over the photons; a Lambertian f is constant and applied once at the end. Keeps
// the farthest photon's share apart: when it defines the radius it is left out (see radiance()).
struct Accumulator {
  const EstimatePoint& q;
  SurfaceSide side;
  bool diffuse, transmits;
  Rgb sum, farthest;
  float farthestD2 = -1;
  uint32_t used = 0;

  explicit Accumulator(const EstimatePoint& point)
      : q(point), side(point.side()), diffuse(point.bsdf.onlyDiffuse()),
        transmits(has(point.bsdf.flags(), BsdfFlags::Transmission)) {}
  [[gnu::always_inline]] void add(const Photon& p, float d2) {
    // Which side the photon came from needs no unit incoming direction; the BSDF of a glossy
    // surface does. A surface that transmits is never only diffuse.
    const Vec3 incoming = octahedralDirection(p.direction), facing = photonFacing(p), offset = p.position - q.position;
    const bool front = photonLights(incoming, facing, offset, d2, side) ||
                       (transmits && photonLightsThrough(incoming, facing, offset, d2, side));
    const Rgb share = diffuse ? p.power * float(front) : front ? glossyShare(p) : Rgb();
    used += front;
    sum += share;
    if (d2 > farthestD2) farthestD2 = d2, farthest = share;
  }
  [[gnu::noinline]] Rgb glossyShare(const Photon& p) const {
    return evalBsdf(q.bsdf, q.woLocal, q.frame.toLocal(photonIncoming(p))) * p.power;
  }
  // The photon on the sphere that fixed the radius is not counted: the density estimate of m
  // photons over the disc through the m-th is biased by m / (m - 1) (Loftsgaarden and
  // Quesenberry 1965), 2% at k = 50. With the maximum radius (fewer than k found) all count.
  Rgb radiance(float radius2) const {
    if (!(radius2 > 0)) return {};
    const Rgb inside = farthestD2 == radius2 ? sum - farthest : sum;
    return diffuse ? diffuseRadiance(inside, q.bsdf.diffuse(), radius2) : inside * (1.0f / (kPi * radius2));
  }
};

}  // namespace estimate_detail

// On the kd-tree: the k nearest photons within the maximum radius (Jensen's max-heap search);
// `heap` holds at least k entries.
inline Rgb estimateRadiance(const PhotonKdTree& tree, const EstimatePoint& q, const EstimateSettings& settings,
                            PhotonDistance* heap, EstimateCounters& counters) {
  estimate_detail::Accumulator acc(q);
  const KdTreeResult r = kdTreeNearest(tree, q.position, settings.k, settings.maxRadius, heap);
  for (uint32_t i = 0; i < r.found; ++i) acc.add(tree.photons[heap[i].index], heap[i].d2);
  ++counters.queries;
  counters.photonsUsed += acc.used;
  counters.photonsExamined += r.nodesVisited;
  return acc.radiance(r.radius2);
}

}  // namespace lucent
