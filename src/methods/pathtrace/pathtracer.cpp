#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/surface.h"

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
};

class PathTracer {
 public:
  PathTracer(const Scene& scene, const Visibility& vis, const PathTraceOptions& opt)
      : scene_(scene), vis_(vis), opt_(opt) {}

  PathResult trace(Ray ray, Rng& rng, Counters& counters) const {
    PathResult out;
    Rgb beta(1.0f);
    bool lastDelta = true;  // the camera ray counts as specular: emission seen directly is not MIS'ed
    float lastPdf = 0;
    Vec3 lastPosition = ray.origin;
    int gatheringVertices = 0;  // non-specular vertices the path has scattered from so far
    // Light arriving at the vertex the path came from is direct if that vertex was the first
    // non-specular one.
    auto gather = [&](int verticesBefore, Rgb contribution) {
      (verticesBefore <= 1 ? out.direct : out.indirect) += contribution;
    };

    for (int bounce = 0;; ++bounce) {
      if (!isFinite(ray.origin) || !isFinite(ray.direction)) {
        out.valid = false;
        return out;
      }
      ++counters.rays;
      const Hit hit = vis_.intersect(ray);
      if (!hit.found()) {
        if (scene_.environment.present) {
          const Rgb le = environmentRadiance(scene_.environment, ray.direction);
          gather(gatheringVertices, beta * le * emissionWeight(lastDelta, lastPdf, environmentLightPdf(scene_, ray.direction)));
        }
        break;
      }
      const SurfacePoint sp = surfaceAt(scene_, hit.triangle, hit.b1, hit.b2);
      const Material& material = scene_.materials[sp.materialId];
      const Vec3 wo = -ray.direction;
      const bool frontFace = dot(wo, sp.geometricNormal) > 0;

      if (!material.ke.isBlack() && frontFace) {
        const float lightPdf =
            lastDelta ? 0.0f : triangleLightPdf(scene_, hit.triangle, ray.direction, length(sp.position - lastPosition));
        gather(gatheringVertices, beta * material.ke * emissionWeight(lastDelta, lastPdf, lightPdf));
      }
      const SurfaceBsdf bsdf = bsdfAt(scene_, sp);
      if (bounce == 0) {
        out.albedo = bsdf.type == MaterialType::Diffuse || bsdf.type == MaterialType::Phong ? bsdf.kd + bsdf.ks
                     : bsdf.type == MaterialType::Mirror ? bsdf.ks : Rgb(1.0f);
        out.normal = sp.shadingNormal;
        out.depth = hit.t;
      }
      if (bounce + 1 > opt_.maxDepth) break;

      // Glass keeps the winding orientation (inside/outside); other materials are two-sided. Where
      // the shading normal puts the viewer on the other side than the geometric normal does (at
      // silhouettes of smooth meshes), the geometric normal is used.
      Vec3 n = dot(wo, sp.shadingNormal) * dot(wo, sp.geometricNormal) > 0 ? sp.shadingNormal : sp.geometricNormal;
      if (bsdf.type != MaterialType::Glass && !frontFace) n = -n;
      const Frame frame(n);
      const Vec3 woLocal = frame.toLocal(wo);

      if (!bsdf.isDelta()) {
        gather(gatheringVertices + 1, beta * estimateDirect(sp, bsdf, frame, woLocal, rng, counters));
        ++gatheringVertices;
      }

      const float uLobe = rng.uniform();
      const BsdfSample bs = sampleBsdf(bsdf, woLocal, uLobe, rng.uniform2());
      if (!bs.valid) break;
      const Vec3 wi = frame.toWorld(bs.wi);
      // Reject directions on the wrong side of the real surface (shading-normal light leaks).
      const bool transmits = bs.wi.z * woLocal.z < 0;
      if ((dot(wi, sp.geometricNormal) * dot(wo, sp.geometricNormal) < 0) != transmits) break;
      beta *= bs.weight;
      if (beta.isBlack()) break;
      lastDelta = bs.delta;
      lastPdf = bs.pdf;
      lastPosition = sp.position;
      ray = {offsetOrigin(sp.position, sp.geometricNormal, wi), wi};

      if (bounce + 1 >= opt_.rouletteDepth) {
        const float survive = std::min(1.0f, beta.maxComponent());
        if (rng.uniform() >= survive) break;
        beta *= 1.0f / survive;
      }
    }
    return out;
  }

 private:
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
  // and directional, always have weight 1).
  Rgb estimateDirect(const SurfacePoint& sp, const SurfaceBsdf& bsdf, const Frame& frame, Vec3 woLocal, Rng& rng,
                     Counters& counters) const {
    const float uLight = rng.uniform();
    const LightSample ls = sampleLight(scene_, sp.position, uLight, rng.uniform2());
    if (!(ls.pdf > 0) || ls.radiance.isBlack()) return {};
    if (opt_.strategy == PathStrategy::BsdfSampling && !ls.delta) return {};
    const Vec3 wiLocal = frame.toLocal(ls.wi);
    if (wiLocal.z <= 0 || dot(ls.wi, sp.geometricNormal) * dot(frame.n, sp.geometricNormal) <= 0) return {};
    const Rgb f = evalBsdf(bsdf, woLocal, wiLocal);
    if (f.isBlack()) return {};
    ++counters.rays;
    if (vis_.occluded(shadowRay(sp.position, sp.geometricNormal, ls))) return {};
    const float w = ls.delta || opt_.strategy == PathStrategy::LightSampling
                        ? 1.0f
                        : powerHeuristic(ls.pdf, bsdfPdf(bsdf, woLocal, wiLocal));
    return f * ls.radiance * (wiLocal.z * w / ls.pdf);
  }

