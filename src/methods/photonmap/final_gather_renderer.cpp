// --method pmfg: Jensen's RT/PM/FG (Jensen 1996; Jensen 2001, chapter 9), the ground truth that GPU
// photon mappers and final gatherers are compared against. At the first diffuse or glossy surface
// reached from the camera (through mirrors, glass and smooth transmitters, the surfaces passed as
// specular: SurfaceBsdf::passedAsSpecular):
//   direct light       shadow rays to the lights (L D E);
//   caustics           the caustic map's radiance estimate (L S+ D E);
//   indirect light     final gathering: gatherRays rays distributed by the BSDF (cosine for
//                      diffuse surfaces), stratified, followed through the surfaces passed as
//                      specular; at the diffuse or glossy surface each reaches, the global map's
//                      estimate with all photons, direct ones included (L {S|D}* D S* D E).
// Emission seen by gather rays (also through specular surfaces) is not added: light reaching the
// shading point straight from an emitter is counted by the shadow rays, and through specular
// surfaces by the caustic map. So is the environment seen by gather rays.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include "lucent/core/oriented_point_grid.h"
#include "lucent/core/parallel.h"
#include "lucent/core/sampling.h"
#include "lucent/core/stop.h"
#include "lucent/scene/surface.h"
#include "estimate_by_cell.h"
#include "band_stages.h"
#include "photon_maps.h"

namespace lucent {
namespace {

// Where a gather ray ended: a diffuse or glossy point to estimate at, and the ray's weight
// (BSDF * cos / pdf at the shading point, times the specular bounces' weights).
struct GatherHit {
  EstimatePoint point;
  Rgb weight;
};

// Per-thread scratch and clocks of the gathering stage.
struct FinalGatherScratch {
  std::vector<GatherHit> hits;
  std::vector<PhotonDistance> heap;
  double traceSeconds = 0, estimateSeconds = 0;
  uint64_t rays = 0;
  uint64_t fallbacks = 0;  // diffuse hits with no precomputed irradiance on their side within reach
  EstimateCounters counters;
};

// Traces the gather rays of one shading point; returns how many reached a diffuse or glossy surface,
// their weights less what the media they crossed absorb.
size_t traceGatherRays(const Scene& scene, const Visibility& vis, const ShadingPoint& point, int count,
                       int maxSpecularDepth, uint64_t seed, GatherHit* hits, uint64_t& rays) {
  Rng rng(seed, point.pixel, uint64_t(point.sample) << 32 | point.branch);
  const Frame frame(point.normal);
  const Vec3 woLocal = frame.toLocal(point.wo);
  size_t found = 0;
  for (int j = 0; j < count; ++j) {
    const float uLobe = rng.uniform();
    const Vec2 u = stratifiedSample2D(uint32_t(j), uint32_t(count), rng.uniform2());
    const BsdfSample bs = sampleBsdf(point.bsdf, woLocal, uLobe, u);
    if (!bs.valid) continue;
    Vec3 wi = frame.toWorld(bs.wi);
    // On the other side of the real surface than the lobe scatters to (a leak past the shading
    // normal; a volume's boundary seen from inside has wo below its frame).
    if (leaksThroughSurface(point.wo, wi, point.geometricNormal, bs.wi.z * woLocal.z < 0)) continue;
    Rgb weight = bs.weight;
    Ray ray{offsetOrigin(point.position, point.geometricNormal, wi), wi};
    uint32_t medium = mediumTowards(scene, scene.materialIds[point.triangle], point.geometricNormal, point.bsdf, wi,
                                    point.medium);
    for (int depth = 0;; ++depth) {
      ++rays;
      const Hit hit = vis.intersect(ray);
      if (!hit.found()) break;  // the environment is direct light
      if (medium != kNoMedium) weight *= transmittanceIn(scene, medium, hit.t);
      const ChainVertex v = chainVertexAt(scene, surfaceAt(scene, hit.triangle, hit.b1, hit.b2), ray.direction);
      if (!v.bsdf.passedAsSpecular()) {
        if (!reflectanceBound(v.bsdf).isBlack())
          hits[found++] = {{v.sp.position, v.frame, v.woLocal, v.bsdf,
                            v.frontFace ? v.sp.geometricNormal : -v.sp.geometricNormal},
                           weight};
        break;
      }
      if (depth >= maxSpecularDepth) break;
      // Through a mirror, glass or a smooth transmitter: one lobe, chosen with its probability (and
      // the smooth lobe's direction in it).
      const float uL = rng.uniform();
      const BsdfSample s = sampleBsdf(v.bsdf, v.woLocal, uL, v.bsdf.isDelta() ? Vec2{} : rng.uniform2());
      const std::optional<Ray> next = followLobe(v, s);
      if (!next) break;
      weight *= s.weight;
      if (weight.isBlack() || !isFinite(weight)) break;
      ray = *next;
      medium = mediumTowards(scene, v.sp, v.bsdf, ray.direction, medium);
    }
  }
  return found;
}

// Christensen 1999 ("Faster photon map global illumination"; Jensen 2001, 9.3): the irradiance
// at every stride-th photon of the global map, estimated from the map at the photon's side of its
// surface, in a grid of the photons' positions and facing normals. A gather ray's diffuse hit then
// reads the nearest one that lies on its surface's side (photonLights) instead of estimating from
// k photons.
struct PrecomputedIrradiance {
  std::vector<Rgb> irradiance;  // by sample
  OrientedPointGrid grid;       // the samples' positions and facing normals
  float reach = 0;              // how far a hit looks for one
};

template <class Map>
PrecomputedIrradiance precomputeIrradiance(const Scene& scene, const Map& map, std::span<const Photon> photons,
                                           const EstimateSettings& settings, uint32_t stride,
                                           EstimateCounters& counters) {
  const size_t n = (photons.size() + stride - 1) / stride;
  PrecomputedIrradiance out;
  out.irradiance.resize(n);
  std::vector<OrientedPoint> points(n);
  tbb::enumerable_thread_specific<std::vector<PhotonDistance>> heaps([&] { return std::vector<PhotonDistance>(settings.k); });
  tbb::enumerable_thread_specific<EstimateCounters> local;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    std::vector<PhotonDistance>& heap = heaps.local();
    EstimateCounters& c = local.local();
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Photon& p = photons[i * stride];
      const Vec3 facing = photonFacing(p);
      EstimatePoint q;
      q.position = p.position;
      q.frame = Frame(facing);
      q.woLocal = {0, 0, 1};
      q.bsdf = LambertianLobe{Rgb(1.0f)};
      q.facingNormal = facing;
      // A white Lambertian surface reflects E / pi.
      out.irradiance[i] = estimateRadiance(map, q, settings, heap.data(), c) * kPi;
      points[i] = {p.position, facing, uint32_t(i)};
    }
  });
  for (const EstimateCounters& c : local) counters += c;
  // Cells about twice the samples' mean spacing over the scene's surfaces; a hit looks four
  // spacings (two cells) far.
  const float spacing = float(std::sqrt(scene.surfaceArea() / double(std::max<size_t>(n, 1))));
  out.grid = buildOrientedPointGrid(points, 2 * spacing);
  out.reach = 4 * spacing;
  return out;
}

