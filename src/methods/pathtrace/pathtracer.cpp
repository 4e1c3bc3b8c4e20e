#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <iostream>
#include <memory>
#include <span>
#include <utility>

#include "lucent/core/parallel.h"
#include "lucent/core/path_sampler.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_driver.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/surface.h"
#include "methods/pathtrace/contribution_roulette.h"
#include "methods/pathtrace/surface_lanes.h"
#include "methods/pathtrace/error_target.h"
#include "methods/pathtrace/shading_steps.h"

namespace lucent {
namespace {

// What one camera path returns: radiance split by the bounce that gathered it, and the
// first-hit features for the auxiliary layers.
struct PathResult {
  Rgb direct;    // emitters seen directly (also through mirrors and glass) and light gathered at the
                 // first non-specular vertex
  Rgb indirect;  // light gathered at later non-specular vertices
  Rgb albedo;
  Vec3 normal;
  float depth = 0;
  bool valid = true;  // false when a ray became non-finite (the sample is dropped and counted)
};

struct Counters {
  uint64_t rays = 0;
  uint64_t laneShadedHits = 0;
  uint64_t invalidSamples = 0;  // dropped for a non-finite value
};

// One camera path in flight. Paths advance together, one bounce per stage (a wavefront), so that
// their hits can be shaded many at a time (SurfaceLanes).
struct Path {
  uint64_t pixel = 0;
  Ray ray;
  PathSampler sampler;
  Rgb beta{1.0f};
  bool lastDelta = true;  // the camera ray counts as specular: emission seen directly is not MIS'ed
  float lastPdf = 0;
  Vec3 lastPosition;
  int gatheringVertices = 0;  // non-specular vertices the path has scattered from so far
  int bounce = 0;
  uint32_t medium = kNoMedium;  // the attenuating medium the ray travels in (mediumTowards)
  // With --paths, where the light is also split by path (the wave's, kept apart so that a path
  // without it stays small: waves of paths 108 bytes longer traced the Cornell box 4% slower).
  PathParts* parts = nullptr;
  Rgb firstDiffuseShare{1.0f};  // the diffuse share of the BSDF at the first non-specular vertex, the way the path left it
  PathResult result;

  // Light arriving at the vertex the path came from is direct if that vertex was the first
  // non-specular one. `diffuseShare`: the first vertex's, towards the light the path sampled there
  // when that light is the contribution's (next-event estimation at the first vertex).
  void gather(int verticesBefore, Rgb contribution) { gather(verticesBefore, contribution, firstDiffuseShare); }
  void gather(int verticesBefore, Rgb contribution, Rgb diffuseShare) {
    (verticesBefore <= 1 ? result.direct : result.indirect) += contribution;
    if (parts) parts->gather(verticesBefore, contribution, diffuseShare);
  }
  // The auxiliary layers' features, at the first hit.
  void recordFirstHit(Rgb albedo, Vec3 normal, float depth) {
    if (bounce > 0) return;
    result.albedo = albedo, result.normal = normal, result.depth = depth;
  }
};

// A light sample's shadow ray, and what it adds to its path if the light is visible.
struct ShadowQuery {
  Ray ray;
  Rgb contribution;
  Rgb diffuseShare{1.0f};  // of the first non-specular vertex's BSDF, for the split by path
  uint32_t path = 0;
  uint32_t light = 0;  // the light sampled
  int verticesBefore = 0;
};

// Which of the wave's lanes shade a hit (PathTracer::laneKind); None: PathTracer::shade.
enum class LaneKind : uint8_t { None, Lambertian, Gltf };

// Paths traced together, one lane each when shaded (kMaxLanes: waves of 256, see there).
constexpr int64_t kWaveSize = kMaxLanes;

// Closest-hit rays go to Embree in packets of kPacketWidth: at every bounce, the live paths of one
// run of a pixel's samples, in sample order (the Cornell box renders 7% faster than with one ray
// at a time; packets of 8 fill better than of 16 once roulette thins the runs). Where two triangles meet at equal distance a closest hit depends on which other rays
// share the packet, so runs are fixed by the sample indices alone: [64 j, 64 j + 64), and below 64
// the doubling runs [0, 1), [1, 2), [2, 4), ..., [32, 64) of the first passes. A pass or part that
// takes only some of a run's samples traces the others too and drops them (ghosts), so that every
// sample meets the packets of the single render; nextPassEnd ends passes where runs end.
constexpr int kRunLength = 64;
constexpr int kPacketWidth = 8;
int runBegin(int sample) {
  if (sample >= kRunLength) return sample - sample % kRunLength;
  if (sample == 0) return 0;
  int begin = 1;
  while (2 * begin <= sample) begin *= 2;
  return begin;
}
int runEnd(int sample) { return sample >= kRunLength ? runBegin(sample) + kRunLength : std::max(1, 2 * runBegin(sample)); }

// What shading a hit reads of the scene: vertex records and per-triangle records.
size_t sceneArrayBytes(const Scene& s) {
  return s.positions.size() * sizeof(Vec3) + s.normals.size() * sizeof(Vec3) + s.texcoords.size() * sizeof(Vec2) +
         s.tangents.size() * sizeof(Tangent) + s.indices.size() * sizeof(uint32_t) +
         s.materialIds.size() * sizeof(uint32_t) + s.faceNormals.size() * sizeof(Vec3);
}

// The samples a pass takes at each pixel: from sampleBegin plus the samples the film has taken
// there, to sampleEnd, or where pixelEnds is given (an error-targeted render of the whole image) to
// sampleBegin + pixelEnds[pixel].
struct PassSamples {
  int sampleBegin = 0, sampleEnd = 0;
  std::span<const uint32_t> pixelEnds;
  int end(uint64_t pixel) const { return pixelEnds.empty() ? sampleEnd : sampleBegin + int(pixelEnds[pixel]); }
};

class PathTracer {
 public:
  PathTracer(const Scene& scene, const Visibility& vis, const PathTraceOptions& opt)
      : scene_(scene), vis_(vis), opt_(opt), camera_(scene.camera), lightChoice_(scene.lightDistribution) {
    for (uint32_t li = 0; li < scene.lights.size(); ++li) laneLights_.push_back(laneLight(scene, li));
    for (const Material& m : scene.materials)
      laneKinds_.push_back(m.type == MaterialType::Diffuse ? LaneKind::Lambertian
                           : gltfShadedInLanes(m)          ? LaneKind::Gltf
                                                           : LaneKind::None);
  }

