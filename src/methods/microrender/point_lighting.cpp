// Lighting the hierarchy's points (Ritschel et al. 2009, section 4): direct light at the leaves by
// shadow rays (Embree instead of the paper's shadow maps), instant radiosity's virtual point lights,
// Jacobi gathering at an interior level with push-pull, or the photon map's estimate; interior nodes
// by pull.
#include "point_lighting.h"

#include <tbb/enumerable_thread_specific.h>

#include "lucent/core/dump.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/particle_scattering.h"
#include "lucent/scene/surface.h"
#include "lucent/techniques/photons/photon_estimate.h"
#include "lucent/techniques/photons/photon_tracing.h"
#include "lucent/techniques/points/bottom_up.h"

namespace lucent {

namespace {

enum class LightingStream : uint64_t { Direct = 11, VplPaths = 12, Radiosity = 13, Photons = 14 };
uint64_t lightingSeed(uint64_t seed, LightingStream s) { return hashKey(seed, uint64_t(s)); }

// A leaf's surface: its triangle at its barycentrics, the side of the face normal (leaves are
// one-sided: back faces are culled), and its diffuse albedo.
struct LeafSurface {
  Vec3 position, faceNormal, normal;
  Rgb albedo;
};
LeafSurface leafSurface(const Scene& scene, const PointHierarchy& h, uint32_t j) {
  const PointSample& s = h.points[j];
  const SurfacePoint sp = surfaceAt(scene, s.triangle, s.b1, s.b2);
  return {sp.position, sp.geometricNormal, sp.shadingNormal, h.floatNodes[h.leafCount + j].albedo};
}

// Per leaf, the direct irradiance over pi (the radiance a white Lambertian leaf would reflect).
std::vector<Rgb> directAtLeaves(const Scene& scene, const Visibility& vis, const PointHierarchy& h, int samples,
                                uint64_t seed, uint64_t& rays) {
  std::vector<Rgb> e(h.leafCount);
  const uint64_t stream = lightingSeed(seed, LightingStream::Direct);
  const DirectLights lights(scene);
  tbb::enumerable_thread_specific<uint64_t> threadRays(0);
  points::parallelFor(0, h.leafCount, [&](uint32_t j) {
    const LeafSurface leaf = leafSurface(scene, h, j);
    if (leaf.albedo.isBlack() || samples == 0) return;
    ShadingPoint sp;
    sp.position = leaf.position;
    sp.geometricNormal = leaf.faceNormal;
    sp.normal = leaf.normal;
    sp.wo = leaf.normal;
    sp.bsdf = LambertianLobe{Rgb(1.0f)};
    sp.pixel = j;
    e[j] = directLight(scene, lights, vis, sp, samples, stream, threadRays.local());
  });
  for (uint64_t r : threadRays) rays += r;
  return e;
}

// Leaves' radiance = albedo x irradiance / pi; interior nodes by pull.
void setLeavesAndPull(const PointHierarchy& h, std::span<const Rgb> irradianceOverPi, std::vector<Rgb>& radiance) {
  radiance.assign(h.nodeCount(), Rgb());
  points::parallelFor(0, h.leafCount, [&](uint32_t j) {
    radiance[h.leafCount + j] = h.floatNodes[h.leafCount + j].albedo * irradianceOverPi[j];
  });
  pullRadiance(h, radiance);
}

// A virtual point light (Keller 1997): where a light path met a diffuse surface, the flux that
// arrived there, and what the surface reflects of it diffusely.
struct VirtualPointLight {
  Vec3 position, normal;  // normal on the side the light arrived from
  Rgb flux;               // arriving flux, over the number of paths
  Rgb kd;
};

// Light paths from the lights, `paths` of them, each followed by BSDF sampling with Russian
// roulette; a VPL at every diffuse or glossy hit. Deterministic by (seed, path index).
std::vector<VirtualPointLight> traceVirtualPointLights(const Scene& scene, const Visibility& vis, uint32_t paths,
                                                       uint64_t seed) {
  std::vector<std::vector<VirtualPointLight>> perPath(paths);
  const uint64_t stream = lightingSeed(seed, LightingStream::VplPaths);
  points::parallelFor(0, paths, [&](uint32_t p) {
    Rng rng(stream, p);
    const float uLight = rng.uniform();
    const Vec2 u1 = rng.uniform2(), u2 = rng.uniform2();
    const EmissionSample e = sampleEmission(scene, uLight, u1, u2);
    if (!e.valid) return;
    Ray ray = e.ray;
    Rgb flux = e.power * (1.0f / float(paths));
    for (int bounce = 0; bounce < 64; ++bounce) {
      const Hit hit = vis.intersect(ray);
      if (!hit.found()) break;
      const SurfacePoint sp = surfaceAt(scene, hit.triangle, hit.b1, hit.b2);
      const SurfaceBsdf bsdf = bsdfAt(scene, sp);
      const Vec3 wo = -ray.direction;
      const bool front = dot(wo, sp.geometricNormal) > 0;
      if (!bsdf.diffuse().isBlack()) {
        // With the cosines' ratio, as photons are stored (particle_scattering.h).
        const float arrival = particleArrivalRatio(sp, particleShadingNormal(bsdf, sp, wo), wo);
        if (arrival > 0 && isFinite(flux * arrival))
          perPath[p].push_back({sp.position, front ? sp.geometricNormal : -sp.geometricNormal, flux * arrival, bsdf.diffuse()});
      }
      // The direction's numbers before the lobe's: the order in which GCC drew them when both were
      // arguments of one sampleBsdf call, so that faces without vertex normals keep their VPLs bit
      // for bit.
      const Vec2 u2 = rng.uniform2();
      const float uLobe = rng.uniform();
      const ParticleScatter s = scatterParticle(bsdf, sp, wo, uLobe, u2, rng);
      if (!s.valid) break;
      Rgb next = flux * s.weight;
      if (!isFinite(next)) break;
      const float survive = std::min(1.0f, next.maxComponent() / std::max(flux.maxComponent(), 1e-30f));
      if (!(survive > 0) || rng.uniform() >= survive) break;
      flux = next * (1.0f / survive);
      ray = {offsetOrigin(sp.position, sp.geometricNormal, s.wi), s.wi};
    }
  });
  std::vector<VirtualPointLight> vpls;
  for (auto& v : perPath) vpls.insert(vpls.end(), v.begin(), v.end());
  return vpls;
}

// Per leaf, the irradiance over pi from the VPLs, each tested by a shadow ray.
std::vector<Rgb> vplsAtLeaves(const Scene& scene, const Visibility& vis, const PointHierarchy& h,
                              std::span<const VirtualPointLight> vpls, uint64_t& rays) {
  std::vector<Rgb> e(h.leafCount);
  tbb::enumerable_thread_specific<uint64_t> threadRays(0);
  points::parallelFor(0, h.leafCount, [&](uint32_t j) {
    const LeafSurface leaf = leafSurface(scene, h, j);
    if (leaf.albedo.isBlack()) return;
    uint64_t& r = threadRays.local();
    Rgb sum;
    for (const VirtualPointLight& v : vpls) {
      const Vec3 d = v.position - leaf.position;
      const float dist2 = dot(d, d);
      if (!(dist2 > 0)) continue;
      const Vec3 w = d / std::sqrt(dist2);
      const float cosLeaf = dot(w, leaf.normal), cosVpl = -dot(w, v.normal);
      if (cosLeaf <= 0 || cosVpl <= 0 || dot(w, leaf.faceNormal) <= 0) continue;
      LightSample ls;
      ls.wi = w;
      ls.point = v.position;
      ls.distance = std::sqrt(dist2);
      ++r;
      if (vis.occluded(shadowRay(leaf.position, leaf.faceNormal, ls))) continue;
      // Irradiance cos_leaf cos_vpl / d^2 times the VPL's diffuse radiance kd / pi per unit flux.
      sum += v.flux * v.kd * (kInvPi * cosLeaf * cosVpl / dist2);
    }
    e[j] = sum * kInvPi;
  });
  for (uint64_t n : threadRays) rays += n;
  return e;
}

// Radiosity-style Jacobi iterations (section 4, "Multiple Bounces with Radiosity"): every node of an
// interior level gathers, by micro-rendering from its middle leaf, the radiance of the previous
// iteration; its leaves take that irradiance (push), and interior nodes are pulled again.
void radiosityBounces(const Scene& scene, const PointHierarchy& h, const GatherContext& ctx, int level, int bounces,
                      uint64_t seed, std::span<const Rgb> directOverPi, NodeRadiance& radiance, RenderStats& stats) {
  const uint32_t first = 1u << level, count = first;
  const uint32_t leavesPerNode = leavesBelow(first, h.leafCount);
  std::vector<Rgb> gathered(count), irradiance(h.leafCount);
  tbb::enumerable_thread_specific<GatherScratch> scratch;
  const uint64_t stream = lightingSeed(seed, LightingStream::Radiosity);
  const SurfaceBsdf white = LambertianLobe{Rgb(1.0f)};
  for (int b = 0; b < bounces; ++b) {
    // Packets of consecutive nodes (neighbours in space, as the point order is the tree's).
    gatherInPackets(
        ctx, count, radiance, scratch,
        [&](size_t k, Rng& rng) {
          const uint32_t node = first + uint32_t(k);
          const LeafSurface rep = leafSurface(scene, h, firstLeafPoint(node, h.leafCount) + leavesPerNode / 2);
          rng = Rng(stream, node, uint64_t(b));
          return GatherRequest{rep.position, rep.normal, surfaceNormalOnSideOf(rep.faceNormal, rep.normal), rep.normal, &white, &rng};
        },
        [&](size_t k, Rgb result) { gathered[k] = result; }, [](size_t) {});
    points::parallelFor(0, h.leafCount, [&](uint32_t j) { irradiance[j] = directOverPi[j] + gathered[j / leavesPerNode]; });
    setLeavesAndPull(h, irradiance, radiance.rgb);
    radiance.finish(h);
  }
  MicroCounters c;
  for (const GatherScratch& s : scratch) c += s.counters;
  stats.addCounter("radiosity_gathers", c.buffers);
}

}  // namespace

NodeRadiance lightPoints(const Scene& scene, const Visibility& vis, const PointHierarchy& h, const GatherContext& ctx,
                        const MicroRenderOptions& o, RenderStats& stats) {
  NodeRadiance radiance;
  radiance.kind = o.nodeRadiance;
  uint64_t rays = 0;
  if (o.lighting == PointLighting::Photons) {
    // The photon map of every stored photon (direct ones included), in Jensen's kd-tree; each
    // leaf's radiance is its estimate.
    Stopwatch traceClock;
    PhotonTracingOptions tracing;
    tracing.photons = o.photons;
    tracing.seed = lightingSeed(o.common.seed, LightingStream::Photons);
    PhotonMaps traced = tracePhotons(scene, vis, tracing);
    stats.addStage("point_lighting.trace_photons", traceClock.seconds());
    Stopwatch buildClock;
    RenderStats buildStats;
    const PhotonKdTree tree = buildPhotonKdTree(traced.global, &buildStats);
    stats.addStage("point_lighting.build_map", buildClock.seconds());
    for (const auto& [name, s] : buildStats.stageSeconds) stats.addStage("point_lighting.build_map.global." + name, s);
    if (!o.shading.dumpDirectory.empty()) dumpPhotonKdTree(o.shading.dumpDirectory, "global", tree);
    stats.addCounter("photons_emitted", traced.emitted);
    stats.addCounter("global_photons", tree.photons.size());
    radiance.rgb.assign(h.nodeCount(), Rgb());
    if (!tree.photons.empty()) {
      const EstimateSettings settings{o.k, defaultMaxRadius(scene), 0};
      tbb::enumerable_thread_specific<std::vector<PhotonDistance>> heaps(std::vector<PhotonDistance>(settings.k));
      tbb::enumerable_thread_specific<EstimateCounters> counters;
      points::parallelFor(0, h.leafCount, [&](uint32_t j) {
        const LeafSurface leaf = leafSurface(scene, h, j);
        if (leaf.albedo.isBlack()) return;
        EstimatePoint q;
        q.position = leaf.position;
        q.frame = Frame(leaf.normal);
        q.woLocal = {0, 0, 1};
        q.bsdf = LambertianLobe{leaf.albedo};
        q.facingNormal = leaf.faceNormal;
        radiance.rgb[h.leafCount + j] = estimateRadiance(tree, q, settings, heaps.local().data(), counters.local());
      });
    }
    pullRadiance(h, radiance.rgb);
    radiance.finish(h);
    return radiance;
  }

  std::vector<Rgb> irradiance = directAtLeaves(scene, vis, h, o.pointLightSamples, o.common.seed, rays);
  if (o.lighting == PointLighting::Vpl) {
    const std::vector<VirtualPointLight> vpls = traceVirtualPointLights(scene, vis, o.vpls, o.common.seed);
    const std::vector<Rgb> fromVpls = vplsAtLeaves(scene, vis, h, vpls, rays);
    for (uint32_t j = 0; j < h.leafCount; ++j) irradiance[j] += fromVpls[j];
    stats.addCounter("vpls", vpls.size());
  }
  setLeavesAndPull(h, irradiance, radiance.rgb);
  radiance.finish(h);
  if (o.lighting == PointLighting::Radiosity) {
    const int level = std::min(o.radiosityLevel, int(leafLevel(h.leafCount)) - 1);
    radiosityBounces(scene, h, ctx, std::max(level, 0), o.bounces, o.common.seed, irradiance, radiance, stats);
  }
  stats.addCounter("point_shadow_rays", rays);
  return radiance;
}

}  // namespace lucent
