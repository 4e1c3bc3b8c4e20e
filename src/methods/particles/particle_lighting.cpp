#include "methods/particles/particle_lighting.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <algorithm>
#include <cmath>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/core/stop.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/scene/light_sampling.h"

namespace lucent {

std::vector<Rgb> emitLight(const Scene& scene, const Visibility& vis, std::span<const AreaParticle> particles,
                           int samples, uint64_t seed, uint64_t& rays) {
  // Each particle as a white Lambertian point seen along its normal: the radiance it reflects is
  // its irradiance over pi.
  std::vector<ShadingPoint> points(particles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, particles.size(), kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const AreaParticle& p = particles[i];
      ShadingPoint& s = points[i];
      s.position = p.position;
      s.geometricNormal = p.normal;
      s.normal = p.normal;
      s.wo = p.normal;
      s.weight = Rgb(1.0f);
      s.bsdf = LambertianLobe{Rgb(1.0f)};
      s.pixel = uint32_t(i);
      s.triangle = p.triangle;
    }
  });
  bool sampled = scene.environment.present;
  for (const Light& light : scene.lights) sampled |= !isDeltaLight(light);
  std::vector<Rgb> reflected(particles.size());
  if (sampled)
    estimateDirectLight(scene, vis, points, samples, seed, reflected, rays);
  else
    analyticDirectLight(scene, vis, points, reflected, rays);
  std::vector<Rgb> flux(particles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, particles.size(), kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) flux[i] = reflected[i] * (kPi * particles[i].area);
  });
  return flux;
}

namespace {

// Flux in 64-bit fixed point: units of 2^-fraction watts, chosen so that all the light there is
// fits (the direct flux, scattered at most `bounces` times, each time no more than it was).
struct FixedFlux {
  double scale = 1;
  explicit FixedFlux(double maxTotal) {
    const double limit = 0x1p62;
    scale = maxTotal > 0 ? std::exp2(std::floor(std::log2(limit / maxTotal))) : 1.0;
  }
  uint64_t units(float watts) const { return uint64_t(std::llround(double(watts) * scale)); }
  float watts(uint64_t units) const { return float(double(units) / scale); }
};

}  // namespace

std::vector<Rgb> scatterLight(std::span<const AreaParticle> particles, std::span<const Rgb> directFlux,
                              const ParticleLinks& links, int bounces, uint64_t seed, ScatterCounters& counters) {
  const size_t n = particles.size();
  std::vector<uint32_t> lit;
  double total = 0;
  for (size_t i = 0; i < n; ++i)
    if (!(directFlux[i] * particles[i].reflectance).isBlack()) {
      lit.push_back(uint32_t(i));
      total += double(directFlux[i].maxComponent());
    }
  counters.litParticles = lit.size();
  float rhoMax = 0;
  for (const AreaParticle& p : particles) rhoMax = std::max(rhoMax, p.reflectance.maxComponent());
  double bound = 0;  // the most light a bounce can carry, over all bounces
  for (int b = 0; b <= bounces; ++b) bound += std::pow(double(rhoMax), b);
  const FixedFlux fixed(total * bound * 1.01);
  std::vector<uint64_t> arrived(3 * n, 0);
  const uint32_t per = links.perParticle();
  tbb::combinable<ScatterCounters> local;
  if (bounces < 1) lit.clear();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, lit.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    ScatterCounters& c = local.local();
    auto deposit = [&](uint32_t target, Rgb e) {
      for (int ch = 0; ch < 3; ++ch)
        std::atomic_ref<uint64_t>(arrived[3 * size_t(target) + size_t(ch)]).fetch_add(fixed.units(e[ch]), std::memory_order_relaxed);
      ++c.deposits;
    };
    for (size_t w = r.begin(); w != r.end(); ++w) {
      const uint32_t i = lit[w];
      const Rgb first = particles[i].reflectance * directFlux[i] * (1.0f / float(per));
      const std::span<const uint32_t> own = links.of(i);
      for (uint32_t k = 0; k < per; ++k) {
        uint32_t at = own[k];
        if (at == kNoParticle) {
          ++c.lost;
          continue;
        }
        Rgb e = first;
        deposit(at, e);
        Rng rng(seed, i, k);
        for (int b = 1; b < bounces; ++b) {
          e = e * particles[at].reflectance;
          if (e.isBlack()) break;
          const uint32_t next = links.of(at)[rng.below(per)];
          if (next == kNoParticle) {
            ++c.lost;
            break;
          }
          at = next;
          deposit(at, e);
        }
      }
    }
  });
  local.combine_each([&](const ScatterCounters& c) {
    counters.deposits += c.deposits;
    counters.lost += c.lost;
  });
  std::vector<Rgb> flux(n);
  for (size_t i = 0; i < n; ++i)
    flux[i] = directFlux[i] + Rgb(fixed.watts(arrived[3 * i]), fixed.watts(arrived[3 * i + 1]), fixed.watts(arrived[3 * i + 2]));
  return flux;
}

}  // namespace lucent