  // One bounce of a path whose ray met `hit` (or nothing): emission found, the light sample (its
  // shadow ray queued in `shadow`, `queued` set), and the next ray. False when the path ends.
  bool shade(Path& path, const Hit& hit, ShadowQuery& shadow, bool& queued) const {
    queued = false;
    const Ray& ray = path.ray;
    if (path.medium != kNoMedium) path.beta *= transmittanceIn(scene_, path.medium, hit.found() ? hit.t : kInf);
    if (!hit.found()) {
      if (scene_.environment.present) {
        const Rgb le = environmentRadiance(scene_.environment, ray.direction);
        path.gather(path.gatheringVertices,
                    path.beta * le *
                        emissionWeight(path.lastDelta, path.lastPdf, environmentLightPdf(scene_, lightChoice_, ray.direction)));
      }
      return false;
    }
    const SurfacePoint sp = surfaceAt(scene_, hit.triangle, hit.b1, hit.b2);
    const Vec3 wo = -ray.direction;

    gatherEmission(path, hit, sp.position);
    const SurfaceBsdf worldBsdf = bsdfAt(scene_, sp);
    path.recordFirstHit(layerAlbedo(worldBsdf), sp.shadingNormal, hit.t);
    if (path.bounce + 1 > opt_.maxDepth) return false;

    // Glass keeps the winding orientation (inside/outside); two-sided lobes turn to the viewer.
    const Frame frame(hitFrameNormal(scene_, sp, wo, twoSidedShading(worldBsdf)));
    const Vec3 woLocal = frame.toLocal(wo);
    const SurfaceBsdf bsdf = worldBsdf.inFrame(frame);

    const BounceNumbers u = drawBounceNumbers(path.sampler, path.bounce, !bsdf.isDelta());
    if (!bsdf.isDelta()) {
      queued = sampleDirect(sp, bsdf, frame, woLocal, u.lightPoint, shadow);
      shadow.contribution *= path.beta;
      if (queued)
        shadow.contribution *= transmittanceIn(scene_, mediumTowards(scene_, sp, bsdf, shadow.ray.direction, path.medium),
                                               shadow.ray.tMax);
      shadow.verticesBefore = ++path.gatheringVertices;
      if (path.gatheringVertices > 1) shadow.diffuseShare = path.firstDiffuseShare;
    }

    const BsdfSample bs = sampleBsdf(bsdf, woLocal, u.lobe, u.bsdfDirection);
    if (!bs.valid) return false;
    // Leaving the first non-specular vertex: the rest of the path's light splits as this direction's BSDF value does.
    if (path.parts && !bsdf.isDelta() && path.gatheringVertices == 1)
      path.firstDiffuseShare = diffuseShare(bsdf, woLocal, bs.wi);
    const Vec3 wi = frame.toWorld(bs.wi);
    if (leaksThroughSurface(wo, wi, sp.geometricNormal, bs.wi.z * woLocal.z < 0)) return false;
    path.medium = mediumTowards(scene_, sp, bsdf, wi, path.medium);
    return continuePath(path, bs.weight, bs.pdf, bs.delta, sp.position,
                        {offsetOrigin(sp.position, sp.geometricNormal, wi), wi});
  }

  // Contribution roulette's scales from here on (set between passes).
  void useRoulette(RouletteScales scales) { roulette_ = std::move(scales); }
  // Whether the light samples of the pilot's lattice pixels are added to the waves' LightMoments
  // (between passes); and the choice of light from here on.
  void learnLightChoice(bool learn) { learningLightChoice_ = learn; }
  void useLightChoice(Distribution1D choice) { lightChoice_ = std::move(choice); }

  // The paths of one wave and the queries between its stages; one per thread, reused.
  struct Wave {
    std::vector<Path> paths;
    std::vector<PathParts> parts;  // with --paths, each path's
    std::vector<Hit> hits;
    std::vector<uint32_t> run;   // per path, its run's number in the wave (traced as one packet)
    std::vector<uint8_t> ghost;  // per path, whether the pass takes its sample (0) or only traces it (1)
    std::vector<uint32_t> active, next;
    std::vector<ShadowQuery> shadows;
    std::unique_ptr<SurfaceLanes> lanes = std::make_unique<SurfaceLanes>();  // zeroed
    std::unique_ptr<CameraLanes> camera = std::make_unique<CameraLanes>();
    std::vector<TexturedLane> textured;
    std::vector<uint32_t> otherLights;  // lanes whose light is not a triangle
    LightMoments lightMoments;          // while the pilot learns the light choice
    // The Sobol sampler's numbers of a bounce's lane hits, drawn together in lanes before the hits
    // are fetched: every hit's light point pair (the light's choice and point), then per hit its
    // other pairs (otherLanePairs).
    struct SobolRequests {
      uint32_t lightPoints = 0;
      std::vector<uint64_t> pixelKey;
      std::vector<uint32_t> index, dimension;
      std::vector<float> x, y;
    } sobol;
  };

  // The pass's samples of the tile's pixels, in pixel order, then sample order, in waves; added to
  // the film (and with --target-error to the streams' sums) in that order.
  // Returns the number of samples taken.
  uint64_t renderTile(const PixelRect& tile, const PassSamples& pass, StreamSums* streams, Wave& wave, Counters& counters,
                      Film& film) const;