  const Scene& scene_;
  const Visibility& vis_;
  const PathTraceOptions& opt_;
};

std::vector<std::string> channelNames(bool layers) {
  std::vector<std::string> c = {"R", "G", "B"};
  if (layers)
    for (const char* name : {"albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "depth.Z",
                             "direct.R", "direct.G", "direct.B", "indirect.R", "indirect.G", "indirect.B"})
      c.push_back(name);
  return c;
}

}  // namespace

RenderOutput renderPathTraced(const Scene& scene, const Visibility& visibility, const PathTraceOptions& options,
                              const ProgressFn& progress) {
  if (options.spp < 1) throw std::invalid_argument("spp must be at least 1");
  if (options.maxDepth < 0) throw std::invalid_argument("max depth must not be negative");
  if (options.tileSize < 1) throw std::invalid_argument("tile size must be at least 1");
  const int width = scene.camera.width, height = scene.camera.height;
  const auto channels = channelNames(options.layers);
  const size_t nc = channels.size();
  // Sums in double, one slot per pixel and channel; every pixel is owned by one tile, and samples
  // are added in sample order, so the image does not depend on threads or tiles.
  std::vector<double> sums(size_t(width) * height * nc, 0.0);
  std::vector<uint32_t> invalid(size_t(width) * height, 0);

  const PathTracer tracer(scene, visibility, options);
  const PinholeCamera camera(scene.camera);
  const int tilesX = (width + options.tileSize - 1) / options.tileSize;
  const int tilesY = (height + options.tileSize - 1) / options.tileSize;
  tbb::enumerable_thread_specific<Counters> counters;
  std::atomic<uint64_t> pixelSamplesDone{0};
  const double totalPixelSamples = double(width) * height * options.spp;

  Stopwatch clock;
  int sppDone = 0;
  while (sppDone < options.spp) {
    // Without a time budget everything is one pass. With one, the first pass takes one sample per
    // pixel and each later pass as many as the remaining time allows at the measured rate. The
    // image depends only on the number of samples taken, never on how they were split into passes.
    int passEnd = options.spp;
    if (options.timeBudget > 0) {
      const double elapsed = clock.seconds(), perSample = sppDone > 0 ? elapsed / sppDone : 0;
      const double affordable = sppDone > 0 ? (options.timeBudget - elapsed) / perSample : 1;
      if (affordable < 1) break;
      passEnd = int(std::min<double>(options.spp, sppDone + std::min<double>(affordable, 2.0 * sppDone + 1)));
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, tilesX * tilesY, 1), [&](const tbb::blocked_range<int>& r) {
      flushDenormals();  // every thread computes alike, whoever created it
      Counters& local = counters.local();
      for (int tile = r.begin(); tile != r.end(); ++tile) {
        const int x0 = (tile % tilesX) * options.tileSize, y0 = (tile / tilesX) * options.tileSize;
        const int x1 = std::min(width, x0 + options.tileSize), y1 = std::min(height, y0 + options.tileSize);
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x) {
            const uint64_t pixel = uint64_t(y) * width + x;
            double* sum = &sums[pixel * nc];
            for (int s = sppDone; s < passEnd; ++s) {
              Rng rng(options.seed, pixel, uint64_t(s));
              const Vec2 jitter = rng.uniform2();
              const PathResult p = tracer.trace(camera.generate(x + jitter.x, y + jitter.y), rng, local);
              const Rgb L = p.direct + p.indirect;
              if (!p.valid || !isFinite(L)) {
                ++invalid[pixel];
                continue;
              }
              for (int c = 0; c < 3; ++c) sum[c] += L[c];
              if (options.layers) {
                const float v[13] = {p.albedo.r, p.albedo.g, p.albedo.b, p.normal.x, p.normal.y, p.normal.z, p.depth,
                                     p.direct.r, p.direct.g, p.direct.b, p.indirect.r, p.indirect.g, p.indirect.b};
                for (int c = 0; c < 13; ++c) sum[3 + c] += v[c];
              }
            }
          }
        const uint64_t done = pixelSamplesDone += uint64_t(x1 - x0) * (y1 - y0) * (passEnd - sppDone);
        if (progress) progress(std::min(1.0, done / totalPixelSamples));
      }
    });
    sppDone = passEnd;
  }

  RenderOutput out;
  out.sppDone = sppDone;
  out.image = Image(width, height, channels);
  uint64_t invalidTotal = 0;
  for (size_t p = 0; p < size_t(width) * height; ++p) {
    invalidTotal += invalid[p];
    const double n = std::max<double>(1, sppDone - invalid[p]);
    for (size_t c = 0; c < nc; ++c) out.image.pixels()[p * nc + c] = float(sums[p * nc + c] / n);
  }
  Counters total;
  for (const Counters& c : counters) {
    total.rays += c.rays;
  }
  out.stats.addStage("trace_paths", clock.seconds());
  out.stats.addCounter("rays", total.rays);
  out.stats.addCounter("samples", uint64_t(width) * height * sppDone);
  out.stats.addCounter("invalid_samples", invalidTotal);
  return out;
}

}  // namespace lucent
