#include "methods/particles/area_particles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "lucent/core/morton.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/surface.h"

namespace lucent {

namespace {

// Surface points in the 3-D Morton order of their positions (ties by their former order).
void sortByMortonCode(const Scene& scene, std::vector<PointSample>& samples) {
  std::vector<std::pair<uint32_t, uint32_t>> order(samples.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
  Stopwatch clock;
  std::vector<PointSample> samples = samplePoints(scene, options.positions, options.sampling, stats);
  // In 3-D Morton order: neighbouring particles' links start near each other, which keeps the BVH
  // and the particle grid in cache (rays from a mesh's points in random order: 2.3x slower,
  // TOOLCHAIN.md).
  sortByMortonCode(scene, samples);
  double totalArea = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) totalArea += scene.triangleArea(t);
  AreaParticles out;
  out.sides = options.sides == ParticleSides::Both ? 2 : 1;
  const float area = float(totalArea / double(samples.size()));
  out.spacing = std::sqrt(area);
  out.particles.resize(samples.size() * size_t(out.sides));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const PointSample& s = samples[i];
      const SurfacePoint sp = surfaceAt(scene, s.triangle, s.b1, s.b2);
      const SurfaceBsdf bsdf = bsdfAt(scene, sp);
      // Particles are Lambertian (4.2.1: f = rho_d / pi): a glossy surface keeps its diffuse part,
      // mirrors and glass absorb.
      const Rgb rho = bsdf.isDelta() ? Rgb(0.0f) : bsdf.kd;
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

ParticleGrid buildParticleGrid(std::span<const AreaParticle> particles, float cellSize) {
  ParticleGrid g;
  Bounds3 b;
  for (const AreaParticle& p : particles) b.extend(p.position);
  if (b.empty()) b.extend({0, 0, 0});
  const Vec3 e = b.extent();
  constexpr double kMaxCells = double(1 << 24);
  double cell = std::max<double>(cellSize, 1e-30);
  auto cells = [&](double c) {
    return (std::floor(e.x / c) + 1) * (std::floor(e.y / c) + 1) * (std::floor(e.z / c) + 1);
  };
  while (cells(cell) > kMaxCells) cell *= 1.25;
  g.origin = b.lo;
  g.cellSize = float(cell);
  g.nx = int(std::floor(e.x / cell)) + 1;
  g.ny = int(std::floor(e.y / cell)) + 1;
  g.nz = int(std::floor(e.z / cell)) + 1;
  const size_t n = size_t(g.nx) * size_t(g.ny) * size_t(g.nz);
  auto cellOf = [&](Vec3 p) {
    return (size_t(g.cellCoord(p.z, g.origin.z, g.nz)) * size_t(g.ny) + size_t(g.cellCoord(p.y, g.origin.y, g.ny))) *
               size_t(g.nx) +
           size_t(g.cellCoord(p.x, g.origin.x, g.nx));
  };
  // A counting sort: stable, so each cell lists its particles in index order.
  g.cellStart.assign(n + 1, 0);
  for (const AreaParticle& p : particles) ++g.cellStart[cellOf(p.position) + 1];
  for (size_t c = 0; c < n; ++c) g.cellStart[c + 1] += g.cellStart[c];
  g.slots.resize(particles.size());
  std::vector<uint32_t> next(g.cellStart.begin(), g.cellStart.end() - 1);
  for (uint32_t i = 0; i < uint32_t(particles.size()); ++i)
    g.slots[next[cellOf(particles[i].position)]++] = {particles[i].position, particles[i].normal, i};
  return g;
}

uint32_t nearestFacingParticle(const ParticleGrid& g, Vec3 point, Vec3 side, float radius) {
  uint32_t best = kNoParticle;
  float bestD2 = radius * radius;
  const int cx = g.cellCoord(point.x, g.origin.x, g.nx), cy = g.cellCoord(point.y, g.origin.y, g.ny),
            cz = g.cellCoord(point.z, g.origin.z, g.nz);
  auto visitCell = [&](int x, int y, int z) {
    const size_t c = (size_t(z) * size_t(g.ny) + size_t(y)) * size_t(g.nx) + size_t(x);
    for (uint32_t k = g.cellStart[c]; k < g.cellStart[c + 1]; ++k) {
      const GridSlot& p = g.slots[k];
      const Vec3 d = p.position - point;
      const float d2 = dot(d, d);
      if (dot(p.normal, side) > 0 && (d2 < bestD2 || (d2 == bestD2 && p.id < best))) bestD2 = d2, best = p.id;
    }
  };
  // The point's own cell first; then the cells of the cube about the point out to the best
  // distance found so far, each skipped when all of it is farther than the best.
  visitCell(cx, cy, cz);
  const float reach = std::sqrt(bestD2);
  const int x0 = g.cellCoord(point.x - reach, g.origin.x, g.nx), x1 = g.cellCoord(point.x + reach, g.origin.x, g.nx);
  const int y0 = g.cellCoord(point.y - reach, g.origin.y, g.ny), y1 = g.cellCoord(point.y + reach, g.origin.y, g.ny);
  const int z0 = g.cellCoord(point.z - reach, g.origin.z, g.nz), z1 = g.cellCoord(point.z + reach, g.origin.z, g.nz);
  auto gap = [&](int i, float v, float o) {  // distance along an axis from v to cell i
    const float lo = o + float(i) * g.cellSize, hi = lo + g.cellSize;
    return v < lo ? lo - v : v > hi ? v - hi : 0.0f;
  };
  for (int z = z0; z <= z1; ++z) {
    const float dz = gap(z, point.z, g.origin.z);
    for (int y = y0; y <= y1; ++y) {
      const float dy = gap(y, point.y, g.origin.y);
      for (int x = x0; x <= x1; ++x) {
        if (x == cx && y == cy && z == cz) continue;
        const float dx = gap(x, point.x, g.origin.x);
        if (dx * dx + dy * dy + dz * dz > bestD2) continue;
        visitCell(x, y, z);
      }
    }
  }
  return best;
}

void measureCatchments(const Scene& scene, AreaParticles& area, const ParticleGrid& grid, float radius,
                       uint32_t samplesPerPosition, uint64_t seed, CatchmentCounters& counters) {
  const uint64_t positions = area.particles.size() / size_t(area.sides);
  const uint32_t triangles = scene.triangleCount();
  double totalArea = 0;
  for (uint32_t t = 0; t < triangles; ++t) totalArea += scene.triangleArea(t);
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