  // Advances every path of the wave to its end: closest hits for all live paths, then shading,
  // then the queued shadow rays, bounce after bounce. Each path sees the same random numbers and the
  // same arithmetic as if traced alone.
  void traceWave(Wave& w, Counters& counters) const {
    w.hits.resize(w.paths.size());
    w.active.resize(w.paths.size());
    for (uint32_t i = 0; i < w.paths.size(); ++i) w.active[i] = i;
    for (RayKind kind = RayKind::Camera; !w.active.empty(); kind = RayKind::Secondary) {
      traceClosestHits(w, kind);
      size_t live = 0;
      for (const uint32_t i : w.active) {
        Path& path = w.paths[i];
        // An untraceable ray misses (Visibility does not trace it), so hits need no test of their own.
        if (!w.hits[i].found() && !traceable(path.ray)) {
          path.result.valid = false;  // the sample is dropped and counted
          continue;
        }
        w.active[live++] = i;
      }
      w.active.resize(live);
      counters.rays += live;
      w.next.clear();
      w.shadows.clear();
      SurfaceLanes& lanes = *w.lanes;
      lanes.count = 0;
      lanes.gltfFirst = kMaxLanes;
      lanes.strategy = opt_.strategy;
      w.textured.clear();
      w.otherLights.clear();
      const bool drawnInLanes = drawLaneNumbers(w);
      // The next lane's light point pair and other pairs in w.sobol.
      DrawnPairs drawn{0, w.sobol.lightPoints};
      for (const uint32_t i : w.active) {
        if (const LaneKind kind = laneKind(w.paths[i], w.hits[i]); kind != LaneKind::None) {
          const DrawnPairs pairs =
              drawnInLanes ? std::exchange(drawn, {drawn.lightPoint + 1, drawn.rest + otherLanePairs(w.paths[i], kind)})
                           : DrawnPairs{kNotDrawn, 0};
          fetchLane(w.paths[i], w.hits[i], kind, i, lanes, w.textured, w.otherLights, pairs, w.sobol);
          continue;
        }
        ShadowQuery shadow;
        bool queued;
        if (shade(w.paths[i], w.hits[i], shadow, queued)) w.next.push_back(i);
        if (queued) {
          shadow.path = i;
          w.shadows.push_back(shadow);
        }
      }
      shadeLanes(w, counters);
      counters.rays += w.shadows.size();
      traceShadows(w);
      std::swap(w.active, w.next);
    }
  }

 private:
  // The wave's shadow rays, in packets of 16 (9% faster than one by one on the Cornell box;
  // docs/measurements/pathtrace.md), and the light of those that reach it added to their paths in query order.
  void traceShadows(Wave& w) const {
    occludedInPackets(
        vis_, w.shadows.size(), [&](size_t i) -> const Ray& { return w.shadows[i].ray; },
        [&](size_t i, bool blocked) {
          const ShadowQuery& shadow = w.shadows[i];
          if (blocked) return;
          Path& path = w.paths[shadow.path];
          path.gather(shadow.verticesBefore, shadow.contribution, shadow.diffuseShare);
          if (learningLightChoice_ && !w.ghost[shadow.path] && onPilotLattice(int(path.pixel % imageWidth_), int(path.pixel / imageWidth_)))
            w.lightMoments.add(scene_.lights[shadow.light].type, shadow.contribution);
        });
  }

  // The closest hits of the wave's live paths, the live paths of a run in one packet (a lone one as
  // a single ray, as in every render).
  void traceClosestHits(Wave& w, RayKind kind) const {
    const std::vector<uint32_t>& live = w.active;
    size_t previousRun = 0;
    for (size_t first = 0; first < live.size();) {
      size_t last = first + 1;
      while (last < live.size() && last - first < kPacketWidth && w.run[live[last]] == w.run[live[first]]) ++last;
      if (last - first == 1) {
        w.hits[live[first]] = vis_.intersect(w.paths[live[first]].ray, kind);
      } else {
        Hit hits[kPacketWidth];
        intersectPacket<kPacketWidth>(
            vis_, int(last - first), [&](int j) -> const Ray& { return w.paths[live[first + size_t(j)]].ray; }, hits,
            kind);
        for (size_t j = first; j < last; ++j) w.hits[live[j]] = hits[j - first];
      }
      if (prefetchSceneData_) {
        // The run's triangle records now, the vertices of the run before (their indices have
        // arrived): both are in cache when fetchLane reads them, one Embree query later.
        for (size_t j = first; j < last; ++j) prefetchTriangle(w.hits[live[j]]);
        for (size_t j = previousRun; j < first; ++j) prefetchVertices(w.hits[live[j]]);
      }
      previousRun = first;
      first = last;
    }
  }

  void prefetchTriangle(const Hit& hit) const {
    if (!hit.found()) return;
    __builtin_prefetch(&scene_.indices[3 * size_t(hit.triangle)]);
    __builtin_prefetch(&scene_.materialIds[hit.triangle]);
    __builtin_prefetch(&scene_.faceNormals[hit.triangle]);
  }
  void prefetchVertices(const Hit& hit) const {
    if (!hit.found()) return;
    const uint32_t* v = &scene_.indices[3 * size_t(hit.triangle)];
    for (int k = 0; k < 3; ++k) {
      __builtin_prefetch(&scene_.positions[v[k]]);
      __builtin_prefetch(&scene_.normals[v[k]]);
      if (!scene_.texcoords.empty()) __builtin_prefetch(&scene_.texcoords[v[k]]);  // built in code: maybe none
      if (!scene_.tangents.empty()) __builtin_prefetch(&scene_.tangents[v[k]]);    // for normal textures
    }
  }

  // The Lambertian and glTF hits fetched into the wave's lanes: their textures' texels, their lights
  // other than LaneLights, the lanes' shading (all at once, or one lane at a time without
  // laneShading), and what it gives their paths; the lanes are then empty.
  void shadeLanes(Wave& w, Counters& counters) const {
    SurfaceLanes& lanes = *w.lanes;
    const uint32_t gltfFirst = lanes.gltfFirst, gltfEnd = kMaxLanes;
    if (lanes.count == 0 && gltfFirst == gltfEnd) return;
    counters.laneShadedHits += lanes.count + (gltfEnd - gltfFirst);
    readLaneTextures(lanes, w.textured);
    sampleOtherLights(lanes, w.otherLights);
    if (opt_.laneShading) {
      shadeDiffuseLanes(lanes, 0, lanes.count);
      shadeGltfLanes(lanes, gltfFirst, gltfEnd);
    } else {
      for (uint32_t k = 0; k < lanes.count; ++k) shadeDiffuseLanes(lanes, k, k + 1);
      for (uint32_t k = gltfFirst; k < gltfEnd; ++k) shadeGltfLanes(lanes, k, k + 1);
    }
    finishLanes(lanes, w);
    lanes.count = 0;
    lanes.gltfFirst = kMaxLanes;
    w.textured.clear();
    w.otherLights.clear();
  }

