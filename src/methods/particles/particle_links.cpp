#include "methods/particles/particle_links.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/core/stop.h"

namespace lucent {

void LinkDirections::of(const AreaParticle& p, uint32_t index, Vec3* out) const {
  Rng rng(seed, index);
  const Frame frame(p.normal);
  const uint32_t n = strata * strata;
  for (uint32_t k = 0; k < n; ++k) {
    const Vec2 u = stratifiedSample2D(k, n, rng.uniform2());
    out[k] = frame.toWorld(sampleCosineHemisphere(u));
  }
}

ParticleLinks buildParticleLinks(const Scene& scene, const Visibility& vis, std::span<const AreaParticle> particles,
                                 const OrientedPointGrid& grid, const LinkDirections& directions, float searchRadius,
                                 LinkCounters& counters, std::span<const uint32_t> only) {
  ParticleLinks links;
  links.strata = directions.strata;
  links.rowParticles.assign(only.begin(), only.end());
  const uint32_t per = links.perParticle();
  const size_t rows = only.empty() ? particles.size() : only.size();
  links.targets.resize(rows * per);
  tbb::combinable<LinkCounters> local;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rows, 16), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    LinkCounters& c = local.local();
    std::vector<Vec3> dirs(per);
    for (size_t row = r.begin(); row != r.end(); ++row) {
      const uint32_t i = only.empty() ? uint32_t(row) : only[row];
      const AreaParticle& p = particles[i];
      directions.of(p, i, dirs.data());
      uint32_t* out = &links.targets[row * per];
      for (uint32_t first = 0; first < per; first += kWidestPacket) {
        const int count = int(std::min<uint32_t>(kWidestPacket, per - first));
        Hit hits[kWidestPacket];
        auto rayOf = [&](int j) {
          const Vec3 d = dirs[first + uint32_t(j)];
          return Ray{offsetOrigin(p.position, p.normal, d), d};
        };
        intersectPacket<kWidestPacket>(vis, count, rayOf, hits);
        c.rays += uint64_t(count);
        for (int j = 0; j < count; ++j) {
          const Vec3 d = dirs[first + uint32_t(j)];
          uint32_t target = kNoParticle;
          if (!hits[j].found()) {
            ++c.misses;
          } else {
            const Ray ray = rayOf(j);
            const Vec3 n = scene.geometricNormal(hits[j].triangle);
            target = nearestFacingParticle(grid, ray.origin + d * hits[j].t, dot(n, d) < 0 ? n : -n,
                                           searchRadius);
            c.unmatched += target == kNoParticle;
          }
          out[first + uint32_t(j)] = target;
        }
      }
    }
  });
  local.combine_each([&](const LinkCounters& c) {
    counters.rays += c.rays;
    counters.misses += c.misses;
    counters.unmatched += c.unmatched;
  });
  return links;
}

}  // namespace lucent