// The radiance a diffuse point reflects from the precomputed irradiance nearest to it on its side
// of its surface; false if none is within reach.
bool irradianceAt(const PrecomputedIrradiance& samples, const EstimatePoint& q, Rgb& radiance) {
  const SurfaceSide side = q.side();
  const uint32_t nearest = samples.grid.nearest(q.position, samples.reach, [&](const OrientedPoint& s, float d2) {
    return photonLights(s.normal, s.normal, s.position - q.position, d2, side);
  });
  if (nearest == kNoPoint) return false;
  radiance = samples.irradiance[nearest] * q.bsdf.diffuse() * kInvPi;
  return true;
}

}  // namespace

RenderOutput renderPhotonMapFinalGather(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                                        const RenderControl& control) {
  RenderDriver driver(pmfgOptionTable(), options, control, scene, vis);
  if (options.bandSamples < 1) throw std::invalid_argument("band samples must be at least 1");
  RenderOutput out;
  const RenderPhotonMaps maps = preparePhotonMaps(scene, vis, options, GlobalPhotons::All, out.stats);

  const Film& film = driver.startFilm(Film::Sums::PerPart, {options.common.layers, true});
  const uint32_t heapSize = maps.globalSettings.k;  // the caustic map is estimated by estimateAtPoints
  tbb::enumerable_thread_specific<FinalGatherScratch> scratch([&] {
    FinalGatherScratch s;
    s.hits.resize(size_t(options.gatherRays));
    s.heap.resize(heapSize);
    return s;
  });
  // Christensen 1999: the irradiance at every irradianceStride-th global photon, once.
  PrecomputedIrradiance irradiance;
  EstimateCounters irradianceCounters;
  uint64_t irradianceFallbacks = 0;
  const bool precomputed = options.gatherEstimate == GatherEstimate::Irradiance && options.gatherRays > 0;
  if (precomputed) {
    beginStage("precompute_irradiance");
    Stopwatch clock;
    withPhotonMaps(maps, options.map, [&](const auto* global, const auto*) {
      if (global)
        irradiance = precomputeIrradiance(scene, *global, std::span<const Photon>(global->photons),
                                          maps.globalSettings, options.irradianceStride, irradianceCounters);
    });
    out.stats.addStage("precompute_irradiance", clock.seconds());
  }
  tbb::enumerable_thread_specific<EstimateCounters> causticCounters;
  const uint64_t gatherSeed = streamSeed(options.common.seed, RenderStream::Gather);
  RenderTotals totals;
  renderBands(scene, vis, options, driver, totals, [&](BandShadingPoints& band, const auto& progress) {
    const EyePaths& eye = band.eye;
    PointRadiance& radiance = band.radiance;
    const size_t n = eye.points.size();
    withPhotonMaps(maps, options.map, [&](const auto* global, const auto* caustic) {
      // Caustics: the caustic map's estimate at every shading point.
      Stopwatch causticClock;
      estimateAtPoints(caustic, eye.points, maps.causticSettings, radiance.caustic, causticCounters);
      totals.estimateSeconds += causticClock.seconds();

      // Final gathering: per shading point, trace its gather rays, then estimate at their hits. The
      // two parts are timed per thread and the stage's wall time is split between trace_rays and
      // radiance_estimate in proportion.
      if (!global || options.gatherRays == 0) return;
      Stopwatch gatherClock;
      for (FinalGatherScratch& s : scratch) s.traceSeconds = s.estimateSeconds = 0;
      std::atomic<size_t> done{0};
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
        stopPoint();
        flushDenormals();
        FinalGatherScratch& s = scratch.local();
        for (size_t i = r.begin(); i != r.end(); ++i) {
          const ShadingPoint& point = eye.points[i];
          Stopwatch traceClock;
          const size_t hits = traceGatherRays(scene, vis, point, options.gatherRays, options.shading.maxSpecularDepth,
                                              gatherSeed, s.hits.data(), s.rays);
          s.traceSeconds += traceClock.seconds();
          Stopwatch estimateClock;
          double sum[3] = {0, 0, 0};
          for (size_t h = 0; h < hits; ++h) {
            const EstimatePoint& q = s.hits[h].point;
            Rgb L;
            if (!precomputed || !q.bsdf.onlyDiffuse() ||
                !irradianceAt(irradiance, q, L)) {
              L = estimateRadiance(*global, q, maps.globalSettings, s.heap.data(), s.counters);
              s.fallbacks += precomputed && q.bsdf.onlyDiffuse();
            }
            L = s.hits[h].weight * L;
            for (int c = 0; c < 3; ++c) sum[c] += L[c];
          }
          const double inv = 1.0 / options.gatherRays;
          radiance.indirect[i] = Rgb(float(sum[0] * inv), float(sum[1] * inv), float(sum[2] * inv));
          s.estimateSeconds += estimateClock.seconds();
        }
        progress(double(done += r.size()) / double(n));
      });
      const double wall = gatherClock.seconds();
      double t = 0, e = 0;
      for (const FinalGatherScratch& s : scratch) t += s.traceSeconds, e += s.estimateSeconds;
      const double share = t + e > 0 ? t / (t + e) : 0.5;
      totals.traceSeconds += wall * share;
      totals.estimateSeconds += wall * (1 - share);
    });
  });

  driver.finish(out);
  totals.invalid += film.droppedPoints();
  EstimateCounters gc, cc;
  uint64_t gatherRays = 0;
  for (const FinalGatherScratch& s : scratch) gc += s.counters, gatherRays += s.rays, irradianceFallbacks += s.fallbacks;
  for (const auto& c : causticCounters) cc += c;
  totals.report(out.stats, gc, cc);
  out.stats.addCounter("gather_rays", gatherRays);
  if (precomputed) {
    out.stats.addCounter("irradiance_samples", irradiance.irradiance.size());
    out.stats.addCounter("irradiance_sample_estimates", irradianceCounters.queries);
    out.stats.addCounter("irradiance_fallbacks", irradianceFallbacks);
  }
  return out;
}

}  // namespace lucent