  // With the Sobol sampler, the numbers fetchLane takes for every Lambertian and glTF hit of
  // the bounce, drawn in lanes: the hits' light points, then their other pairs, each in the order of
  // the hits (light points take more work, which a batch of them alone pays: sobolPairs). False with
  // the independent sampler, whose numbers come in sequence from each path's generator, and without
  // laneShading, where each path draws its own as shade() does.
  static constexpr uint32_t kNotDrawn = ~0u;
  bool drawLaneNumbers(Wave& w) const {
    if (opt_.sampler != SamplerKind::Sobol || !opt_.laneShading) return false;
    Wave::SobolRequests& r = w.sobol;
    r.pixelKey.clear(), r.index.clear(), r.dimension.clear();
    auto request = [&](const Path& path, uint32_t dimension) {
      r.pixelKey.push_back(path.sampler.pixelKey());
      r.index.push_back(path.sampler.index());
      r.dimension.push_back(dimension);
    };
    for (const uint32_t i : w.active)
      if (laneKind(w.paths[i], w.hits[i]) != LaneKind::None)
        request(w.paths[i], PathSampler::dimension(w.paths[i].bounce, SampleUse::LightPoint));
    r.lightPoints = uint32_t(r.index.size());
    for (const uint32_t i : w.active) {
      const Path& path = w.paths[i];
      const LaneKind kind = laneKind(path, w.hits[i]);
      if (kind == LaneKind::None) continue;
      const uint32_t lobe = PathSampler::dimension(path.bounce, SampleUse::Lobe) & ~1u;  // the pair holding it
      const uint32_t roulette = PathSampler::dimension(path.bounce + 1, SampleUse::Roulette);
      const uint32_t dimensions[] = {PathSampler::dimension(path.bounce, SampleUse::BsdfDirection),
                                     kind == LaneKind::Gltf ? lobe : roulette, roulette};
      for (uint32_t k = 0; k < otherLanePairs(path, kind); ++k) request(path, dimensions[k]);
    }
    const uint32_t all = uint32_t(r.index.size()), lights = r.lightPoints;
    r.x.resize(all), r.y.resize(all);
    sobolPairs(r.pixelKey.data(), r.index.data(), r.dimension.data(), lights, r.x.data(), r.y.data());
    sobolPairs(r.pixelKey.data() + lights, r.index.data() + lights, r.dimension.data() + lights, all - lights,
               r.x.data() + lights, r.y.data() + lights);
    return true;
  }
  // Where a lane hit's pairs are in the wave's SobolRequests: its light point's, and its other
  // pairs' from `rest` on (the BSDF direction's, a glTF hit's lobe choice's, the roulette's).
  struct DrawnPairs {
    uint32_t lightPoint, rest;
  };

  // The Sobol pairs drawn in lanes for a hit besides its light point's: its BSDF direction's, a glTF
  // hit's lobe choice's (the second of its bounce's roulette pair), and where roulette may end the
  // path on the next bounce, that bounce's roulette pair.
  uint32_t otherLanePairs(const Path& path, LaneKind kind) const {
    return 1 + (kind == LaneKind::Gltf ? 1 : 0) + (path.bounce + 1 >= opt_.rouletteDepth ? 1 : 0);
  }

  // Which lanes shade a hit: Lambertian surfaces and the glTF materials of gltfShadedInLanes below
  // the depth limit, reached outside any medium (shade() takes the other materials' hits and the
  // attenuated paths).
  LaneKind laneKind(const Path& path, const Hit& hit) const {
    if (!hit.found() || path.bounce >= opt_.maxDepth || path.medium != kNoMedium) return LaneKind::None;
    return laneKinds_[scene_.materialIds[hit.triangle]];
  }

  // The lane's surface data and the random numbers shade draws (drawBounceNumbers): the
  // independent sampler's from the path's generator, the Sobol sampler's drawn beforehand (at
  // `drawn` in `sobol`).
  void fetchLane(Path& path, const Hit& hit, LaneKind kind, uint32_t pathIndex, SurfaceLanes& l,
                        std::vector<TexturedLane>& textured, std::vector<uint32_t>& otherLights, DrawnPairs drawn,
                        const Wave::SobolRequests& sobol) const {
    const bool gltf = kind == LaneKind::Gltf;
    const uint32_t k = gltf ? --l.gltfFirst : l.count++;
    const Scene& s = scene_;
    l.path[k] = pathIndex;
    if (gltf) fetchGltfSurface(s, hit, path.ray.direction, l, k, textured);
    else fetchLambertianSurface(s, hit, path.ray.direction, l, k, textured);
    const Vec3 position{l.posX[k], l.posY[k], l.posZ[k]};
    if (drawn.lightPoint != kNotDrawn) {
      const uint32_t rest = drawn.rest;
      l.uLightX[k] = sobol.x[drawn.lightPoint], l.uLightY[k] = sobol.y[drawn.lightPoint];
      l.uBsdfX[k] = sobol.x[rest], l.uBsdfY[k] = sobol.y[rest];
      const uint32_t next = rest + 1 + (gltf ? 1 : 0);
      if (gltf) l.uLobe[k] = sobol.y[rest + 1];
      // The next bounce's roulette pair holds its lobe choice too, which shade draws itself.
      l.uRoulette[k] = next < rest + otherLanePairs(path, kind) ? sobol.x[next] : kDrawLater;
    } else {
      l.uRoulette[k] = kDrawLater;
      // shade's numbers, its lobe choice among them (which a Lambertian surface does not use).
      const BounceNumbers u = drawBounceNumbers(path.sampler, path.bounce, true);
      l.uLightX[k] = u.lightPoint.x, l.uLightY[k] = u.lightPoint.y;
      l.uLobe[k] = u.lobe;
      l.uBsdfX[k] = u.bsdfDirection.x, l.uBsdfY[k] = u.bsdfDirection.y;
    }

    // The light, chosen by the light point's first number (rescaled for the point): a LaneLight's
    // data for the lanes' own sampling; any other light is sampled by sampleOtherLights, as is the
    // no light of a scene without one (no sample then).
    const LightChoice choice =
        s.lights.empty() ? LightChoice{} : chooseLight(s, lightChoice_, position, l.uLightX[k], &l.uLightX[k]);
    l.light[k] = choice.light;
    l.lightPmf[k] = choice.pmf;
    const LaneLight* light = s.lights.empty() ? nullptr : &laneLights_[choice.light];
    l.lightIsTriangle[k] = light && light->isTriangle;
    l.lightDelta[k] = false;  // set by sampleOtherLights for the others
    if (!l.lightIsTriangle[k]) {
      otherLights.push_back(k);
      return;
    }
    fetchLaneLight(*light, l, k);
  }

