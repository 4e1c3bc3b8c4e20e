#include "lucent/pipeline/shading_points.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <memory>

#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/core/sampling.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/surface.h"
#include "lucent/core/stop.h"

namespace lucent {
namespace {

struct Branch {
  Ray ray;
  Rgb weight;
  int depth = 0;                // specular bounces so far
  uint32_t medium = kNoMedium;  // the attenuating medium the ray travels in (the camera's: none)
};

// Depth-first over a camera sample's branches: each pop pushes at most two, and the depth is
// bounded by maxSpecularDepth (at most 64), so the stack never holds more than 66.
constexpr int kMaxBranchStack = 80;
// A stack slot, left uninitialized: clearing 80 branches (3.8 KB) per camera sample took 10% of
// RING's eye-ray stage (purcell, 512 x 384).
union BranchSlot {
  BranchSlot() {}
  Branch branch;
};

struct SampleResult {
  Rgb emitted;
  bool valid = true;
};

// Follows one camera ray, whose closest hit is given, through specular bounces; appends the shading
// points it reaches. Specular are the surfaces passed as specular (SurfaceBsdf::passedAsSpecular):
// mirrors and glass, and the smooth surfaces that transmit, followed by a sample of their lobe.
// What other light reaches such a surface the chain's next hits bring; the point, spot and
// directional lights, which no ray meets, are taken at it by a shadow ray each. Inside a
// KHR_materials_volume medium the weight loses what the medium absorbs along each segment.
SampleResult traceCameraSample(const Scene& scene, const Visibility& vis, const DirectLights& lights,
                               const EyePathSettings& settings, Ray ray, float filterWeight, const Hit& cameraHit,
                               uint32_t pixel, uint32_t sample, Rng& rng, FirstHit* firstHit,
                               std::vector<ShadingPoint>& points, uint64_t& rays) {
  SampleResult out;
  BranchSlot stack[kMaxBranchStack];
  int top = 0;
  stack[top++].branch = {ray, Rgb(filterWeight), 0, kNoMedium};
  uint32_t branch = 0;
  bool fromCamera = true;
  while (top > 0) {
    Branch b = stack[--top].branch;
    if (!isFinite(b.ray.origin) || !isFinite(b.ray.direction) || !isFinite(b.weight)) {
      out.valid = false;
      return out;
    }
    ++rays;
    const Hit hit = fromCamera ? cameraHit : vis.intersect(b.ray);
    fromCamera = false;
    if (b.medium != kNoMedium) b.weight *= transmittanceIn(scene, b.medium, hit.found() ? hit.t : kInf);
    if (!hit.found()) {
      if (scene.environment.present) out.emitted += b.weight * environmentRadiance(scene.environment, b.ray.direction);
      continue;
    }
    const ChainVertex v = chainVertexAt(scene, surfaceAt(scene, hit.triangle, hit.b1, hit.b2), b.ray.direction);
    const SurfacePoint& sp = v.sp;
    const SurfaceBsdf& bsdf = v.bsdf;
    if (!scene.materials[sp.materialId].ke.isBlack())
      out.emitted += b.weight * emittedRadiance(scene, hit.triangle, hit.b1, hit.b2, v.wo);
    if (firstHit) {
      firstHit->albedo = layerAlbedo(bsdf);
      firstHit->normal = sp.shadingNormal;
      firstHit->depth = hit.t;
      firstHit = nullptr;
    }

    if (!bsdf.passedAsSpecular()) {
      if (!reflectanceBound(bsdf).isBlack())
        points.push_back(
            {sp.position, sp.geometricNormal, v.frame.n, v.wo, b.weight, bsdf, pixel, sample, branch++, sp.triangle, b.medium});
      continue;
    }
    const bool smoothTransmitter = !bsdf.isDelta();
    if (smoothTransmitter && !lights.delta.empty()) {
      const ShadingPoint at{sp.position, sp.geometricNormal, v.frame.n, v.wo, b.weight, bsdf, pixel, sample, 0, sp.triangle,
                            b.medium};
      out.emitted += b.weight * directLight(scene, lights, vis, at, 0, 0, rays);
    }
    if (b.depth >= settings.maxSpecularDepth) continue;
    const Vec3 woLocal = v.woLocal;
    // Pushes the continuation along s with weight w, unless it leaves on the wrong side of the
    // real surface (shading-normal leaks), as the path tracer does.
    auto push = [&](const BsdfSample& s, Rgb w) {
      const std::optional<Ray> next = followLobe(v, s);
      if (!next) return;
      const Rgb weight = b.weight * w;
      if (weight.isBlack()) return;
      stack[top++].branch = {*next, weight, b.depth + 1, mediumTowards(scene, sp, bsdf, next->direction, b.medium)};
    };
    if (!smoothTransmitter && has(bsdf.flags(), BsdfFlags::Transmission) && b.weight.maxComponent() >= kSplitWeight) {
      // Both lobes, each weighted by the probability with which sampleBsdf would pick it (F, 1 - F):
      // u = 0 picks reflection unless F = 0, u just below 1 refraction unless F = 1 (total internal
      // reflection).
      const BsdfSample r = sampleBsdf(bsdf, woLocal, 0.0f, {});
      const BsdfSample t = sampleBsdf(bsdf, woLocal, 0x1.fffffep-1f, {});
      if (r.valid && r.wi.z * woLocal.z > 0) push(r, r.weight * r.pdf);
      if (t.valid && t.wi.z * woLocal.z < 0) push(t, t.weight * t.pdf);
    } else {
      // One lobe, chosen with its probability (sampleBsdf's weight for delta lobes has it divided out);
      // a smooth transmitter's direction in its lobe.
      const float uLobe = rng.uniform();
      const BsdfSample s = sampleBsdf(bsdf, woLocal, uLobe, smoothTransmitter ? rng.uniform2() : Vec2{});
      push(s, s.weight);
    }
  }
  return out;
}

// A camera sample waiting for its packet: its ray, its pixel filter's weight and its generator
// after the pixel offset.
struct CameraSample {
  Ray ray;
  float filterWeight;
  Rng rng;
  uint32_t pixel, sample;
};

}  // namespace

EyePaths traceEyePaths(const Scene& scene, const Visibility& vis, const EyePathSettings& settings) {
  const int width = scene.camera.width;
  const PixelRect region = settings.region.empty() ? PixelRect{0, 0, width, scene.camera.height} : settings.region;
  const int sampleBegin = settings.sampleBegin, sampleEnd = settings.sampleEnd > 0 ? settings.sampleEnd : settings.spp;
  const int samples = sampleEnd - sampleBegin;
  // Tiles of the image's fixed grid, cut to the region: a crop's packets are the whole image's
  // where the crop's edges are on the grid.
  const int tile = settings.tileSize;
  const int tileX0 = region.x0 / tile, tileY0 = region.y0 / tile;
  const int tilesX = (region.x1 + tile - 1) / tile - tileX0, tilesY = (region.y1 + tile - 1) / tile - tileY0;
  const int tiles = tilesX * tilesY;
  const PinholeCamera camera(scene.camera);
  const PixelFilter filter(settings.filter);
  const uint64_t seed = streamSeed(settings.seed, RenderStream::Eye);
  const DirectLights lights(scene);

  // Most camera samples end in one shading point, held per tile, then in the band's array, with the
  // radiance the method computes at it (direct and indirect).
  requireMemory(region.pixelCount() * (sizeof(EyePixel) + (settings.layers ? sizeof(EyeFeatures) : 0) +
                                       uint64_t(samples) * (2 * sizeof(ShadingPoint) + 2 * sizeof(Rgb))),
                "the camera paths' shading points", "lower --spp or --resolution, or render in parts (--crop)");
  EyePaths out;
  out.region = region;
  out.pixels.resize(size_t(region.pixelCount()));  // constructed by the tiles
  if (settings.layers) out.features.resize(size_t(region.pixelCount()));
  std::vector<std::vector<ShadingPoint>> tilePoints(tiles);
  std::vector<uint64_t> tileRays(tiles, 0), tileInvalid(tiles, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& r) {
    stopPoint();
    flushDenormals();
    for (int t = r.begin(); t != r.end(); ++t) {
      const int x0 = std::max(region.x0, (tileX0 + t % tilesX) * tile), y0 = std::max(region.y0, (tileY0 + t / tilesX) * tile);
      const int x1 = std::min(region.x1, (tileX0 + t % tilesX + 1) * tile), y1 = std::min(region.y1, (tileY0 + t / tilesX + 1) * tile);
      auto pixelIndex = [&](int x, int y) { return size_t(y - region.y0) * size_t(region.width()) + size_t(x - region.x0); };
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          ::new (&out.pixels[pixelIndex(x, y)]) EyePixel{};
          if (settings.layers) ::new (&out.features[pixelIndex(x, y)]) EyeFeatures{};
        }
      std::vector<ShadingPoint>& points = tilePoints[t];
      points.reserve(size_t(x1 - x0) * size_t(y1 - y0) * size_t(samples));  // most samples end in one point
      // The tile's camera samples in order (row, pixel, sample), their rays traced sixteen at a
      // time as a packet (coherent rays: several times Embree's single-ray speed). A packet never
      // spans two rows, so its rays depend only on the row and the fixed 16-pixel tile columns:
      // neither the threads nor the bands of rows change them.
      CameraSample batch[kWidestPacket];
      int queued = 0;
      auto traceBatch = [&] {
        Hit hits[kWidestPacket];
        intersectPacket<kWidestPacket>(vis, queued, [&](int j) -> const Ray& { return batch[j].ray; }, hits,
                                       RayKind::Camera);
        for (int j = 0; j < queued; ++j) {
          CameraSample& cs = batch[j];
          const Hit& hit = hits[j];
          const size_t index = pixelIndex(int(cs.pixel % uint32_t(width)), int(cs.pixel / uint32_t(width)));
          const size_t before = points.size();
          FirstHit first;
          const SampleResult res = traceCameraSample(scene, vis, lights, settings, cs.ray, cs.filterWeight, hit, cs.pixel,
                                                     cs.sample, cs.rng, settings.layers ? &first : nullptr, points,
                                                     tileRays[t]);
          if (!res.valid || !summable(res.emitted)) {
            points.resize(before);
            ++tileInvalid[t];
            continue;
          }
          out.pixels[index].addSample(res.emitted);
          if (settings.layers) out.features[index].add(first);
        }
        queued = 0;
      };
      const bool masked = !settings.pixelMask.empty();
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const uint32_t pixel = uint32_t(y) * uint32_t(width) + uint32_t(x);
          const bool traced = !masked || settings.pixelMask[pixelIndex(x, y)];
          for (int s = sampleBegin; traced && s < sampleEnd; ++s) {
            CameraSample& cs = batch[queued];
            cs.rng = Rng(seed, pixel, uint64_t(s));
            // One box-filtered sample is the pixel's centre; others are stratified over the
            // pixel and drawn through its filter.
            const bool centre = settings.spp == 1 && filter.isBox();
            cs.filterWeight = 1;
            const Vec2 offset = centre ? Vec2{0.5f, 0.5f}
                                       : filter.position(stratifiedSample2D(uint32_t(s), uint32_t(settings.spp), cs.rng.uniform2()),
                                                         cs.filterWeight);
            cs.ray = camera.generate(float(x) + offset.x, float(y) + offset.y);
            cs.pixel = pixel, cs.sample = uint32_t(s);
            if (++queued == kWidestPacket) traceBatch();
          }
          if (x + 1 == x1 && queued > 0) traceBatch();
        }
    }
  });
  // The tiles' points joined in tile order, copied in parallel.
  std::vector<size_t> first(tiles + 1, 0);
  for (int t = 0; t < tiles; ++t) {
    first[t + 1] = first[t] + tilePoints[t].size();
    out.rays += tileRays[t];
    out.invalid += tileInvalid[t];
  }
  out.points.resize(first[tiles]);
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& r) {
    stopPoint();
    for (int t = r.begin(); t != r.end(); ++t) {
      std::uninitialized_copy(tilePoints[t].begin(), tilePoints[t].end(), out.points.begin() + ptrdiff_t(first[t]));
      std::vector<ShadingPoint>().swap(tilePoints[t]);
    }
  });
  return out;
}

std::vector<uint32_t> tracePixelSurfaces(const Scene& scene, const Visibility& vis, const PixelRect& region) {
  const PinholeCamera camera(scene.camera);
  const bool environmentEmits = scene.environment.present;
  std::vector<uint32_t> codes(size_t(region.pixelCount()));
  tbb::parallel_for(tbb::blocked_range<int>(region.y0, region.y1), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y)
      for (int x = region.x0; x < region.x1; ++x) {
        const Ray ray = camera.generate(float(x) + 0.5f, float(y) + 0.5f);
        const Hit hit = vis.intersect(ray, RayKind::Camera);
        uint32_t code = PixelSurface::code(-1, environmentEmits);
        if (hit.found()) {
          const bool emits = !emittedRadiance(scene, hit.triangle, hit.b1, hit.b2, -ray.direction).isBlack();
          code = PixelSurface::code(int(scene.materialIds[hit.triangle]), emits);
        }
        codes[size_t(y - region.y0) * size_t(region.width()) + size_t(x - region.x0)] = code;
      }
  });
  return codes;
}

}  // namespace lucent
