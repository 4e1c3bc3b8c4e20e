// --method micro: the renderer of Ritschel et al. 2009. Camera paths (through mirrors and glass) to
// diffuse and glossy shading points; direct light there by shadow rays, at every pixel; indirect
// light by micro-rendering final gathering at every pixel or at a lattice of 1/4 or 1/16 of them
// with bilateral upsampling (2.4); gather points processed in 3-D Morton order (3.2), grouped by
// the axis their normal faces most.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <atomic>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

#include "gathering.h"
#include "lucent/core/dump.h"
#include "lucent/core/memory.h"
#include "lucent/core/morton.h"
#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"
#include "lucent/methods/microrender.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_driver.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/surface.h"
#include "point_lighting.h"
#include "upsampling.h"

namespace lucent {

namespace {

enum class MicroStream : uint64_t { Points = 21, Gather = 22 };

// The stage clocks and counters of every thread's gathering, summed.
struct GatherTotals {
  double build = 0, evaluate = 0, rasterize = 0, rayCast = 0, convolve = 0;
  MicroCounters counters;
  void add(const tbb::enumerable_thread_specific<GatherScratch>& scratch) {
    for (const GatherScratch& s : scratch) {
      build += s.buildSeconds, evaluate += s.evaluateSeconds, rasterize += s.rasterizeSeconds;
      convolve += s.convolveSeconds;
      counters += s.counters;
    }
    rayCast = counters.rayCastSeconds;
  }
};

}  // namespace

namespace {

// Dumps (docs/dump-format.md): the hierarchy, the points' radiance, and the shading points with the
// light each part of the image gives them.
void dumpHierarchy(const std::string& dir, const PointHierarchy& h) {
  writeDump(dir, "hierarchy.points", "PointSample", std::span(h.points));
  writeDump(dir, "hierarchy.float_nodes", "FloatNode", std::span(h.floatNodes));
  writeDump(dir, "hierarchy.node_areas", "float", std::span(h.nodeAreas));
  if (h.encoding != NodeEncoding::Packed) return;
  writeDump(dir, "hierarchy.packed_nodes", "PackedNode", std::span(h.packedNodes));
  writeDump(dir, "hierarchy.quantization", "NodeQuantization", std::span(&h.quantization, 1));
}

void dumpPointRadiance(const std::string& dir, const NodeRadiance& radiance) {
  writeDump(dir, "point_radiance", "Rgb", std::span(radiance.rgb));
  if (!radiance.half.empty()) writeDump(dir, "point_radiance_half", "HalfRgb", std::span(radiance.half));
  if (!radiance.directional.empty())
    writeDump(dir, "point_radiance_directional", "DirectionalRadiance", std::span(radiance.directional));
}

}  // namespace

uint32_t defaultPointCount(const Scene& scene, float spacing) {
  const double area = scene.surfaceArea();
  const Camera& c = scene.camera;
  const double distance = std::max(1e-30, double(length(scene.boundingCenter() - c.eye)));
  const double footprint = 2.0 * distance * std::tan(double(c.fovY) * kPi / 360.0) / double(c.height);
  const double n = area / std::pow(spacing * footprint, 2.0);
  const double log2n = std::clamp(std::round(std::log2(std::max(n, 1.0))), 12.0, 22.0);
  return uint32_t(1) << int(log2n);
}

// The lattice pixels beyond a part's crop that bilateral upsampling reads for the crop's pixels
// (those up to a lattice step beyond each edge), traced as the crop's are; none without upsampling.
EyePaths latticeMargin(const Scene& scene, const Visibility& vis, const MicroRenderOptions& o, const RenderPart& part,
                       int step) {
  const PixelRect& crop = part.region;
  const int width = scene.camera.width, height = scene.camera.height;
  const PixelRect wide{crop.x0 / step * step, crop.y0 / step * step,
                       std::min(width, (crop.x1 - 1) / step * step + step + 1),
                       std::min(height, (crop.y1 - 1) / step * step + step + 1)};
  if (step == 1 || wide == crop) return {};
  std::vector<uint8_t> mask(wide.pixelCount(), 0);
  for (int y = wide.y0; y < wide.y1; ++y)
    for (int x = wide.x0; x < wide.x1; ++x)
      mask[size_t(y - wide.y0) * size_t(wide.width()) + size_t(x - wide.x0)] =
          x % step == 0 && y % step == 0 && !crop.contains(x, y);
  EyePathSettings settings = eyePathSettings(o.common, o.shading.maxSpecularDepth, part);
  settings.region = wide;
  settings.pixelMask = mask;
  return traceEyePaths(scene, vis, settings);
}

namespace {

// Final gathering (2.2, 3.2) at a set of gather points (`order`: indices into `points`), by the way
// they face and in Morton order of their positions (facingMortonKey), so that neighbouring work
// items compute similar cuts: on Sponza at 512 x 512, 1/16 of the pixels, a packet visit tests 6.17
// active lanes instead of 5.89. Results go to `indirect`; progress runs from progressBase by
// progressShare.
struct GatherPass {
  const GatherContext& ctx;
  const GatherContext& backCtx;  // the same, back faces occluding
  const NodeRadiance& radiance;
  std::span<const ShadingPoint> points;
  const Scene& scene;
  uint64_t seed;
  const ProgressFn& progress;
  tbb::enumerable_thread_specific<GatherScratch>& scratch;
  UninitializedVector<Rgb>& indirect;