  // Point, directional and environment lights and two-sided or textured emitters: the light each lane
  // chose, sampled at its surface point.
  void sampleOtherLights(SurfaceLanes& l, const std::vector<uint32_t>& lanes) const {
    for (const uint32_t k : lanes) {
      const LightSample ls = scene_.lights.empty() ? LightSample{}
                                                   : sampleChosenLight(scene_, l.light[k], l.lightPmf[k], {l.posX[k], l.posY[k], l.posZ[k]},
                                                                       {l.uLightX[k], l.uLightY[k]});
      l.wiX[k] = ls.wi.x, l.wiY[k] = ls.wi.y, l.wiZ[k] = ls.wi.z, l.lightDistance[k] = ls.distance;
      l.pointX[k] = ls.point.x, l.pointY[k] = ls.point.y, l.pointZ[k] = ls.point.z;
      l.leR[k] = ls.radiance.r, l.leG[k] = ls.radiance.g, l.leB[k] = ls.radiance.b;
      l.lightPdf[k] = ls.pdf;
      l.lightDelta[k] = ls.delta;
    }
  }

  // What shade does with the lanes' results: emission, first-hit layers, the shadow query, the
  // next ray and Russian roulette; Lambertian lanes first, then glTF lanes, each in the order of
  // their paths.
  void finishLanes(const SurfaceLanes& l, Wave& w) const {
    for (uint32_t k = 0; k < l.count; ++k) finishLane(l, k, false, w);
    for (uint32_t k = kMaxLanes; k-- > l.gltfFirst;) finishLane(l, k, true, w);
  }
  void finishLane(const SurfaceLanes& l, uint32_t k, bool gltf, Wave& w) const {
    const uint32_t i = l.path[k];
    Path& path = w.paths[i];
    const Hit& hit = w.hits[i];
    const Vec3 position{l.posX[k], l.posY[k], l.posZ[k]};
    if (l.emits[k]) gatherEmission(path, hit, position);
    auto lobe = [&] {
      return gltf ? SurfaceBsdf(gltfLaneLobe(l, k)) : SurfaceBsdf(LambertianLobe{{l.kdR[k], l.kdG[k], l.kdB[k]}});
    };
    if (path.bounce == 0) path.recordFirstHit(layerAlbedo(lobe()), {l.snX[k], l.snY[k], l.snZ[k]}, hit.t);
    const int verticesBefore = ++path.gatheringVertices;
    // The diffuse share of the lobe towards wi at the path's first non-specular vertex, for the
    // split by path: all of a Lambertian surface's light.
    auto firstVertexShare = [&](Vec3 wi) {
      if (!gltf || !path.parts) return Rgb(1.0f);
      const Frame frame({l.frameX[k], l.frameY[k], l.frameZ[k]});
      return diffuseShare(lobe(), frame.toLocal(-path.ray.direction), frame.toLocal(wi));
    };
    if (l.shadowQueued[k]) {
      ShadowQuery& shadow = w.shadows.emplace_back();
      shadow.ray = {{l.shadowOx[k], l.shadowOy[k], l.shadowOz[k]}, {l.shadowDx[k], l.shadowDy[k], l.shadowDz[k]}};
      shadow.ray.tMax = l.shadowTMax[k];
      shadow.contribution = Rgb(l.directR[k], l.directG[k], l.directB[k]) * path.beta;
      shadow.verticesBefore = verticesBefore;
      shadow.diffuseShare = verticesBefore == 1 ? firstVertexShare({l.wiX[k], l.wiY[k], l.wiZ[k]}) : path.firstDiffuseShare;
      shadow.path = i;
      shadow.light = l.light[k];
    }
    const Vec3 next{l.nextDx[k], l.nextDy[k], l.nextDz[k]};
    if (verticesBefore == 1) path.firstDiffuseShare = firstVertexShare(next);
    if (l.scattered[k] && continuePath(path, {l.weightR[k], l.weightG[k], l.weightB[k]}, l.scatterPdf[k], false,
                                       position, {{l.nextOx[k], l.nextOy[k], l.nextOz[k]}, next}, l.uRoulette[k]))
      w.next.push_back(i);
  }

  // Emission of the face the path's ray has met, towards the ray's origin, weighted against light
  // sampling.
  void gatherEmission(Path& path, const Hit& hit, Vec3 position) const {
    const Rgb le = emittedRadiance(scene_, hit.triangle, hit.b1, hit.b2, -path.ray.direction);
    if (le.isBlack()) return;
    const float lightPdf = path.lastDelta ? 0.0f
                                          : triangleLightPdf(scene_, lightChoice_, hit.triangle, path.ray.direction,
                                                             length(position - path.lastPosition));
    path.gather(path.gatheringVertices, path.beta * le * emissionWeight(path.lastDelta, path.lastPdf, lightPdf));
  }

  // The path goes on from `position` along `next`, its throughput scaled by the sample's weight:
  // false when the throughput is black or Russian roulette ends the path. `uRoulette`: the next
  // bounce's roulette number if drawn already (the lanes'), or kDrawLater.
  static constexpr float kDrawLater = -1.0f;
  bool continuePath(Path& path, Rgb weight, float pdf, bool delta, Vec3 position, const Ray& next,
                    float uRoulette = kDrawLater) const {
    path.beta *= weight;
    if (path.beta.isBlack()) return false;
    path.lastDelta = delta;
    path.lastPdf = pdf;
    path.lastPosition = position;
    path.ray = next;
    return survivesRoulette(path, uRoulette);
  }

  // Counts the bounce just taken; from the roulette depth on, ends the path with probability one
  // minus its throughput's largest component, scaled by its pixel's roulette scale where contribution
  // roulette has one, and scales the survivors up by as much.
  bool survivesRoulette(Path& path, float u) const {
    ++path.bounce;
    return path.bounce < opt_.rouletteDepth ||
           survivesRussianRoulette(path.beta, u != kDrawLater ? u : path.sampler.uniform(path.bounce, SampleUse::Roulette),
                                   roulette_.empty() ? Rgb(1.0f) : roulette_.at(path.pixel));
  }

  // A light chosen for the receiver by the tracer's light choice from u's first number, and a
  // sample of it from u (the first rescaled): one stratified pair spreads its points over all the
  // lights together. `light` is set to the light chosen.
  LightSample sampleLight(Vec3 receiver, Vec2 u, uint32_t& light) const {
    if (scene_.lights.empty()) return {};
    const LightChoice choice = chooseLight(scene_, lightChoice_, receiver, u.x, &u.x);
    light = choice.light;
    return sampleChosenLight(scene_, choice.light, choice.pmf, receiver, u);
  }

