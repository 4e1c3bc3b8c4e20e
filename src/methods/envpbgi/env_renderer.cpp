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
#include "lucent/methods/envpbgi.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_driver.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/surface.h"
#include "lucent/techniques/points/point_radiance.h"
#include "methods/envpbgi/env_lighting.h"
#include "methods/envpbgi/radiance_cache.h"
#include "methods/envpbgi/visible_points.h"

namespace lucent {

namespace {

enum class EnvStream : uint64_t { Points = 31 };

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

// The stages of one render (Fig. 6), in order, and what they hand on to each other.
class EnvPbgiRender {
 public:
  EnvPbgiRender(const Scene& scene, const Visibility& vis, const EnvPbgiOptions& o, RenderDriver& driver,
                RenderStats& stats)
      : scene_(scene), vis_(vis), o_(o), driver_(driver), part_(driver.part()), stats_(stats), env_(scene.environment) {}
  EnvPbgiRender(const EnvPbgiRender&) = delete;
  EnvPbgiRender& operator=(const EnvPbgiRender&) = delete;

  // Section 4 "Data structure": points by a low-discrepancy sequence, a binary tree over them, the
  // paper's 48-byte nodes.
  void buildHierarchy() {
    StageTimer timer(stats_, "hierarchy");
    PointHierarchyOptions ho;
    ho.pointCount = o_.points;
    ho.encoding = NodeEncoding::Float;
    ho.sampling.method = o_.pointSampling;
    ho.sampling.seed = hashKey(o_.common.seed, uint64_t(EnvStream::Points));
    const uint64_t nodeBytes = sizeof(FloatNode) + sizeof(EnvPointNode) + sizeof(Surfel) + sizeof(TraversalNode) +
                               sizeof(Rgb) + 4 * sizeof(float);
    requireMemory(uint64_t(o_.points) * (2 * nodeBytes + sizeof(PointSample) + 32), "the point hierarchy",
                  "lower --points");
    RenderStats hierarchyStats;
    h_ = makeEnvHierarchy(buildPointHierarchy(scene_, ho, &hierarchyStats));
    micro_ = prepareMicroHierarchy(h_.points);
    settings_.depth = DepthCoding::forExtent(length(scene_.bounds.extent()));
    settings_.splatReach = o_.splatReach;
    direct_.assign(h_.nodes.size(), Rgb(0.0f));
  }

  // 3.4, 4: primary visible points, from the camera's depth buffer. The brute force, with a
  // micro-buffer at every pixel and direct light at every leaf, has no use for them.
  void selectPrimary() {
    StageTimer timer(stats_, "select_primary_points");
    if (o_.pixelIrradiance != PixelIrradiance::Caches) return;
    const CameraDepth depth = traceCameraDepth(scene_, vis_);
    const float pixelAngle = PinholeCamera(scene_.camera).pixelAngle();
    PrimarySelection selection;
    selection.maxSolidAngle = o_.primaryPixels * pixelAngle * pixelAngle;
    selection.maxConeAngle = o_.primaryConeAngle * kPi / 180.0f;
    selection.thickness = micro_.thickness;
    primary_ = selectPrimaryPoints(h_, scene_.camera, depth, selection);
  }

  // 3.3, 4: their micro-buffers, and the nodes those show: the secondary visible points.
  void selectSecondary() {
    StageTimer timer(stats_, "select_secondary_points");
    requireMemory(uint64_t(primary_.size()) * (primaryTexelCount_ * sizeof(uint32_t) + sizeof(RadianceCache)),
                  "the primary points' micro-buffers and caches", "raise --primary-pixels or lower --resolution");
    primaryTexels_.resize(primary_.size() * primaryTexelCount_);
    renderBuffers(micro_, settings_, primaryQuadrature_, primary_.size(),
                  [&](size_t k) { return surfelOrigin(h_.surfels[primary_[k]]); },
                  primaryTexels_, counters_);
    markSecondaryPoints(h_, primaryTexels_);
  }

