#include "methods/particles/radiance_particles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "lucent/core/memory.h"
#include "lucent/core/stop.h"

namespace lucent {

Vec3 Tessellation::position(const Scene& scene, uint32_t triangle, uint32_t i, uint32_t j) const {
  const float m = float(triangles[triangle].segments);
  const Vec3 v0 = scene.vertex(triangle, 0), v1 = scene.vertex(triangle, 1), v2 = scene.vertex(triangle, 2);
  return v0 + (v1 - v0) * (float(j) / m) + (v2 - v0) * (float(i) / m);
}

Tessellation tessellate(const Scene& scene, float threshold, uint32_t sides) {
  Tessellation t;
  t.sides = sides;
  t.triangles.resize(scene.triangleCount());
  uint64_t next = 0;
  for (uint32_t tri = 0; tri < scene.triangleCount(); ++tri) {
    const Vec3 v0 = scene.vertex(tri, 0), v1 = scene.vertex(tri, 1), v2 = scene.vertex(tri, 2);
    const float longest = std::max({length(v1 - v0), length(v2 - v1), length(v0 - v2)});
    const double pieces = std::ceil(double(longest) / double(threshold));
    const uint32_t m = uint32_t(std::clamp(pieces, 1.0, double(kMaxTessellationSegments)));
    t.triangles[tri] = {uint32_t(std::min<uint64_t>(next, 0xffffffffu)), m};
    next += uint64_t(sides) * tessellationVertices(m);
  }
  if (next > 0xffffffffu)
    throw MemoryLimitError("the tessellation would make " + std::to_string(next) +
                           " radiance particles, more than 32-bit ids can name: raise --tessellation");
  t.count = next;
  return t;
}

SubtriangleWeights subtriangleAt(const Tessellation& t, uint32_t triangle, uint32_t side, float b1, float b2) {
  const TriangleTessellation& tt = t.triangles[triangle];
  const uint32_t m = tt.segments;
  const uint32_t base = tt.first + side * tessellationVertices(m);
  const float s = std::clamp(b1, 0.0f, 1.0f) * float(m), u = std::clamp(b2, 0.0f, 1.0f) * float(m);
  uint32_t j0 = std::min(uint32_t(s), m - 1), i0 = std::min(uint32_t(u), m - 1);
  if (i0 + j0 > m - 1) (j0 > 0 ? j0 : i0) -= 1;
  if (i0 + j0 > m - 1) (i0 > 0 ? i0 : j0) -= 1;
  float fs = s - float(j0), ft = u - float(i0);
  SubtriangleWeights w;
  if (fs + ft > 1 && i0 + j0 + 2 <= m) {
    w.ids[0] = base + tessellationIndex(i0 + 1, j0 + 1, m);
    w.ids[1] = base + tessellationIndex(i0, j0 + 1, m);
    w.ids[2] = base + tessellationIndex(i0 + 1, j0, m);
    w.weights[0] = std::max(fs + ft - 1, 0.0f), w.weights[1] = std::max(1 - ft, 0.0f), w.weights[2] = std::max(1 - fs, 0.0f);
  } else {
    // On the triangle's own diagonal edge rounding can put (fs, ft) just past it.
    if (fs + ft > 1) fs /= fs + ft, ft = 1 - fs;
    w.ids[0] = base + tessellationIndex(i0, j0, m);
    w.ids[1] = base + tessellationIndex(i0, j0 + 1, m);
    w.ids[2] = base + tessellationIndex(i0 + 1, j0, m);
    w.weights[0] = std::max(1 - fs - ft, 0.0f), w.weights[1] = std::max(fs, 0.0f), w.weights[2] = std::max(ft, 0.0f);
  }
  return w;
}

RadianceParticleAt Tessellation::locate(uint32_t id) const {
  const auto after = std::upper_bound(triangles.begin(), triangles.end(), id,
                                      [](uint32_t v, const TriangleTessellation& t) { return v < t.first; });
  RadianceParticleAt at;
  at.triangle = uint32_t(after - triangles.begin()) - 1;
  const uint32_t m = triangles[at.triangle].segments, vertices = tessellationVertices(m);
  const uint32_t offset = id - triangles[at.triangle].first;
  at.side = offset / vertices;
  const uint32_t index = offset % vertices;
  // Row i starts at tessellationIndex(i, 0, m); rows shrink by one vertex each.
  while (at.i < m && tessellationIndex(at.i + 1, 0, m) <= index) ++at.i;
  at.j = index - tessellationIndex(at.i, 0, m);
  return at;
}

EstimationLists buildEstimationLists(const Scene& scene, const Tessellation& t, const OrientedPointGrid& grid, float radius,
                                     float minCosine,
                                     std::span<const uint32_t> ids) {
  EstimationLists lists;
  requireMemory((ids.size() + 1) * sizeof(uint64_t), "the estimation lists' offsets", "raise --tessellation");
  lists.offsets.assign(ids.size() + 1, 0);
  const float r2 = radius * radius;
  // Radiance particle id's list into scratch, in index order.
  const float slope = onSurfaceSlope(minCosine);
  auto listOf = [&](uint32_t id, std::vector<uint32_t>& scratch) {
    const RadianceParticleAt at = t.locate(id);
    const Vec3 q = t.position(scene, at.triangle, at.i, at.j);
    const Vec3 normal = at.side == 0 ? scene.geometricNormal(at.triangle) : -scene.geometricNormal(at.triangle);
    scratch.clear();
    grid.forEachNear(q, radius, [&](const OrientedPoint& p) {
      const Vec3 d = p.position - q;
      if (dot(d, d) <= r2 && dot(p.normal, normal) >= minCosine && onSameSurface(d, normal, p.normal, slope))
        scratch.push_back(p.id);
    });
    std::sort(scratch.begin(), scratch.end());
  };
  // Searched twice, to count and then to fill: the lists can take hundreds of megabytes (Table 1:
  // 366 MB for MAZE), so their size is checked against the memory limit before they are made.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    std::vector<uint32_t> scratch;
    for (size_t k = r.begin(); k != r.end(); ++k) {
      listOf(ids[k], scratch);
      lists.offsets[k + 1] = scratch.size();
    }
  });
  for (size_t k = 0; k < ids.size(); ++k) lists.offsets[k + 1] += lists.offsets[k];
  requireMemory(lists.offsets.back() * sizeof(uint32_t), "the estimation lists",
                "lower --list-radius or raise --tessellation");
  lists.particles.resize(lists.offsets.back());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    std::vector<uint32_t> scratch;
    for (size_t k = r.begin(); k != r.end(); ++k) {
      listOf(ids[k], scratch);
      std::copy(scratch.begin(), scratch.end(), lists.particles.begin() + int64_t(lists.offsets[k]));
    }
  });
  return lists;
}

}  // namespace lucent
