// Area particle links (3.1, 4.1): per particle, n_s x n_s directions stratified over the cosine-
// weighted hemisphere about its normal, each traced with Embree to its first hit and linked to the
// area particle nearest to that hit on the side the ray arrives from.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/trace/visibility.h"
#include "methods/particles/area_particles.h"

namespace lucent {

// The links of every particle, or of some: row r holds particle rowParticles[r]'s (every particle's,
// row i particle i's, when rowParticles is empty).
struct ParticleLinks {
  uint32_t strata = 0;                 // n_s: the links of a particle are n_s x n_s
  std::vector<uint32_t> targets;       // row r's link k at r * n_s^2 + k; kNoParticle: none
  std::vector<uint32_t> rowParticles;  // empty: row i is particle i
  uint32_t perParticle() const { return strata * strata; }
  std::span<const uint32_t> row(size_t r) const { return std::span(targets).subspan(r * perParticle(), perParticle()); }
  // Every particle's links only (rowParticles empty).
  std::span<const uint32_t> of(uint32_t particle) const { return row(particle); }
};

struct LinkCounters {
  uint64_t rays = 0;
  uint64_t misses = 0;     // rays that left the scene
  uint64_t unmatched = 0;  // hits with no particle facing the ray within the search radius
};

// Link k's direction about particle `index` (stratum k of the n_s x n_s grid over the unit square,
// jittered, mapped to the cosine-weighted hemisphere): the numbers of particle `index` come from
// one generator keyed by (seed, index), drawn in link order.
struct LinkDirections {
  uint64_t seed = 0;
  uint32_t strata = 4;
  // All n_s^2 directions of a particle, into `out`.
  void of(const AreaParticle& p, uint32_t index, Vec3* out) const;
};

// Stage G2 or G3: the links of the particles `only` names (every particle's when it is empty), the
// same whichever others are built. A hit links to nearestFacingParticle(hit, the hit
// triangle's normal on the ray's side, searchRadius): light stays on the side of a wall it
// arrived on (notes A2). Rays are traced in
// packets of 16 that share their particle's origin.
ParticleLinks buildParticleLinks(const Scene& scene, const Visibility& vis, std::span<const AreaParticle> particles,
                                 const OrientedPointGrid& grid, const LinkDirections& directions, float searchRadius,
                                 LinkCounters& counters, std::span<const uint32_t> only = {});

}  // namespace lucent