  // 3.3, 3.4, Fig. 3: which points need a micro-buffer of their own, then their direct light.
  void selectDirectLightPoints() {
    StageTimer timer(stats_, "select_direct_light_points");
    counts_ = lucent::selectDirectLightPoints(h_, primary_, o_.primarySources);
  }

  void computeDirectLight() {
    StageTimer timer(stats_, "direct_light");
    std::vector<uint32_t> ownBuffer;
    if (o_.directLight == PointDirectLight::Selected) {
      for (uint32_t i = kRootNode; i < uint32_t(h_.nodes.size()); ++i)
        if (h_.nodes[i].selection & kOwnBuffer) ownBuffer.push_back(i);
    } else {
      for (uint32_t i = h_.leafCount(); i < uint32_t(h_.nodes.size()); ++i) ownBuffer.push_back(i);
    }
    const uint32_t secondaryTexelCount = secondaryQuadrature_.texels();
    std::vector<uint32_t> ownTexels(std::min<size_t>(ownBuffer.size(), 1u << 16) * secondaryTexelCount);
    tbb::enumerable_thread_specific<uint64_t> rays(0);
    // Direct light at a point from its buffer's empty texels and from the analytic lights.
    auto directAt = [&](uint32_t node, std::span<const uint32_t> texels, const BufferQuadrature& q) {
      const Surfel& s = h_.surfels[node];
      const BufferIrradiance e = bufferIrradiance(texels, q, s.normal, env_, {});
      const Rgb analytic = analyticIrradiance(scene_, vis_, s.position, s.normal, rays.local());
      return h_.points.floatNodes[node].albedo * ((e.environment + analytic) * kInvPi);
    };
    // In chunks, so that the buffers held at once stay bounded (every leaf: 2^19 buffers).
    const size_t chunk = ownTexels.size() / std::max<uint32_t>(secondaryTexelCount, 1);
    for (size_t first = 0; first < ownBuffer.size(); first += chunk) {
      const size_t count = std::min(chunk, ownBuffer.size() - first);
      renderBuffers(micro_, settings_, secondaryQuadrature_, count,
                    [&](size_t k) { return surfelOrigin(h_.surfels[ownBuffer[first + k]]); },
                    ownTexels, counters_);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 64), [&](const tbb::blocked_range<size_t>& r) {
        stopPoint();
        for (size_t k = r.begin(); k != r.end(); ++k)
          direct_[ownBuffer[first + k]] = directAt(
              ownBuffer[first + k], std::span(ownTexels).subspan(k * secondaryTexelCount, secondaryTexelCount),
              secondaryQuadrature_);
      });
    }
    ownTexels = {};
    // The primary points reuse their buffers (3.5: "almost for free").
    tbb::parallel_for(tbb::blocked_range<size_t>(0, primary_.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t k = r.begin(); k != r.end(); ++k)
        if (o_.directLight == PointDirectLight::Selected)
          direct_[primary_[k]] = directAt(primary_[k], primaryBuffer(k), primaryQuadrature_);
    });
    for (uint64_t r : rays) shadowRays_ += r;
  }

  void propagate() {
    StageTimer timer(stats_, "propagate_direct_light");
    if (o_.directLight == PointDirectLight::Selected) {
      propagateDirectLight(h_, primary_, direct_);
      for (const EnvPointNode& node : h_.nodes)
        secondaryWithoutLight_ += (node.selection & kSecondary) && !(node.selection & kHasDirect);
    } else {
      pullRadiance(h_.points, direct_);
    }
  }

  // 3.5, 4: the radiance caches and their screen-space grid; then the stages' dumps.
  void buildCaches() {
    {
      StageTimer timer(stats_, "radiance_caches");
      caches_.resize(primary_.size());
      if (o_.pixelIrradiance == PixelIrradiance::Caches) {
        const CacheConvolution convolution = makeCacheConvolution(primaryQuadrature_);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, primary_.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
          stopPoint();
          for (size_t k = r.begin(); k != r.end(); ++k)
            caches_[k] = buildRadianceCache(primaryBuffer(k), primaryQuadrature_, convolution, h_.surfels[primary_[k]],
                                            o_.cacheRadiusScale * h_.nodes[primary_[k]].radius, env_, direct_);
        });
        grid_ = buildCacheGrid(caches_, scene_.camera, o_.tileSize);
      }
    }
    dumpStages(o_.dumpDirectory, h_, primary_, primaryTexels_, direct_, caches_, grid_);
    primaryTexels_ = {};
  }

  // The pixels, band by band of rows: camera paths to shading points, the analytic lights by shadow
  // rays, the rest from the caches (Eq. 5) or, brute force, from a micro-buffer each (bands of
  // kReusableBandSamples); a dump holds the whole image's shading points, in one band.
  void shadePixels(RenderOutput& out) {
    beginStage("pixels");
    Stopwatch pixelClock;
    Film& film = driver_.startFilm(Film::Sums::PerPart, {o_.common.layers, false});
    BandLoop loop;
    loop.maxSamples = o_.dumpDirectory.empty() ? kReusableBandSamples : ~uint64_t(0);
    loop.progressFrom = 0.65;
    const bool finished = driver_.renderBands(loop, [&](const PixelRect& band, size_t, const auto&) {
      const EyePaths eye = shadeBand(band);
      Stopwatch filmClock;
      addBand(film, eye, bandShading_, scene_.camera.width, part_);
      imageSeconds_ += filmClock.seconds();
    });
    if (!finished) throw RenderStopped();
    stats_.addStage("pixels", pixelClock.seconds() - imageSeconds_);
    Stopwatch imageClock;
    driver_.finish(out);
    stats_.addStage("image", imageSeconds_ + imageClock.seconds());
  }

  void reportCounters(const RenderOutput& out) const {
    stats_.addCounter("primary_points", counts_.primary);
    stats_.addCounter("secondary_points", counts_.secondary);
    stats_.addCounter("secondary_after_upward", counts_.afterUpward);
    stats_.addCounter("secondary_after_downward", counts_.afterDownward);
    stats_.addCounter("secondary_own_buffers", counts_.ownBuffers);
    stats_.addCounter("secondary_without_light", secondaryWithoutLight_);
    counters_.report(stats_);
    stats_.addCounter("shadow_rays", shadowRays_);
    stats_.addCounter("eye_rays", eyeRays_);
    stats_.addCounter("shading_points", shadingPoints_);
    stats_.addCounter("cache_fallbacks", fallbacks_);
    stats_.addCounter("glossy_shaded_diffuse", glossy_);
    stats_.addCounter("grid_references", grid_.caches.size());
    stats_.addCounter("cache_candidates", cacheCandidates_);
    stats_.addCounter("invalid_samples", invalidSamples_ + out.film->droppedPoints());
  }

  uint32_t leafCount() const { return h_.leafCount(); }

 private:
  std::span<const uint32_t> primaryBuffer(size_t k) const {
    return std::span(primaryTexels_).subspan(k * primaryTexelCount_, primaryTexelCount_);
  }

  // One band's camera paths and, in bandShading_, their light.
  EyePaths shadeBand(const PixelRect& band) {
    EyePathSettings settingsOfBand = eyePathSettings(o_.common, o_.maxSpecularDepth, part_);
    settingsOfBand.region = band;
    EyePaths eye = traceEyePaths(scene_, vis_, settingsOfBand);
    const size_t n = eye.points.size();
    bandShading_ = PointRadiance(n);
    // The analytic lights by shadow rays with the full BSDF; the environment's and the nodes' light
    // as diffuse.
    analyticDirectLight(scene_, vis_, eye.points, bandShading_.direct, shadowRays_);
    if (o_.pixelIrradiance == PixelIrradiance::Caches) {
      interpolateBand(eye);
    } else {
      std::vector<uint32_t> all(n);
      std::iota(all.begin(), all.end(), 0u);
      shadeFromOwnBuffers(eye, all);
    }
    if (!o_.dumpDirectory.empty()) {
      dumpShadingPoints(o_.dumpDirectory, "", eye, bandShading_, false);
      if (o_.pixelIrradiance == PixelIrradiance::Caches)
        writeDump(o_.dumpDirectory, "envpbgi.receiver_tiles", "uint32", std::span(tileOfPoint_));
    }
    eyeRays_ += eye.rays, shadingPoints_ += n, invalidSamples_ += eye.invalid;
    return eye;
  }

  // Eq. 5 at each of the band's points from the caches of its tile's list; points no cache reaches
  // from their own buffers.
  void interpolateBand(const EyePaths& eye) {
    const size_t n = eye.points.size();
    const PinholeCamera camera(scene_.camera);
    Interpolation interpolation;
    interpolation.maxAngle = o_.cacheMaxAngle * kPi / 180.0f;
    // Each receiver's tile and view depth, then the band's tile lists cut to its depths.
    tileOfPoint_.resize(n), depthOfPoint_.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const ShadingPoint& p = eye.points[i];
        const CacheGrid::Placement at = grid_.place(camera, p.position, p.pixel, scene_.camera.width, scene_.camera.height);
        tileOfPoint_[i] = at.tile, depthOfPoint_[i] = at.depth;
      }
    });
    cutTileLists(grid_, tileOfPoint_, depthOfPoint_, tileLists_);
    unreached_.assign(n, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      uint64_t candidatesHere = 0;
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const ShadingPoint& p = eye.points[i];
        const std::span<const uint32_t> candidates = tileLists_.of(grid_, tileOfPoint_[i]);
        const std::optional<BufferIrradiance> e =
            interpolateCaches(caches_, grid_, candidates, p.position, p.normal, interpolation);
        candidatesHere += candidates.size();
        if (e) shade(eye, i, *e);
        else unreached_[i] = 1;
      }
      cacheCandidates_ += candidatesHere;
    });
    std::vector<uint32_t> own;
    for (uint32_t i = 0; i < n; ++i)
      if (unreached_[i]) own.push_back(i);
    fallbacks_ += own.size();
    shadeFromOwnBuffers(eye, own);
  }

  void shade(const EyePaths& eye, size_t i, const BufferIrradiance& e) {
    const ShadingPoint& p = eye.points[i];
    // Every receiver is shaded as diffuse (the paper's surfaces are), a glossy one by its diffuse part.
    const Rgb rho = p.bsdf.diffuse() * kInvPi;
    bandShading_.direct[i] += rho * e.environment;
    bandShading_.indirect[i] = rho * e.nodes;
    if (!p.bsdf.onlyDiffuse()) ++glossy_;
  }

  // The receivers `which` (indices into the band's points), each from a micro-buffer of its own, in
  // chunks of at most 2^14 buffers. A receiver on a surface seen from behind (a wall of outward
  // faces seen from inside) renders with back faces occluding: culled, they would show what lies
  // beyond (micro-rendering does the same).
  void shadeFromOwnBuffers(const EyePaths& eye, std::span<const uint32_t> which) {
    MicroRenderSettings backSettings = settings_;
    backSettings.backFacesOcclude = true;
    std::vector<uint32_t> sorted(which.begin(), which.end());
    const size_t front = size_t(std::stable_partition(sorted.begin(), sorted.end(), [&](uint32_t i) {
                                  return dot(eye.points[i].normal, eye.points[i].geometricNormal) >= 0;
                                }) - sorted.begin());
    texels_.resize(std::min<size_t>(std::max<size_t>(sorted.size(), 1), 1u << 14) * primaryTexelCount_);
    const size_t chunk = texels_.size() / primaryTexelCount_;
    for (const bool back : {false, true}) {
      const std::span<const uint32_t> group = back ? std::span(sorted).subspan(front) : std::span(sorted).subspan(0, front);
      for (size_t first = 0; first < group.size(); first += chunk) {
        const size_t count = std::min(chunk, group.size() - first);
        renderBuffers(micro_, back ? backSettings : settings_, primaryQuadrature_, count,
                      [&](size_t k) {
                        const ShadingPoint& p = eye.points[group[first + k]];
                        return BufferOrigin{p.position, p.normal, surfaceNormalOnSideOf(p.geometricNormal, p.normal)};
                      },
                      texels_, counters_);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 64), [&](const tbb::blocked_range<size_t>& r) {
          stopPoint();
          for (size_t k = r.begin(); k != r.end(); ++k)
            shade(eye, group[first + k],
                  bufferIrradiance(std::span(texels_).subspan(k * primaryTexelCount_, primaryTexelCount_),
                                   primaryQuadrature_, eye.points[group[first + k]].normal, env_, direct_));
        });
      }
    }
  }

  const Scene& scene_;
  const Visibility& vis_;
  const EnvPbgiOptions& o_;
  RenderDriver& driver_;
  const RenderPart& part_;
  RenderStats& stats_;
  const Environment& env_;
  const BufferQuadrature primaryQuadrature_ = makeQuadrature(o_.mapping, o_.primaryBufferSide);
  const BufferQuadrature secondaryQuadrature_ = makeQuadrature(o_.mapping, o_.secondaryBufferSide);
  const uint32_t primaryTexelCount_ = primaryQuadrature_.texels();

  // The hierarchy and what the stages find on it, node by node.
  EnvHierarchy h_;
  MicroHierarchy micro_;  // reads h_.points
  MicroRenderSettings settings_;
  std::vector<uint32_t> primary_, primaryTexels_;  // the primary points and their buffers
  SelectionCounts counts_;
  std::vector<Rgb> direct_;
  std::vector<RadianceCache> caches_;
  CacheGrid grid_;

  // The pixels' scratch, reused from band to band.
  PointRadiance bandShading_{0};
  std::vector<uint32_t> texels_, tileOfPoint_;
  std::vector<float> depthOfPoint_;
  std::vector<uint8_t> unreached_;
  TileLists tileLists_;
  double imageSeconds_ = 0;

  MicroCounters counters_;
  uint64_t shadowRays_ = 0, secondaryWithoutLight_ = 0, eyeRays_ = 0, shadingPoints_ = 0, invalidSamples_ = 0;
  std::atomic<uint64_t> fallbacks_{0}, glossy_{0}, cacheCandidates_{0};
};

}  // namespace

RenderOutput renderEnvPbgi(const Scene& scene, const Visibility& vis, const EnvPbgiOptions& o,
                           const RenderControl& control) {
  RenderDriver driver(envPbgiOptionTable(), o, control, scene, vis, "--method envpbgi renders the image at once");
  requireEnvironmentLights(scene);
  if (hasCutOutSurfaces(scene))
    throw std::invalid_argument("--method envpbgi places its surface points on the surfaces, which would cover the holes of '" +
                                scene.sourcePath + "' (glTF alphaMode MASK or BLEND): render it with pt, pmfg or purcell");
  RenderOutput out;
  auto report = [&](double fraction) { driver.reportProgress(fraction); };
  EnvPbgiRender render(scene, vis, o, driver, out.stats);
  render.buildHierarchy();
  out.stats.addCounter("points", render.leafCount());
  report(0.05);
  render.selectPrimary();
  render.selectSecondary();
  report(0.3);
  render.selectDirectLightPoints();
  render.computeDirectLight();
  report(0.55);
  render.propagate();
  render.buildCaches();
  report(0.65);
  render.shadePixels(out);
  report(1.0);
  render.reportCounters(out);
  return out;
}

}  // namespace lucent