  // Weight of emission found by BSDF sampling, against light sampling of the same light.
  float emissionWeight(bool lastDelta, float bsdfPdf, float lightPdf) const {
    if (lastDelta) return 1.0f;
    switch (opt_.strategy) {
      case PathStrategy::Mis: return powerHeuristic(bsdfPdf, lightPdf);
      case PathStrategy::LightSampling: return 0.0f;
      case PathStrategy::BsdfSampling: return 1.0f;
    }
    return 1.0f;
  }

  // One light sample, weighted against BSDF sampling (lights that BSDF sampling cannot hit, point
  // and directional, always have weight 1): its shadow ray and what it brings if unoccluded. False
  // when the sample brings nothing whatever the shadow ray finds.
  bool sampleDirect(const SurfacePoint& sp, const SurfaceBsdf& bsdf, const Frame& frame, Vec3 woLocal, Vec2 uLightPoint,
                    ShadowQuery& shadow) const {
    const LightSample ls = sampleLight(sp.position, uLightPoint, shadow.light);
    const Vec3 wiLocal = frame.toLocal(ls.wi);
    const NextEventSample sample = weighLightSample(opt_.strategy, ls.pdf, ls.delta, ls.radiance, ls.wi, wiLocal,
                                                    frame.n, sp.geometricNormal, evalBsdfAndPdf(bsdf, woLocal, wiLocal),
                                                    has(bsdf.flags(), BsdfFlags::Transmission));
    if (!sample.queued) return false;
    shadow.ray = shadowRay(sp.position, sp.geometricNormal, ls);
    shadow.contribution = sample.contribution;
    if (opt_.paths) shadow.diffuseShare = diffuseShare(bsdf, woLocal, wiLocal);
    return true;
  }