  // Its wall-clock seconds.
  double run(std::vector<uint32_t>& order, double progressShare, double progressBase) const {
    Stopwatch clock;
    if (order.size() >= (size_t(1) << 31)) throw std::logic_error("micro: at most 2^31 - 1 gather points at once");
    std::vector<uint64_t> keys(order.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), kItemsPerTask), [&](const auto& r) {
      stopPoint();
      for (size_t k = r.begin(); k != r.end(); ++k) {
        const ShadingPoint& p = points[order[k]];
        keys[k] = facingMortonKey(p.position, p.normal, scene.bounds) << 31 | order[k];
      }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    for (size_t k = 0; k < keys.size(); ++k) order[k] = uint32_t(keys[k] & ((uint64_t(1) << 31) - 1));
    // Points on a surface seen from behind (one-sided walls seen from inside) gather with back
    // faces occluding: culled, they would show what lies beyond the walls.
    const size_t front = size_t(std::stable_partition(order.begin(), order.end(), [&](uint32_t i) {
                                  return dot(points[i].normal, points[i].geometricNormal) >= 0;
                                }) - order.begin());
    // Packets of consecutive gather points in that order (one SIMD lane each, as the threads of a
    // warp in the paper).
    std::atomic<size_t> done{0};
    for (const bool back : {false, true}) {
      const size_t first = back ? front : 0, count = back ? order.size() - front : front;
      gatherInPackets(
          back ? backCtx : ctx, count, radiance, scratch,
          [&](size_t k, Rng& rng) {
            const ShadingPoint& p = points[order[first + k]];
            rng = Rng(seed, p.pixel, uint64_t(p.sample) << 32 | p.branch);
            return GatherRequest{p.position, p.normal, surfaceNormalOnSideOf(p.geometricNormal, p.normal), p.wo, &p.bsdf, &rng};
          },
          [&](size_t k, Rgb result) { indirect[order[first + k]] = result; },
          [&](size_t gathered) {
            if (progress) progress(progressBase + progressShare * double(done += gathered) / double(order.size()));
          });
    }
    return clock.seconds();
  }
};

// The hierarchy's stages as the paper's Table 1 has them: its build's parts, and their sum over the
// node data that a deforming scene would refit every frame, the "hierarchy update".
void reportHierarchyStages(const RenderStats& hierarchyStats, RenderStats& stats) {
  double update = 0;
  for (const auto& [name, s] : hierarchyStats.stageSeconds) {
    stats.addStage("hierarchy." + name, s);
    if (name == "leaf_nodes" || name == "interior_nodes" || name == "packed_nodes") update += s;
  }
  stats.addStage("hierarchy_update", update);
}

// Gathering's parts are timed per thread; the stage's wall time is split in proportion.
GatherTotals reportGatherStages(const tbb::enumerable_thread_specific<GatherScratch>& scratch, double gatherSeconds,
                                double upsampleSeconds, RenderStats& stats) {
  GatherTotals totals;
  totals.add(scratch);
  const double cpu = totals.build + totals.evaluate + totals.rasterize + totals.rayCast + totals.convolve;
  const double scale = cpu > 0 ? gatherSeconds / cpu : 0.0;
  stats.addStage("final_gathering", gatherSeconds);
  stats.addStage("build_mappings", totals.build * scale);
  stats.addStage("evaluate_mappings", totals.evaluate * scale);
  stats.addStage("rasterize", totals.rasterize * scale);
  stats.addStage("ray_casting", totals.rayCast * scale);
  stats.addStage("convolution", totals.convolve * scale);
  stats.addStage("upsampling", upsampleSeconds);
  return totals;
}

}  // namespace

RenderOutput renderMicro(const Scene& scene, const Visibility& vis, const MicroRenderOptions& o,
                         const RenderControl& control) {
  // Gathering runs over the whole part at once (its Morton order and the upsampling lattice span
  // it): there is no state between stages to checkpoint.
  RenderDriver driver(microOptionTable(), o, control, scene, vis, "--method micro gathers the whole image at once");
  const RenderPart& part = driver.part();
  if (hasCutOutSurfaces(scene))
    throw std::invalid_argument("--method micro places its point hierarchy's points on the surfaces, which would cover the holes of '" +
                                scene.sourcePath + "' (glTF alphaMode MASK or BLEND): render it with pt, pmfg or purcell");
  RenderOutput out;
  RenderStats& stats = out.stats;

  // The point hierarchy (2.1).
  PointHierarchyOptions ho;
  ho.pointCount = o.points > 0 ? o.points : defaultPointCount(scene, o.pointSpacing);
  ho.encoding = o.encoding;
  ho.sampling.seed = hashKey(o.common.seed, uint64_t(MicroStream::Points));
  // Two nodes per point (leaves and interior), each as floats in the hierarchy and in the micro
  // copy, packed, with its area, radiance and thickness; the samples and the median split's keys.
  const uint64_t nodeBytes = 2 * sizeof(FloatNode) + sizeof(PackedNode) + sizeof(float) + sizeof(Rgb) + 2 * sizeof(float);
  requireMemory(uint64_t(ho.pointCount) * (2 * nodeBytes + sizeof(PointSample) + 32), "the point hierarchy",
                "lower --points or raise --point-spacing");
  RenderStats hierarchyStats;
  PointHierarchy hierarchy;
  MicroHierarchy micro;  // reads `hierarchy`
  {
    StageTimer timer(stats, "hierarchy");
    hierarchy = buildPointHierarchy(scene, ho, &hierarchyStats);
    micro = prepareMicroHierarchy(hierarchy);
  }
  reportHierarchyStages(hierarchyStats, stats);
  stats.addCounter("points", hierarchy.leafCount);
  stats.addDerived("points", hierarchy.leafCount);
  if (!o.shading.dumpDirectory.empty()) dumpHierarchy(o.shading.dumpDirectory, hierarchy);

  MicroRenderSettings settings;
  settings.rayCasting = o.rayCasting;
  settings.splatReach = o.splatReach;
  settings.depth = DepthCoding::forExtent(length(scene.bounds.extent()));
  const MappingTables tables = makeMappingTables(o.bufferSide, o.tableSize);
  const GatherContext ctx{&micro, &tables, o.mapping, settings};
  GatherContext backCtx = ctx;
  backCtx.settings.backFacesOcclude = true;

  // Section 4: the radiance of the points.
  NodeRadiance radiance;
  {
    StageTimer timer(stats, "point_lighting");
    radiance = lightPoints(scene, vis, hierarchy, ctx, o, stats);
  }
  if (!o.shading.dumpDirectory.empty()) dumpPointRadiance(o.shading.dumpDirectory, radiance);

  // Camera paths and direct light, at every pixel.
  EyePaths eye;
  PointRadiance shading(0);
  uint64_t shadowRays = 0;
  {
    StageTimer timer(stats, "eye_rays_and_direct_light");
    eye = traceEyePaths(scene, vis, eyePathSettings(o.common, o.shading.maxSpecularDepth, part));
    shading = PointRadiance(eye.points.size());
    if (o.shading.lightSamples > 0) estimateDirectLight(scene, vis, eye.points, o.shading.lightSamples, o.common.seed, shading.direct, shadowRays);
  }
  const size_t n = eye.points.size();

  // Final gathering at the points of the gathering lattice (every pixel without upsampling). A
  // crop's pixels near its edges interpolate from lattice pixels beyond it: those are traced and
  // gathered too (after the crop's own points), so that a crop's pixels are the whole image's.
  const int step = o.upsampling == 16 ? 4 : o.upsampling == 4 ? 2 : 1;
  const int width = scene.camera.width;
  const EyePaths margin = latticeMargin(scene, vis, o, part, step);
  std::vector<ShadingPoint> withMargin;
  if (!margin.points.empty()) {
    withMargin.assign(eye.points.begin(), eye.points.end());
    withMargin.insert(withMargin.end(), margin.points.begin(), margin.points.end());
  }
  const std::span<const ShadingPoint> points =
      withMargin.empty() ? std::span<const ShadingPoint>(eye.points) : std::span<const ShadingPoint>(withMargin);
  UninitializedVector<Rgb> indirect(points.size());
  std::vector<uint32_t> gatherOrder;
  for (uint32_t i = 0; i < points.size(); ++i)
    if (onGatherLattice(points[i].pixel, width, step)) gatherOrder.push_back(i);
  tbb::enumerable_thread_specific<GatherScratch> scratch;
  const GatherPass pass{ctx,   backCtx, radiance, points,  scene, hashKey(o.common.seed, uint64_t(MicroStream::Gather)),
                        control.progress, scratch, indirect};
  beginStage("final_gathering");
  double gatherSeconds = pass.run(gatherOrder, step == 1 ? 1.0 : 0.9, 0.0);
  // 2.4: bilateral upsampling from the lattice; the pixels it cannot interpolate are gathered.
  uint64_t recomputed = 0;
  double upsampleSeconds = 0;
  if (step > 1) {
    beginStage("upsampling");
    Stopwatch upClock;
    UpsamplingSettings us;
    us.width = width;
    us.height = scene.camera.height;
    us.step = step;
    us.eye = scene.camera.eye;
    us.pixelAngle = float(2.0 * std::tan(double(scene.camera.fovY) * kPi / 360.0) / scene.camera.height);
    std::vector<uint32_t> left = upsampleIndirect(points, us, indirect);
    upsampleSeconds = upClock.seconds();
    recomputed = left.size();
    gatherSeconds += pass.run(left, 0.1, 0.9);
  }
  std::copy(indirect.begin(), indirect.begin() + ptrdiff_t(n), shading.indirect.begin());
  const GatherTotals totals = reportGatherStages(scratch, gatherSeconds, upsampleSeconds, stats);

  if (!o.shading.dumpDirectory.empty()) dumpShadingPoints(o.shading.dumpDirectory, "", eye, shading, false);
  driver.shadeAtOnce(out, eye, shading, {o.common.layers, false});

  const MicroCounters& c = totals.counters;
  stats.addCounter("eye_rays", eye.rays);
  stats.addCounter("shadow_rays", shadowRays);
  stats.addCounter("shading_points", n);
  stats.addCounter("invalid_samples", eye.invalid + out.film->droppedPoints());
  c.report(stats);
  stats.addCounter("upsampling_recomputed", recomputed);
  stats.addCounter("gather_samples", c.buffers * uint64_t(o.bufferSide) * uint64_t(o.bufferSide));
  return out;
}

}  // namespace lucent
