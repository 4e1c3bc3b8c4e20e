// Radiance particles and their estimation lists (3.2): each triangle is cut into m x m
// subtriangles (m from its longest edge and a size threshold), whose vertices, enumerated row by
// row as triangle strips are, are the triangle's radiance particles, one set per side. Nothing
// about them is stored but each triangle's m and first index: a hit's barycentrics give its
// subtriangle's three particles and their interpolation weights. Each radiance particle has the
// list of area particles within a radius whose normals are close to its own.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "lucent/scene/scene.h"
#include "methods/particles/area_particles.h"

namespace lucent {

// A triangle's radiance particles: ids first .. first + sides * (m+1)(m+2)/2 - 1, the front
// side's (counter-clockwise winding normal) before the back side's.
struct TriangleTessellation {
  uint32_t first = 0;
  uint32_t segments = 1;  // m: each edge is cut into m pieces
};
static_assert(sizeof(TriangleTessellation) == 8 && std::is_trivially_copyable_v<TriangleTessellation>);

inline constexpr uint32_t kMaxTessellationSegments = 128;

inline constexpr uint32_t tessellationVertices(uint32_t m) { return (m + 1) * (m + 2) / 2; }
// Vertex (i, j), i rows up from edge v0-v1 and j along it (i + j <= m), in strip order.
inline constexpr uint32_t tessellationIndex(uint32_t i, uint32_t j, uint32_t m) {
  return i * (m + 1) - i * (i - 1) / 2 + j;
}

// A radiance particle by its place: its triangle, side and vertex (i, j).
struct RadianceParticleAt {
  uint32_t triangle = 0, side = 0, i = 0, j = 0;
};

struct Tessellation {
  std::vector<TriangleTessellation> triangles;
  uint32_t sides = 2;
  uint64_t count = 0;  // radiance particles in all
  // Vertex (i, j)'s position on the triangle.
  Vec3 position(const Scene& scene, uint32_t triangle, uint32_t i, uint32_t j) const;
  // Where radiance particle `id` is (a search over the triangles' first ids).
  RadianceParticleAt locate(uint32_t id) const;
};

// Stage G4: m = ceil(longest edge / threshold), at most kMaxTessellationSegments. Throws
// MemoryLimitError beyond 2^32 radiance particles.
Tessellation tessellate(const Scene& scene, float threshold, uint32_t sides);

// The three radiance particles around barycentrics (b1, b2) of a triangle's side and their weights.
struct SubtriangleWeights {
  uint32_t ids[3];
  float weights[3];
};
SubtriangleWeights subtriangleAt(const Tessellation& t, uint32_t triangle, uint32_t side, float b1, float b2);

// Whether a particle at offset d from a radiance particle, both with these normals (at most
// acos(minCosine) apart), can lie on one smooth surface with it: on any smooth surface the chord
// between two points is perpendicular to the mean of their normals (exactly on a sphere), and
// across a fold between facets it leans from that plane by at most the sine of half the fold. A
// particle further off that plane lies on another surface that faces the same way: the far face
// of a thick wall seen from inside the wall, a panel just in front of a wall.
inline float onSurfaceSlope(float minCosine) { return std::sqrt(std::max(0.0f, (1.0f - minCosine) * 0.5f)); }
inline bool onSameSurface(Vec3 d, Vec3 normal, Vec3 otherNormal, float slope) {
  const Vec3 mean = normal + otherNormal;
  const float off = dot(d, mean);
  return off * off <= slope * slope * dot(d, d) * dot(mean, mean);
}

// Lists in CSR form, one per radiance particle asked for: the k-th one's area particles are
// particles[offsets[k] .. offsets[k+1]), in index order.
struct EstimationLists {
  std::vector<uint64_t> offsets;
  std::vector<uint32_t> particles;
  std::span<const uint32_t> list(size_t k) const {
    return std::span(particles).subspan(offsets[k], offsets[k + 1] - offsets[k]);
  }
};

// Stage G5: for each radiance particle of `ids`, the area particles within `radius` of it whose
// normal n satisfies n . n_r >= minCosine, n_r the normal of the radiance particle's side, and
// which lie on the same surface (onSameSurface). `grid`
// should have cells about `radius` wide. Throws MemoryLimitError when the lists would not fit.
EstimationLists buildEstimationLists(const Scene& scene, const Tessellation& t, const OrientedPointGrid& grid, float radius,
                                     float minCosine,
                                     std::span<const uint32_t> ids);

}  // namespace lucent
