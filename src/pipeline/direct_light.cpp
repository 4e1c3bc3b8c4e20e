#include "lucent/pipeline/direct_light.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

#include "lucent/core/distribution.h"
#include "lucent/core/parallel.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/core/stop.h"

namespace lucent {

DirectLights::DirectLights(const Scene& scene) {
  std::vector<float> weights;
  for (uint32_t i = 0; i < uint32_t(scene.lights.size()); ++i)
    if (isDeltaLight(scene.lights[i])) delta.push_back(i);
    else sampled.push_back(i), weights.push_back(scene.lightDistribution.weight(i));
  anySampled = !sampled.empty();
  if (!anySampled) return;
  // Shadow rays are these methods' only way to direct light: a light that owned no cell of the
  // choice's grid would be missing from it (where the lights are more than the cells, some must be).
  const std::vector<uint8_t> ownCell(weights.size() <= Distribution1D::kCells ? weights.size() : 0, 1);
  choice = Distribution1D(weights, ownCell);
}

namespace {

// A receiver's light sample: the contribution its shadow ray brings if unoccluded, less what a
// medium it crosses absorbs.
template <class Emit>
void emitLightSample(const Scene& scene, const ShadingPoint& point, const Frame& frame, Vec3 woLocal,
                     const LightSample& ls, Emit&& emit) {
  if (!(ls.pdf > 0) || ls.radiance.isBlack()) return;
  const Vec3 wiLocal = frame.toLocal(ls.wi);
  const float cosine = receivingCosine(ls.wi, wiLocal, point.normal, point.geometricNormal,
                                       has(point.bsdf.flags(), BsdfFlags::Transmission));
  if (!(cosine > 0)) return;
  const Rgb f = evalBsdf(point.bsdf, woLocal, wiLocal);
  if (f.isBlack()) return;
  const Ray ray = shadowRay(point.position, point.geometricNormal, ls);
  const uint32_t medium =
      mediumTowards(scene, scene.materialIds[point.triangle], point.geometricNormal, point.bsdf, ls.wi, point.medium);
  emit(ray, f * ls.radiance * (cosine / ls.pdf) * transmittanceIn(scene, medium, ray.tMax));
}

// The shadow rays of one point, in order: emit(ray, contribution, exact). First one to each point and
// directional light (exact: counted once), then `samples` samples of the other lights (each to be
// divided by `samples`), stratified over the light's area.
template <class Emit>
void shadowSamples(const Scene& scene, const DirectLights& lights, const ShadingPoint& point, int samples,
                   uint64_t seed, Emit&& emit) {
  const Frame frame(point.normal);
  const Vec3 woLocal = frame.toLocal(point.wo);
  for (const uint32_t i : lights.delta)
    emitLightSample(scene, point, frame, woLocal, deltaLightSample(scene.lights[i], point.position),
                    [&](const Ray& ray, Rgb c) { emit(ray, c, true); });
  if (!lights.anySampled || samples <= 0) return;
  Rng rng(seed, point.pixel, uint64_t(point.sample) << 32 | point.branch);
  for (int i = 0; i < samples; ++i) {
    const float uLight = rng.uniform();
    const Vec2 u = stratifiedSample2D(uint32_t(i), uint32_t(samples), rng.uniform2());
    const uint32_t k = lights.choice.pick(uLight);
    const LightSample ls = sampleChosenLight(scene, lights.sampled[k], lights.choice.pmf(k), point.position, u);
    emitLightSample(scene, point, frame, woLocal, ls, [&](const Ray& ray, Rgb c) { emit(ray, c, false); });
  }
}

// Shadow rays queued and traced as packets of up to kWidestPacket (a lone ray alone); each
// unoccluded ray's contribution is added to its sum, in queue order.
struct ShadowPackets {
  static constexpr int kPacket = kWidestPacket;
  ShadowPackets(const Visibility& visibility, uint64_t& rayCount) : vis(visibility), rays(rayCount) {}
  const Visibility& vis;
  uint64_t& rays;
  Ray queuedRays[kPacket];
  Rgb contribution[kPacket];
  Rgb* sumOf[kPacket];
  int queued = 0;

