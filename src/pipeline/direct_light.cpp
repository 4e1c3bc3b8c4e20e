#include "lucent/pipeline/direct_light.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

#include "lucent/core/parallel.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/light_sampling.h"

namespace lucent {

namespace {

// The light samples of one point that need a shadow ray, in sample order: emit(ray, contribution),
// the contribution counting if the ray is unoccluded (before the 1 / samples).
template <class Emit>
void shadowSamples(const Scene& scene, const ShadingPoint& point, int samples, uint64_t seed, Emit&& emit) {
  Rng rng(seed, point.pixel, uint64_t(point.sample) << 32 | point.branch);
  const Frame frame(point.normal);
  const Vec3 woLocal = frame.toLocal(point.wo);
  const float side = dot(point.normal, point.geometricNormal);
  for (int i = 0; i < samples; ++i) {
    const float uLight = rng.uniform();
    const Vec2 u = stratifiedSample2D(uint32_t(i), uint32_t(samples), rng.uniform2());
    const LightSample ls = sampleLight(scene, point.position, uLight, u);
    if (!(ls.pdf > 0) || ls.radiance.isBlack()) continue;
    const Vec3 wiLocal = frame.toLocal(ls.wi);
    if (wiLocal.z <= 0 || dot(ls.wi, point.geometricNormal) * side <= 0) continue;
    const Rgb f = evalBsdf(point.bsdf, woLocal, wiLocal);
    if (f.isBlack()) continue;
    emit(shadowRay(point.position, point.geometricNormal, ls), f * ls.radiance * (wiLocal.z / ls.pdf));
  }
}

// Shadow rays queued and traced as packets of up to kWidestPacket (a lone ray alone); each
// unoccluded ray's contribution is added to its point's sum, in queue order.
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

Rgb directLight(const Scene& scene, const Visibility& vis, const ShadingPoint& point, int samples, uint64_t seed,
                uint64_t& rays) {
  Rgb sum;
  ShadowPackets packets(vis, rays);
  shadowSamples(scene, point, samples, seed, [&](const Ray& ray, Rgb c) { packets.add(ray, c, &sum); });
  packets.flush();
  return sum * (1.0f / float(samples));
}

namespace {

// Every point's shadow rays, queued by samples(i, add) as add(ray, contribution), traced in packets
// shared across the points of blocks of 256 (neighbouring pixels' rays head for the same lights: a
// point with 1 or 4 samples no longer traces packets of 1 or 4); direct[i] is the sum of point i's
// unoccluded contributions times `scale`. Occlusion is a yes or no, so the grouping changes no
// answer, and each point's sum keeps its sample order.
template <class Samples>
void shadowRaysInBlocks(const Visibility& vis, std::span<Rgb> direct, float scale, uint64_t& rays, Samples&& samples) {
  constexpr size_t kBlock = 256;
  const size_t blocks = (direct.size() + kBlock - 1) / kBlock;
  std::vector<uint64_t> blockRays(blocks, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& r) {
    flushDenormals();
    for (size_t b = r.begin(); b != r.end(); ++b) {
      const size_t first = b * kBlock, last = std::min(direct.size(), first + kBlock);
      for (size_t i = first; i < last; ++i) direct[i] = Rgb();
      ShadowPackets packets(vis, blockRays[b]);
      for (size_t i = first; i < last; ++i) samples(i, [&](const Ray& ray, Rgb c) { packets.add(ray, c, &direct[i]); });
      packets.flush();
      for (size_t i = first; i < last; ++i) direct[i] = direct[i] * scale;
    }
  });
  for (uint64_t n : blockRays) rays += n;
}

}  // namespace

void estimateDirectLight(const Scene& scene, const Visibility& vis, std::span<const ShadingPoint> points,
                         int samples, uint64_t seed, std::span<Rgb> direct, uint64_t& rays) {
  const uint64_t stream = streamSeed(seed, RenderStream::Direct);
  // A single point or directional light gives every sample the same shadow ray: one is enough
  // (the paper's RING: "only shoots one shadow ray per pixel").
  if (scene.lights.size() == 1 && (scene.lights[0].type == LightType::Point || scene.lights[0].type == LightType::Directional))
    samples = std::min(samples, 1);
  shadowRaysInBlocks(vis, direct.first(points.size()), 1.0f / float(samples), rays, [&](size_t i, auto add) {
    shadowSamples(scene, points[i], samples, stream, add);
  });
}

void analyticDirectLight(const Scene& scene, const Visibility& vis, std::span<const ShadingPoint> points,
                         std::span<Rgb> direct, uint64_t& rays) {
  shadowRaysInBlocks(vis, direct.first(points.size()), 1.0f, rays, [&](size_t i, auto add) {
    const ShadingPoint& p = points[i];
    const Frame frame(p.normal);
    const Vec3 woLocal = frame.toLocal(p.wo);
    const float side = dot(p.normal, p.geometricNormal);
    for (const Light& light : scene.lights) {
      if (light.type != LightType::Point && light.type != LightType::Directional) continue;
      const LightSample ls = deltaLightSample(light, p.position);
      const Vec3 wiLocal = frame.toLocal(ls.wi);
      if (ls.radiance.isBlack() || wiLocal.z <= 0 || dot(ls.wi, p.geometricNormal) * side <= 0) continue;
      const Rgb f = evalBsdf(p.bsdf, woLocal, wiLocal);
      if (!f.isBlack()) add(shadowRay(p.position, p.geometricNormal, ls), f * ls.radiance * wiLocal.z);
    }
  });
}

}  // namespace lucent
