#include "methods/particles/area_particles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "lucent/core/parallel.h"
#include "lucent/core/morton.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/core/stop.h"
#include "lucent/scene/surface.h"

namespace lucent {

namespace {

// Surface points in the 3-D Morton order of their positions (ties by their former order).
void sortByMortonCode(const Scene& scene, std::vector<PointSample>& samples) {
  std::vector<std::pair<uint32_t, uint32_t>> order(samples.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i)
      order[i] = {mortonCode(pointPosition(scene, samples[i]), scene.bounds), uint32_t(i)};
  });
  tbb::parallel_sort(order.begin(), order.end());
  std::vector<PointSample> sorted(samples.size());
  for (size_t i = 0; i < order.size(); ++i) sorted[i] = samples[order[i].second];
  samples = std::move(sorted);
}

}  // namespace

AreaParticles distributeAreaParticles(const Scene& scene, const AreaParticleOptions& options, RenderStats* stats) {
  beginStage("area_particles");
  Stopwatch clock;
  std::vector<PointSample> samples = samplePoints(scene, options.positions, options.sampling, stats);
  // In 3-D Morton order: neighbouring particles' links start near each other, which keeps the BVH
  // and the particle grid in cache (rays from a mesh's points in random order: 2.3x slower,
  // TOOLCHAIN.md).
  sortByMortonCode(scene, samples);
  const double totalArea = scene.surfaceArea();
  AreaParticles out;
  out.sides = options.sides == ParticleSides::Both ? 2 : 1;
  const float area = float(totalArea / double(samples.size()));
  out.spacing = std::sqrt(area);
  out.particles.resize(samples.size() * size_t(out.sides));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const PointSample& s = samples[i];
      const SurfacePoint sp = surfaceAt(scene, s.triangle, s.b1, s.b2);
      const SurfaceBsdf bsdf = bsdfAt(scene, sp);
      // Particles are Lambertian (4.2.1: f = rho_d / pi): a glossy surface keeps its diffuse part,
      // mirrors and glass absorb.
      const Rgb rho = bsdf.diffuse();
      for (int side = 0; side < out.sides; ++side)
        out.particles[i * size_t(out.sides) + size_t(side)] = {
            sp.position, side == 0 ? sp.geometricNormal : -sp.geometricNormal, area, rho, s.triangle};
    }
  });
  if (stats) {
    stats->addStage("area_particles", clock.seconds());
    stats->addCounter("area_particles", out.particles.size());
  }
  return out;
}

std::vector<uint8_t> coveredParticles(const Visibility& vis, std::span<const AreaParticle> particles, float reach) {
  std::vector<uint8_t> covered(particles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, particles.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    std::vector<Ray> rays;
    rays.reserve(r.size());
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const AreaParticle& p = particles[i];
      rays.push_back({offsetOrigin(p.position, p.normal, p.normal), p.normal});
      rays.back().tMax = reach;
    }
    occludedInPackets(vis, rays.size(), [&](size_t k) -> const Ray& { return rays[k]; },
                      [&](size_t k, bool blocked) { covered[r.begin() + k] = blocked; });
  });
  return covered;
}

OrientedPointGrid buildParticleGrid(std::span<const AreaParticle> particles, float cellSize,
                                    std::span<const uint8_t> left) {
  std::vector<OrientedPoint> points;
  points.reserve(particles.size());
  for (uint32_t i = 0; i < uint32_t(particles.size()); ++i)
    if (left.empty() || !left[i]) points.push_back({particles[i].position, particles[i].normal, i});
  return buildOrientedPointGrid(points, cellSize);
}

void measureCatchments(const Scene& scene, AreaParticles& area, const OrientedPointGrid& grid, float radius,
                       uint32_t samplesPerPosition, uint64_t seed, CatchmentCounters& counters) {
  const uint64_t positions = area.particles.size() / size_t(area.sides);
  const uint32_t triangles = scene.triangleCount();
  const double totalArea = scene.surfaceArea();
  const double perArea = double(positions) * double(samplesPerPosition) / totalArea;
  // Areas summed in 64-bit fixed point (units of 2^-k of the scene's area): the same sums
  // whichever thread adds first.
  const double scale = std::exp2(std::floor(std::log2(0x1p62 / std::max(totalArea, 1e-30))));
  std::vector<uint64_t> areaUnits(area.particles.size(), 0);
  std::atomic<uint64_t> looked{0}, unmatched{0};
  // Each triangle's points: as many as its share of the surface (at least one), each standing for
  // an equal part of it, at the points of a randomly shifted R2 lattice (Roberts 2018) warped onto
  // the triangle: low-discrepancy, and in an order that keeps the lookups near each other.
  constexpr double kPlastic = 1.32471795724474602596;
  const double a1 = 1.0 / kPlastic, a2 = 1.0 / (kPlastic * kPlastic);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, triangles, 64), [&](const tbb::blocked_range<uint32_t>& r) {
    stopPoint();
    uint64_t lookups = 0, lost = 0;
    for (uint32_t t = r.begin(); t != r.end(); ++t) {
      const double triangleArea = scene.triangleArea(t);
      if (!(triangleArea > 0)) continue;
      const uint64_t n = std::max<uint64_t>(1, uint64_t(std::llround(triangleArea * perArea)));
      const uint64_t units = uint64_t(std::llround(triangleArea / double(n) * scale));
      const Vec3 v0 = scene.vertex(t, 0), v1 = scene.vertex(t, 1), v2 = scene.vertex(t, 2);
      const Vec3 normal = scene.geometricNormal(t);
      Rng rng(seed, t);
      const double s1 = rng.uniform(), s2 = rng.uniform();
      for (uint64_t j = 0; j < n; ++j) {
        if (j % 4096 == 0) stopPoint();  // a large triangle holds many points
        const double u1 = s1 + double(j) * a1, u2 = s2 + double(j) * a2;
        const Vec2 b = sampleUniformTriangle({float(u1 - std::floor(u1)), float(u2 - std::floor(u2))});
        const Vec3 p = barycentric(v0, v1, v2, b.x, b.y);
        for (int side = 0; side < area.sides; ++side) {
          ++lookups;
          const uint32_t id = nearestFacingParticle(grid, p, side == 0 ? normal : -normal, radius);
          if (id == kNoParticle) {
            ++lost;
            continue;
          }
          std::atomic_ref<uint64_t>(areaUnits[id]).fetch_add(units, std::memory_order_relaxed);
        }
      }
    }
    looked += lookups;
    unmatched += lost;
  });
  // A particle that no point reached keeps a token area (half a point's), so that its radiance
  // is defined; nothing reaches it, so it holds no light.
  const float token = float(0.5 / perArea);
  uint64_t empty = 0;
  for (size_t i = 0; i < area.particles.size(); ++i) {
    empty += areaUnits[i] == 0;
    area.particles[i].area = areaUnits[i] > 0 ? float(double(areaUnits[i]) / scale) : token;
  }
  counters.samples += looked;
  counters.unmatched += unmatched;
  counters.empty += empty;
}

}  // namespace lucent