  const Scene& scene_;
  const Visibility& vis_;
  const PathTraceOptions& opt_;
  const PinholeCamera camera_;
  const PixelFilter filter_{{opt_.common.pixelFilter, opt_.common.filterRadius}};
  std::vector<LaneLight> laneLights_;  // by light index
  std::vector<LaneKind> laneKinds_;    // by material index
  // A hit's triangle and vertex records are prefetched when the scene's arrays outgrow a core's
  // second-level cache (1 MiB here): Sponza's shading reads then wait on memory (its fetch stage
  // is 1.5x slower without), while the Cornell box's stay cached and prefetching costs it 1%.
  const bool prefetchSceneData_ = sceneArrayBytes(scene_) > (size_t(1) << 20);
  RouletteScales roulette_;  // empty: throughput roulette
  Distribution1D lightChoice_;  // over the scene's lights: by power, or learnt from the pilot
  bool learningLightChoice_ = false;
  const uint64_t imageWidth_ = uint64_t(scene_.camera.width);
};

// The samples of the tile's pixels from each pixel's next (sampleBegin plus the samples the film
// has taken there) to the pass's end, in order (row, pixel, sample), with the rest of their runs;
// then the film takes the pass's. With streams, sample s of a pixel is sample s / 2 of its stream s % 2.
uint64_t PathTracer::renderTile(const PixelRect& tile, const PassSamples& pass, StreamSums* streams, Wave& wave,
                                Counters& counters, Film& film) const {
  uint64_t taken = 0;
  const uint64_t width = uint64_t(scene_.camera.width);
  auto pixelOf = [&](int x, int y) { return uint64_t(y) * width + uint64_t(x); };
  CameraLanes& start = *wave.camera;
  start.count = 0;
  wave.run.resize(kWaveSize), wave.ghost.resize(kWaveSize);
  uint32_t runs = 0;
  // The queued samples' paths, traced; then the film takes the pass's samples.
  auto traceQueued = [&] {
    // The camera rays, all lanes at once, or one path at a time.
    if (opt_.laneShading)
      startCameraPaths(start, 0, start.count, opt_.sampler, opt_.common.seed, camera_, filter_, opt_.pixelCentres);
    else
      for (uint32_t k = 0; k < start.count; ++k)
        startCameraPaths(start, k, k + 1, opt_.sampler, opt_.common.seed, camera_, filter_, opt_.pixelCentres);
    wave.paths.resize(start.count);
    if (opt_.paths) wave.parts.assign(start.count, PathParts{});
    for (uint32_t k = 0; k < start.count; ++k) {
      Path& path = wave.paths[k];
      path = Path{};
      path.pixel = start.pixel[k];
      path.sampler = start.sampler[k];
      path.ray = {camera_.eye(), {start.dirX[k], start.dirY[k], start.dirZ[k]}};
      path.lastPosition = path.ray.origin;
      if (opt_.paths) path.parts = &wave.parts[k];
    }
    traceWave(wave, counters);
    for (uint32_t k = 0; k < start.count; ++k) {
      if (wave.ghost[k]) continue;
      ++taken;
      Path& path = wave.paths[k];
      PathResult& p = path.result;
      if (start.filterWeight[k] != 1.0f) {
        // A negative lobe of the pixel filter (Mitchell's): the sample's light counts with its weight.
        const float w = start.filterWeight[k];
        p.direct = p.direct * w, p.indirect = p.indirect * w;
        if (path.parts)
          for (Rgb& part : path.parts->light) part = part * w;
      }
      if (!p.valid || !summable(p.direct) || !summable(p.indirect) || !summable(p.direct + p.indirect) ||
          (path.parts && !std::all_of(path.parts->light.begin(), path.parts->light.end(), [](Rgb part) { return summable(part); }))) {
        ++counters.invalidSamples;
        continue;
      }
      film.addSample(path.pixel, p.direct, p.indirect, p.albedo, p.normal, p.depth, path.parts ? *path.parts : PathParts{});
      if (streams) streams->add(path.pixel, start.streamPixel[k] != path.pixel, p.direct + p.indirect);
    }
    start.count = 0;
    runs = 0;
  };
  // Each pixel's samples from its next (sampleBegin plus the samples the film has taken there) to
  // the pass's end, in order, in whole runs (with --target-error's two streams, one sample a run).
  // A stop request ends the tile between two pixels: the pixels queued are traced and counted, the
  // rest keep the samples they had (a tile of slow rays would otherwise hold a stop for seconds).
  const uint64_t tileWidth = uint64_t(tile.x1 - tile.x0), tilePixels = tileWidth * uint64_t(tile.y1 - tile.y0);
  uint64_t queuedPixels = 0;  // in row order
  for (; queuedPixels < tilePixels && !stopRequested(); ++queuedPixels) {
    const int x = tile.x0 + int(queuedPixels % tileWidth), y = tile.y0 + int(queuedPixels / tileWidth);
    const uint64_t pixel = pixelOf(x, y);
    const int first = pass.sampleBegin + int(film.taken(pixel)), end = pass.end(pixel);
    for (int sample = first; sample < end;) {
      const int begin = streams ? sample : runBegin(sample), finish = streams ? sample + 1 : runEnd(sample);
      if (start.count + uint32_t(finish - begin) > uint32_t(kWaveSize)) traceQueued();
      for (int s = begin; s < finish; ++s) {
        const uint32_t k = start.count++;
        start.pixel[k] = pixel;
        start.streamPixel[k] = streams && s % 2 == 1 ? pixel | kSecondStream : pixel;
        start.sample[k] = uint64_t(streams ? s / 2 : s);
        start.x[k] = float(x), start.y[k] = float(y);
        wave.run[k] = runs;
        wave.ghost[k] = s < first || s >= end;
      }
      ++runs;
      sample = finish;
    }
  }
  if (start.count > 0) traceQueued();
  for (uint64_t i = 0; i < queuedPixels; ++i) {
    const uint64_t pixel = pixelOf(tile.x0 + int(i % tileWidth), tile.y0 + int(i / tileWidth));
    film.setTaken(pixel, std::max(film.taken(pixel), uint32_t(pass.end(pixel) - pass.sampleBegin)));
  }
  return taken;
}

// The end of the next pass of samples, counted from the part's first. With a time budget, the
// first pass takes one sample per pixel and each later pass as many as the remaining time allows at
// the measured rate (no more: the returned end is done). Otherwise passes double (1, 2, 4, ...
// samples) up to 64 samples each, so that checkpoints come often (a stop request ends a tile
// between two of its pixels). A pass ends at pilotEnd, where
// contribution roulette's pilot is read from the film (0: none). The image depends only on the
// samples taken, never on how they were split into passes.
int nextPassEnd(const PathTraceOptions& options, int first, int samples, int done, double elapsed, int pilotEnd) {
  int end = [&] {
    if (options.timeBudget > 0) {
      if (done == 0) return 1;
      const double affordable = (options.timeBudget - elapsed) / (elapsed / done);
      if (affordable < 1) return done;
      return int(std::min<double>(samples, done + std::min<double>(affordable, 2.0 * done + 1)));
    }
    return std::min(samples, done + std::clamp(done, 1, 64));
  }();
  // Passes end where runs do (counted from sample 0, first the part's first sample), so that no
  // run is traced twice: up to the run's end, or with a time budget down to its beginning where
  // the pass keeps a sample.
  if (end > done && end < samples) {
    if (options.timeBudget <= 0) end = std::min(samples, runEnd(first + end - 1) - first);
    else if (runBegin(first + end) - first > done) end = runBegin(first + end) - first;
  }
  return done < pilotEnd ? std::min(end, pilotEnd) : end;
}

// A path-traced render: passes of samples over the image's tiles (RenderDriver), to the part's spp,
// a time budget or an error target, with contribution roulette's pilot before its first pass.
class PathTracedRender {
 public:
  PathTracedRender(const Scene& scene, const Visibility& visibility, const PathTraceOptions& options,
                   RenderDriver& driver)
      : scene_(scene), options_(options), driver_(driver), tracer_(scene, visibility, options) {
    // Every pixel is owned by one tile, and its samples are added in sample order.
    film_ = &driver.startFilm(Film::Sums::PerSample, {options.common.layers, false, options.variance, options.paths});
    resumedSamples_ = driver.samplesTaken();
    driver.expectSamples(double(part().region.pixelCount()) * part().samples());
    if (options.targetError > 0) streams_ = std::make_unique<StreamSums>(part().region.pixelCount());
    // Contribution roulette (contribution_roulette.h) from sample kPilotSamples on, the samples
    // before it taken with throughput roulette. Its pilot is the image's own first samples where the
    // render starts there and covers the whole image; a crop, a later sample range or a resumed
    // render traces the pilot's pixels first, on a film of its own.
    contribution_ = options.roulette == RouletteKind::Contribution && part().sampleEnd > int(kPilotSamples);
    pilotInFilm_ = part().region == PixelRect{0, 0, scene.camera.width, scene.camera.height} &&
                   part().sampleBegin == 0 && resumedSamples_ == 0;
    // The light choice is learnt from the pilot's light samples too (LightMoments).
    learnLightChoice_ = contribution_ && options.lightChoice == LightChoiceKind::Learned && learnsLightChoice(scene);
    tracer_.learnLightChoice(learnLightChoice_);
  }

  RenderOutput render() {
    beginStage("trace_paths");
    clock_ = Stopwatch();
    if (contribution_ && !pilotInFilm_) tracePilot();
    RenderOutput out;
    if (options_.targetError > 0) out.measured = renderToErrorTarget();
    else renderPasses();
    driver_.finish(out);
    // A render that its time budget or error target ended is whole; one that a stop request ended is not.
    if (options_.timeBudget > 0 || options_.targetError > 0) out.complete = !driver_.stopped();
    Counters total;
    for (const Counters& c : counters_) {
      total.rays += c.rays;
      total.laneShadedHits += c.laneShadedHits;
      total.invalidSamples += c.invalidSamples;
    }
    out.stats.addStage("trace_paths", clock_.seconds());
    out.stats.addCounter("rays", total.rays);
    out.stats.addCounter("lane_shaded_hits", total.laneShadedHits);
    out.stats.addCounter("samples", driver_.samplesTaken() - resumedSamples_);
    out.stats.addCounter("invalid_samples", total.invalidSamples);
    return out;
  }

 private:
  const RenderPart& part() const { return driver_.part(); }

  // Every tile's samples of the pass on `target` (the image's film, or the pilot's over `area`).
  void passOn(const PassSamples& pass, Film& target, const PixelRect& area) {
    const bool image = &target == film_;
    driver_.renderTiles(area, options_.tileSize, [&](const PixelRect& tile) {
      return tracer_.renderTile(tile, pass, image ? streams_.get() : nullptr, waves_.local(), counters_.local(), target);
    }, image);
  }

  void pass(const PassSamples& samples) {
    passOn(samples, *film_, part().region);
    driver_.passDone();
  }

