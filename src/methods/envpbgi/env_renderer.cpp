// --method envpbgi: the pipeline of the environment-lighting PBGI paper (Fig. 6's stages): the point
// hierarchy, the camera's depth buffer, primary visible points, their micro-buffers and the
// secondary visible points, the selection of direct-light points, direct light, propagation, the
// radiance caches and their grid, and per pixel the caches' interpolation with the analytic lights'
// direct light by shadow rays.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "lucent/core/dump.h"
#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/bsdf.h"
#include "lucent/techniques/points/point_radiance.h"
#include "methods/envpbgi/env_lighting.h"
#include "methods/envpbgi/env_pbgi.h"
#include "methods/envpbgi/radiance_cache.h"
#include "methods/envpbgi/visible_points.h"

namespace lucent {

namespace {

enum class EnvStream : uint64_t { Points = 31 };

// A shading point's diffuse reflectance: the method shades every receiver as diffuse (the paper's
// surfaces are), a glossy one by its diffuse part.
Rgb diffusePart(const SurfaceBsdf& bsdf) { return bsdf.kd; }

// Dumps (docs/dump-format.md) of the stages before the pixels.
void dumpStages(const std::string& dir, const EnvHierarchy& h, std::span<const uint32_t> primary,
                std::span<const uint32_t> primaryTexels, std::span<const Rgb> direct,
                std::span<const RadianceCache> caches, const CacheGrid& grid) {
  if (dir.empty()) return;
  writeDump(dir, "envpbgi.nodes", "EnvPointNode", std::span(h.nodes));
  writeDump(dir, "envpbgi.surfels", "Surfel", std::span(h.surfels));
  writeDump(dir, "envpbgi.node_areas", "float", std::span(h.points.nodeAreas));
  writeDump(dir, "envpbgi.primary", "uint32", primary);
  writeDump(dir, "envpbgi.primary_buffers", "uint32", primaryTexels);
  std::vector<uint32_t> secondary;
  for (uint32_t i = kRootNode; i < uint32_t(h.nodes.size()); ++i)
    if (h.nodes[i].selection & kSecondary) secondary.push_back(i);
  writeDump(dir, "envpbgi.secondary", "uint32", std::span(secondary));
  writeDump(dir, "envpbgi.direct_light", "Rgb", direct);
  writeDump(dir, "envpbgi.caches", "RadianceCache", caches);
  writeDump(dir, "envpbgi.grid_begin", "uint32", std::span(grid.begin));
  writeDump(dir, "envpbgi.grid_caches", "uint32", std::span(grid.caches));
}

}  // namespace

RenderOutput renderEnvPbgi(const Scene& scene, const Visibility& vis, const EnvPbgiOptions& o,
                           const RenderControl& control) {
  const RenderPart part = beginRender(envPbgiOptionTable(), o, control, scene, "--method envpbgi renders the image at once");
  requireEnvironmentLights(scene);
  RenderOutput out;
  RenderStats& stats = out.stats;
  const ProgressFn& progress = control.progress;
  auto report = [&](double fraction) {
    if (progress) progress(fraction);
  };

  // Section 4 "Data structure": points by a low-discrepancy sequence, a binary tree over them, the
  // paper's 48-byte nodes.
  beginStage("hierarchy");
  Stopwatch hierarchyClock;
  PointHierarchyOptions ho;
  ho.pointCount = o.points;
  ho.encoding = NodeEncoding::Float;
  ho.sampling.method = o.pointSampling;
  ho.sampling.seed = hashKey(o.seed, uint64_t(EnvStream::Points));
  const uint64_t nodeBytes = sizeof(FloatNode) + sizeof(EnvPointNode) + sizeof(Surfel) + sizeof(TraversalNode) +
                             sizeof(Rgb) + 4 * sizeof(float);
  requireMemory(uint64_t(o.points) * (2 * nodeBytes + sizeof(PointSample) + 32), "the point hierarchy", "lower --points");
  RenderStats hierarchyStats;
  EnvHierarchy h = makeEnvHierarchy(buildPointHierarchy(scene, ho, &hierarchyStats));
  const MicroHierarchy micro = prepareMicroHierarchy(h.points);
  stats.addStage("hierarchy", hierarchyClock.seconds());
  stats.addCounter("points", h.leafCount());
  report(0.05);

  MicroRenderSettings settings;
  settings.depth = DepthCoding::forExtent(length(scene.bounds.extent()));
  settings.splatReach = o.splatReach;
  const BufferQuadrature primaryQuadrature = makeQuadrature(o.mapping, o.primaryBufferSide);
  const BufferQuadrature secondaryQuadrature = makeQuadrature(o.mapping, o.secondaryBufferSide);
  const Environment& env = scene.environment;
  MicroCounters counters;
  uint64_t shadowRays = 0;
  std::vector<Rgb> direct(h.nodes.size());

  // 3.4, 4: primary visible points, from the camera's depth buffer. The brute force, with a
  // micro-buffer at every pixel and direct light at every leaf, has no use for them.
  beginStage("select_primary_points");
  Stopwatch primaryClock;
  std::vector<uint32_t> primary;
  if (o.pixelIrradiance == PixelIrradiance::Caches) {
    const CameraDepth depth = traceCameraDepth(scene, vis);
    const float pixelAngle = PinholeCamera(scene.camera).pixelAngle();
    PrimarySelection selection;
    selection.maxSolidAngle = o.primaryPixels * pixelAngle * pixelAngle;
    selection.maxConeAngle = o.primaryConeAngle * kPi / 180.0f;
    selection.thickness = micro.thickness;
    primary = selectPrimaryPoints(h, scene.camera, depth, selection);
  }
  stats.addStage("select_primary_points", primaryClock.seconds());

  // 3.3, 4: their micro-buffers, and the nodes those show: the secondary visible points.
  beginStage("select_secondary_points");
  Stopwatch secondaryClock;
  const uint32_t primaryTexelCount = primaryQuadrature.texels();
  requireMemory(uint64_t(primary.size()) * (primaryTexelCount * sizeof(uint32_t) + sizeof(RadianceCache)),
                "the primary points' micro-buffers and caches", "raise --primary-pixels or lower --resolution");
  std::vector<uint32_t> primaryTexels(primary.size() * primaryTexelCount);
  renderBuffers(micro, settings, primaryQuadrature, primary.size(),
                [&](size_t k) { return BufferOrigin{h.surfels[primary[k]].position, h.surfels[primary[k]].normal}; },
                primaryTexels, counters);
  markSecondaryPoints(h, primaryTexels);
  stats.addStage("select_secondary_points", secondaryClock.seconds());
  report(0.3);

  // 3.3, 3.4, Fig. 3: which points need a micro-buffer of their own, then their direct light.
  beginStage("select_direct_light_points");
  Stopwatch selectClock;
  const SelectionCounts counts = selectDirectLightPoints(h, primary, o.primarySources);
  stats.addStage("select_direct_light_points", selectClock.seconds());

  beginStage("direct_light");
  Stopwatch directClock;
  std::vector<uint32_t> ownBuffer;
  if (o.directLight == PointDirectLight::Selected) {
    for (uint32_t i = kRootNode; i < uint32_t(h.nodes.size()); ++i)
      if (h.nodes[i].selection & kOwnBuffer) ownBuffer.push_back(i);
  } else {
    for (uint32_t i = h.leafCount(); i < uint32_t(h.nodes.size()); ++i) ownBuffer.push_back(i);
  }
  const uint32_t secondaryTexelCount = secondaryQuadrature.texels();
  std::vector<uint32_t> ownTexels(std::min<size_t>(ownBuffer.size(), 1u << 16) * secondaryTexelCount);
  tbb::enumerable_thread_specific<uint64_t> rays(0);
  // Direct light at a point from its buffer's empty texels and from the analytic lights.
  auto directAt = [&](uint32_t node, std::span<const uint32_t> texels, const BufferQuadrature& q) {
    const Surfel& s = h.surfels[node];
    const BufferIrradiance e = bufferIrradiance(texels, q, s.normal, env, {});
    const Rgb analytic = analyticIrradiance(scene, vis, s.position, s.normal, rays.local());
    return h.points.floatNodes[node].albedo * ((e.environment + analytic) * kInvPi);
  };
  // In chunks, so that the buffers held at once stay bounded (every leaf: 2^19 buffers).
  const size_t chunk = ownTexels.size() / std::max<uint32_t>(secondaryTexelCount, 1);
  for (size_t first = 0; first < ownBuffer.size(); first += chunk) {
    const size_t count = std::min(chunk, ownBuffer.size() - first);
    renderBuffers(micro, settings, secondaryQuadrature, count,
                  [&](size_t k) { return BufferOrigin{h.surfels[ownBuffer[first + k]].position, h.surfels[ownBuffer[first + k]].normal}; },
                  ownTexels, counters);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 64), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t k = r.begin(); k != r.end(); ++k)
        direct[ownBuffer[first + k]] =
            directAt(ownBuffer[first + k], std::span(ownTexels).subspan(k * secondaryTexelCount, secondaryTexelCount),
                     secondaryQuadrature);
    });
  }
  ownTexels = {};
  // The primary points reuse their buffers (3.5: "almost for free").
  tbb::parallel_for(tbb::blocked_range<size_t>(0, primary.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k)
      if (o.directLight == PointDirectLight::Selected)
        direct[primary[k]] = directAt(primary[k], std::span(primaryTexels).subspan(k * primaryTexelCount, primaryTexelCount),
                                      primaryQuadrature);
  });
  for (uint64_t r : rays) shadowRays += r;
  stats.addStage("direct_light", directClock.seconds());
  report(0.55);

  beginStage("propagate_direct_light");
  Stopwatch propagateClock;
  uint64_t secondaryWithoutLight = 0;
  if (o.directLight == PointDirectLight::Selected) {
    propagateDirectLight(h, primary, direct);
    for (const EnvPointNode& node : h.nodes)
      secondaryWithoutLight += (node.selection & kSecondary) && !(node.selection & kHasDirect);
  } else {
    pullRadiance(h.points, direct);
  }
  stats.addStage("propagate_direct_light", propagateClock.seconds());

  // 3.5, 4: the radiance caches and their screen-space grid.
  beginStage("radiance_caches");
  Stopwatch cacheClock;
  std::vector<RadianceCache> caches(primary.size());
  CacheGrid grid;
  if (o.pixelIrradiance == PixelIrradiance::Caches) {
    const CacheConvolution convolution = makeCacheConvolution(primaryQuadrature);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, primary.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t k = r.begin(); k != r.end(); ++k)
        caches[k] = buildRadianceCache(std::span(primaryTexels).subspan(k * primaryTexelCount, primaryTexelCount),
                                       primaryQuadrature, convolution, h.surfels[primary[k]],
                                       o.cacheRadiusScale * h.nodes[primary[k]].radius, env, direct);
    });
    grid = buildCacheGrid(caches, scene.camera, o.tileSize);
  }
  stats.addStage("radiance_caches", cacheClock.seconds());
  dumpStages(o.dumpDirectory, h, primary, primaryTexels, direct, caches, grid);
  primaryTexels = {};
  report(0.65);

  // The pixels, band by band of rows: camera paths to shading points, the analytic lights by shadow
  // rays, the rest from the caches (Eq. 5) or, brute force, from a micro-buffer each (bands of
  // kReusableBandSamples); a dump holds the whole image's shading points, in one band.
  beginStage("pixels");
  Stopwatch pixelClock;
  double imageSeconds = 0;
  auto film = std::make_shared<Film>(startFilm(control, scene, part, Film::Sums::PerPart, {o.layers, false}));
  const PinholeCamera camera(scene.camera);
  Interpolation interpolation;
  interpolation.maxAngle = o.cacheMaxAngle * kPi / 180.0f;
  std::atomic<uint64_t> fallbacks{0}, glossy{0}, cacheCandidates{0};
  uint64_t eyeRays = 0, shadingPoints = 0, invalidSamples = 0;
  std::vector<uint32_t> texels, tileOfPoint;
  std::vector<uint8_t> unreached;
  MicroRenderSettings backSettings = settings;
  backSettings.backFacesOcclude = true;
  std::vector<float> depthOfPoint;
  TileLists tileLists;
  BandLoop loop;
  loop.maxSamples = o.dumpDirectory.empty() ? kReusableBandSamples : ~uint64_t(0);
  loop.progressFrom = 0.65;
  const bool finished = renderRowBands(control, part, loop, *film, [&](const PixelRect& band, size_t, const auto&) {
    EyePathSettings settingsOfBand = eyePathSettings(o, part);
    settingsOfBand.region = band;
    const EyePaths eye = traceEyePaths(scene, vis, settingsOfBand);
    const size_t n = eye.points.size();
    PointRadiance shading(n);
    // The analytic lights by shadow rays with the full BSDF; the environment's and the nodes' light
    // as diffuse.
    analyticDirectLight(scene, vis, eye.points, shading.direct, shadowRays);
    auto shade = [&](size_t i, const BufferIrradiance& e) {
      const ShadingPoint& p = eye.points[i];
      const Rgb rho = diffusePart(p.bsdf) * kInvPi;
      shading.direct[i] += rho * e.environment;
      shading.indirect[i] = rho * e.nodes;
      if (p.bsdf.type != MaterialType::Diffuse) ++glossy;
    };
    // The receivers `which` (indices into the band's points), each from a micro-buffer of its own,
    // in chunks of at most 2^14 buffers. A receiver on a surface seen from behind (a wall of
    // outward faces seen from inside) renders with back faces occluding: culled, they would show
    // what lies beyond (micro-rendering does the same).
    auto shadeFromOwnBuffers = [&](std::span<const uint32_t> which) {
      std::vector<uint32_t> sorted(which.begin(), which.end());
      const size_t front = size_t(std::stable_partition(sorted.begin(), sorted.end(), [&](uint32_t i) {
                                    return dot(eye.points[i].normal, eye.points[i].geometricNormal) >= 0;
                                  }) - sorted.begin());
      texels.resize(std::min<size_t>(std::max<size_t>(sorted.size(), 1), 1u << 14) * primaryTexelCount);
      const size_t chunk = texels.size() / primaryTexelCount;
      for (const bool back : {false, true}) {
        const std::span<const uint32_t> group =
            back ? std::span(sorted).subspan(front) : std::span(sorted).subspan(0, front);
        for (size_t first = 0; first < group.size(); first += chunk) {
          const size_t count = std::min(chunk, group.size() - first);
          renderBuffers(micro, back ? backSettings : settings, primaryQuadrature, count,
                        [&](size_t k) {
                          const ShadingPoint& p = eye.points[group[first + k]];
                          return BufferOrigin{p.position, p.normal};
                        },
                        texels, counters);
          tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 64), [&](const tbb::blocked_range<size_t>& r) {
            stopPoint();
            for (size_t k = r.begin(); k != r.end(); ++k)
              shade(group[first + k],
                    bufferIrradiance(std::span(texels).subspan(k * primaryTexelCount, primaryTexelCount),
                                     primaryQuadrature, eye.points[group[first + k]].normal, env, direct));
          });
        }
      }
    };
    if (o.pixelIrradiance == PixelIrradiance::Caches) {
      // Each receiver's tile and view depth, then the band's tile lists cut to its depths.
      tileOfPoint.resize(n), depthOfPoint.resize(n);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        stopPoint();
        for (size_t i = r.begin(); i != r.end(); ++i) {
          const ShadingPoint& p = eye.points[i];
          const CacheGrid::Placement at = grid.place(camera, p.position, p.pixel, scene.camera.width, scene.camera.height);
          tileOfPoint[i] = at.tile, depthOfPoint[i] = at.depth;
        }
      });
      cutTileLists(grid, tileOfPoint, depthOfPoint, tileLists);
      unreached.assign(n, 0);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
        stopPoint();
        uint64_t candidatesHere = 0;
        for (size_t i = r.begin(); i != r.end(); ++i) {
          const ShadingPoint& p = eye.points[i];
          const std::span<const uint32_t> candidates = tileLists.of(grid, tileOfPoint[i]);
          const std::optional<BufferIrradiance> e =
              interpolateCaches(caches, grid, candidates, p.position, p.normal, interpolation);
          candidatesHere += candidates.size();
          if (e) shade(i, *e);
          else unreached[i] = 1;
        }
        cacheCandidates += candidatesHere;
      });
      std::vector<uint32_t> own;
      for (uint32_t i = 0; i < n; ++i)
        if (unreached[i]) own.push_back(i);
      fallbacks += own.size();
      shadeFromOwnBuffers(own);
    } else {
      std::vector<uint32_t> all(n);
      std::iota(all.begin(), all.end(), 0u);
      shadeFromOwnBuffers(all);
    }
    if (!o.dumpDirectory.empty()) dumpShadingPoints(o.dumpDirectory, "", eye, shading, false);
    Stopwatch filmClock;
    addBand(*film, eye, shading, scene.camera.width, part);
    imageSeconds += filmClock.seconds();
    eyeRays += eye.rays, shadingPoints += n, invalidSamples += eye.invalid;
  });
  if (!finished) throw RenderStopped();
  stats.addStage("pixels", pixelClock.seconds() - imageSeconds);
  Stopwatch imageClock;
  out.image = film->image();
  out.film = film;
  out.sppDone = part.samples();
  stats.addStage("image", imageSeconds + imageClock.seconds());
  report(1.0);

  stats.addCounter("primary_points", counts.primary);
  stats.addCounter("secondary_points", counts.secondary);
  stats.addCounter("secondary_after_upward", counts.afterUpward);
  stats.addCounter("secondary_after_downward", counts.afterDownward);
  stats.addCounter("secondary_own_buffers", counts.ownBuffers);
  stats.addCounter("secondary_without_light", secondaryWithoutLight);
  counters.report(stats);
  stats.addCounter("shadow_rays", shadowRays);
  stats.addCounter("eye_rays", eyeRays);
  stats.addCounter("shading_points", shadingPoints);
  stats.addCounter("cache_fallbacks", fallbacks);
  stats.addCounter("glossy_shaded_diffuse", glossy);
  stats.addCounter("grid_references", grid.caches.size());
  stats.addCounter("cache_candidates", cacheCandidates);
  stats.addCounter("invalid_samples", invalidSamples + out.film->droppedPoints());
  return out;
}

}  // namespace lucent
