// Area particles (Chang, Park and Ihm, 3.1 and 4.2.1): small pieces of the surfaces, one per side
// of a surface that light can reach, where light arrives and from where it leaves; and the uniform
// grid that finds the particle nearest to a point.
#pragma once
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "lucent/core/oriented_point_grid.h"
#include "lucent/core/stats.h"
#include "lucent/methods/particles.h"
#include "lucent/methods/particles_records.h"
#include "lucent/scene/scene.h"
#include "lucent/techniques/points/point_hierarchy.h"
#include "lucent/trace/visibility.h"

namespace lucent {

inline constexpr uint32_t kNoParticle = kNoPoint;

struct AreaParticleOptions {
  uint32_t positions = 50000;  // places on the surfaces (the paper: 50,000 for CBOX, 150,000 for SPONZA)
  ParticleSides sides = ParticleSides::Both;
  PointSamplingOptions sampling;
};

struct AreaParticles {
  std::vector<AreaParticle> particles;  // by position, the front side's first
  float spacing = 0;                    // sqrt(area per position): the mean distance between neighbours
  int sides = 2;
};

// Stage "area_particles" (G1): positions uniform by area (samplePoints), each particle standing
// for the same area (5.2: "distributed uniformly", hence 4.3.1's constant Delta A = A / N).
// Throws std::invalid_argument for a scene without area.
AreaParticles distributeAreaParticles(const Scene& scene, const AreaParticleOptions& options, RenderStats* stats);

struct CatchmentCounters {
  uint64_t samples = 0;    // surface points looked up (per side)
  uint64_t unmatched = 0;  // of those, points with no particle within the radius
  uint64_t empty = 0;      // particles no point reached (given half a point's area)
};

// Stage "particle_areas": each particle's Delta A as its catchment, the share of its side of the
// surface for which it is nearestFacingParticle, measured with about samplesPerPosition
// low-discrepancy surface points per position (each triangle's share, at least one). With equal areas, the particles
// that hold the most surface would both collect more flux (links land on them more often) and be
// gathered more often, and the estimate would be too bright by the squared coefficient of
// variation of the areas (README, "Departures").
void measureCatchments(const Scene& scene, AreaParticles& area, const OrientedPointGrid& grid, float radius,
                       uint32_t samplesPerPosition, uint64_t seed, CatchmentCounters& counters);

// Which particles face another surface nearer than `reach` along their normal (with `reach` a
// particle spacing: the ceiling above a two-sided lamp hung just beneath it, a floor under a box
// standing on it). The light between such surfaces is held in a gap that the particles cannot
// resolve: a covered particle's light (above the lamp, the back face's L pi) would reach the room
// through the links that end at it and the estimation lists that hold it, where the gap lets out
// almost none. One ray each along the normal, in packets.
std::vector<uint8_t> coveredParticles(const Visibility& vis, std::span<const AreaParticle> particles, float reach);

// The particles' positions and normals in a grid of cells about `cellSize` wide, less those marked
// in `left` (empty: none), which nothing then finds.
OrientedPointGrid buildParticleGrid(std::span<const AreaParticle> particles, float cellSize,
                                    std::span<const uint8_t> left = {});

// The particle nearest to `point` of those that face the way `side` does (normal . side > 0),
// within `radius`; kNoParticle if there is none. Of equally near ones, the lowest index. With
// `side` the normal of a hit's surface on the side a ray arrived from, the particle lies on that
// side: not behind a zero-thickness wall, whose other side's particles face the other way, nor on
// the far side of a neighbouring surface at a corner.
inline uint32_t nearestFacingParticle(const OrientedPointGrid& grid, Vec3 point, Vec3 side, float radius) {
  return grid.nearest(point, radius, [&](const OrientedPoint& p, float) { return dot(p.normal, side) > 0; });
}

}  // namespace lucent