  void add(const Ray& ray, Rgb c, Rgb* sum) {
    queuedRays[queued] = ray, contribution[queued] = c, sumOf[queued] = sum;
    if (++queued == kPacket) flush();
  }
  void flush() {
    bool occluded[kPacket];
    if (queued > 0) occludedPacket<kPacket>(vis, queued, [&](int j) -> const Ray& { return queuedRays[j]; }, occluded);
    for (int j = 0; j < queued; ++j)
      if (!occluded[j]) *sumOf[j] += contribution[j];
    rays += uint64_t(queued);
    queued = 0;
  }
};

}  // namespace

Rgb directLight(const Scene& scene, const DirectLights& lights, const Visibility& vis, const ShadingPoint& point,
                int samples, uint64_t seed, uint64_t& rays) {
  Rgb sampled, exact;
  ShadowPackets packets(vis, rays);
  shadowSamples(scene, lights, point, samples, seed,
                [&](const Ray& ray, Rgb c, bool isExact) { packets.add(ray, c, isExact ? &exact : &sampled); });
  packets.flush();
  return samples > 0 ? sampled * (1.0f / float(samples)) + exact : exact;
}

namespace {

// Every point's shadow rays, queued by samples(i, add) as add(ray, contribution, exact), traced in
// packets shared across the points of blocks of 256 (neighbouring pixels' rays head for the same
// lights: a point with 1 or 4 samples no longer traces packets of 1 or 4); direct[i] is the sum of
// point i's unoccluded sampled contributions times `scale`, plus its exact ones. Occlusion is a yes
// or no, so the grouping changes no answer, and each point's sums keep their sample order.
template <class Samples>
void shadowRaysInBlocks(const Visibility& vis, std::span<Rgb> direct, float scale, uint64_t& rays, Samples&& samples) {
  constexpr size_t kBlock = 256;
  const size_t blocks = (direct.size() + kBlock - 1) / kBlock;
  std::vector<uint64_t> blockRays(blocks, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    flushDenormals();
    Rgb exact[kBlock];
    for (size_t b = r.begin(); b != r.end(); ++b) {
      const size_t first = b * kBlock, last = std::min(direct.size(), first + kBlock);
      for (size_t i = first; i < last; ++i) direct[i] = Rgb(), exact[i - first] = Rgb();
      ShadowPackets packets(vis, blockRays[b]);
      for (size_t i = first; i < last; ++i)
        samples(i, [&](const Ray& ray, Rgb c, bool isExact) { packets.add(ray, c, isExact ? &exact[i - first] : &direct[i]); });
      packets.flush();
      for (size_t i = first; i < last; ++i) direct[i] = direct[i] * scale + exact[i - first];
    }
  });
  for (uint64_t n : blockRays) rays += n;
}

}  // namespace

void estimateDirectLight(const Scene& scene, const Visibility& vis, std::span<const ShadingPoint> points,
                         int samples, uint64_t seed, std::span<Rgb> direct, uint64_t& rays) {
  if (samples <= 0) {
    std::fill_n(direct.begin(), points.size(), Rgb());
    return;
  }
  const uint64_t stream = streamSeed(seed, RenderStream::Direct);
  const DirectLights lights(scene);
  shadowRaysInBlocks(vis, direct.first(points.size()), 1.0f / float(samples), rays,
                     [&](size_t i, auto add) { shadowSamples(scene, lights, points[i], samples, stream, add); });
}

void analyticDirectLight(const Scene& scene, const Visibility& vis, std::span<const ShadingPoint> points,
                         std::span<Rgb> direct, uint64_t& rays) {
  const DirectLights lights(scene);  // with no samples: the point and directional lights alone
  shadowRaysInBlocks(vis, direct.first(points.size()), 0.0f, rays,
                     [&](size_t i, auto add) { shadowSamples(scene, lights, points[i], 0, 0, add); });
}

}  // namespace lucent