  // The waves' light moments, summed exactly and cleared, as the light choice they teach.
  Distribution1D learntChoice() {
    LightMoments moments;
    for (PathTracer::Wave& w : waves_) moments.add(std::exchange(w.lightMoments, {}));
    tracer_.learnLightChoice(false);
    return learnLightChoice_ ? learntLightChoice(scene_, moments) : scene_.lightDistribution;
  }

  // The pilot's pixels on a film of their own. No layers: per-sample sums keep each sample's total,
  // so R, G and B are the image film's, and a whole-image film with the --paths and --variance
  // layers would take some thirty times the memory.
  void tracePilot() {
    const int width = scene_.camera.width, height = scene_.camera.height;
    Film pilot(width, height, Film::Sums::PerSample, {});
    passOn({0, 0, pilotPixels(width, height, part().region)}, pilot, {0, 0, width, height});
    tracedScales_ = RouletteScales(pilot.image(), part().region);
    tracedChoice_ = learntChoice();
  }

  void startContributionRoulette() {
    tracer_.useRoulette(pilotInFilm_ ? RouletteScales(film_->image(), part().region) : std::move(tracedScales_));
    tracer_.useLightChoice(pilotInFilm_ ? learntChoice() : std::move(tracedChoice_));
  }

  // Passes of doubling samples (or as the time budget allows: nextPassEnd) to the part's spp. A
  // resumed render goes on from the fewest samples any pixel has (pixels with more skip them).
  void renderPasses() {
    int done = int(*std::min_element(film_->samplesTaken().begin(), film_->samplesTaken().end()));
    // Where contribution roulette starts, counted from the part's first sample.
    const int pilotEnd = contribution_ ? std::max(0, int(kPilotSamples) - part().sampleBegin) : 0;
    if (contribution_ && done >= pilotEnd && !driver_.stopped()) startContributionRoulette();
    for (int passEnd; done < part().samples() && !driver_.stopped() &&
                      (passEnd = nextPassEnd(options_, part().sampleBegin, part().samples(), done, clock_.seconds(),
                                             pilotEnd)) > done;
         done = passEnd) {
      pass({part().sampleBegin, part().sampleBegin + passEnd, {}});
      if (contribution_ && passEnd == pilotEnd && !driver_.stopped()) startContributionRoulette();
    }
  }

  // The first pass: kFirstPass samples everywhere; then passes planned from the pixels' estimated
  // errors, until the image's is at most the target (or the time budget or --spp stops it).
  std::vector<std::pair<std::string, double>> renderToErrorTarget() {
    constexpr uint32_t kFirstPass = 8;
    static_assert(kFirstPass == kPilotSamples, "contribution roulette's pilot is the first pass");
    const PixelRect& region = part().region;
    std::vector<uint32_t> ends(region.pixelCount(), kFirstPass);
    driver_.expectSamples(double(region.pixelCount()) * kFirstPass);
    double estimate = 0, rate = 1;
    uint64_t taken = 0;
    int passes = 0;
    for (;;) {
      pass({0, 0, ends});
      ++passes;
      if (driver_.stopped()) break;
      if (contribution_ && passes == 1) startContributionRoulette();
      const std::vector<float> pixelError = streams_->pixelRelMse();
      const uint64_t takenBefore = std::exchange(taken, driver_.samplesTaken());
      const double estimateBefore = std::exchange(estimate, meanRelMse(pixelError));
      if (estimate <= options_.targetError) break;
      if (passes > 1) rate = errorRate(estimateBefore, takenBefore, estimate, taken);
      uint64_t allowed = taken;  // a pass at most doubles the samples: its plan comes from theirs
      bool budgetLimits = false;
      if (options_.timeBudget > 0) {
        const double elapsed = clock_.seconds();
        const double affordable = std::max(0.0, (options_.timeBudget - elapsed) / (elapsed / double(taken)));
        budgetLimits = affordable < double(allowed);
        if (budgetLimits) allowed = uint64_t(affordable);
      }
      // Aimed a little below the target, so that noise in the prediction seldom costs another pass.
      const PassPlan plan = planNextPass(pixelError, film_->samplesTaken(), region.width(), region.height(),
                                         0.95 * options_.targetError, rate, allowed, uint32_t(part().samples()));
      if (plan.total == taken) {
        std::cerr << "lucent: warning: --target-error " << options_.targetError << " not reached: the estimated relMSE is "
                  << estimate << " (";
        if (budgetLimits) std::cerr << "the time budget of " << options_.timeBudget << " s ended the render)\n";
        else std::cerr << "the pixels that need more samples have --spp " << part().samples() << ", the most a pixel takes)\n";
        break;
      }
      ends = plan.samples;
      driver_.expectSamples(double(std::max(plan.totalForAim, plan.total)));
    }
    return {{"estimated_relmse", estimate}, {"samples_spent", double(driver_.samplesTaken())}, {"passes", double(passes)}};
  }

  const Scene& scene_;
  const PathTraceOptions& options_;
  RenderDriver& driver_;
  PathTracer tracer_;
  Film* film_ = nullptr;
  uint64_t resumedSamples_ = 0;
  std::unique_ptr<StreamSums> streams_;
  tbb::enumerable_thread_specific<Counters> counters_;
  tbb::enumerable_thread_specific<PathTracer::Wave> waves_;
  bool contribution_ = false, pilotInFilm_ = false, learnLightChoice_ = false;
  RouletteScales tracedScales_;
  Distribution1D tracedChoice_;
  Stopwatch clock_;
};

}  // namespace

RenderOutput renderPathTraced(const Scene& scene, const Visibility& visibility, const PathTraceOptions& options,
                              const RenderControl& control) {
  RenderDriver driver(pathTraceOptionTable(), options, control, scene, visibility);
  const bool targeted = options.targetError > 0;
  if ((options.timeBudget > 0 || targeted) && (control.isPart() || control.resume || control.checkpointSeconds > 0)) {
    const char* flag = targeted ? "--target-error" : "--time-budget";
    throw OptionError(targeted ? "target_error" : "time_budget",
                      std::string(flag) + ": a render " + (targeted ? "to an error target" : "with a time budget") +
                          " takes as many samples as it needs, so it cannot be split (--crop, --samples), "
                          "checkpointed or resumed");
  }
  return PathTracedRender(scene, visibility, options, driver).render();
}

}  // namespace lucent
