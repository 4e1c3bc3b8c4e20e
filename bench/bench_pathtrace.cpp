// Path tracer throughput against a raw Embree loop over the same scene and the same kinds of rays.
//
// The raw loop first walks paths the way the path tracer does (camera ray, then at each hit one
// shadow ray to a sampled light and one cosine-distributed continuation, the path tracer's Russian
// roulette by throughput) and records every ray; only tracing the recorded rays is timed. Its paths
// are then as long as the path tracer's: pt_rays and raw_rays agree within a few per cent (a loop
// with longer paths traces more of the slow, scattered rays and flatters the path tracer). The path tracer's rays
// per second over the same scene, resolution and samples are then a fraction of that loop's: the
// cost of shading, sampling and bookkeeping.
//
// The path tracer traces its shadow rays in packets of 16, which Embree traces faster than one by
// one. "raw" traces every ray alone (the yardstick); "raw_shadow_packets" traces the
// recorded shadow rays in packets of 16 too, so that pt_over_raw_shadow_packets compares like with
// like: the cost of what the path tracer does besides Embree's work.
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <nlohmann/json.hpp>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/surface.h"

using namespace lucent;

namespace {

struct RecordedRays {
  std::vector<Ray> closest;
  std::vector<Ray> shadow;
};

// The raw loop's paths: the path tracer's (opt's) length, throughput and roulette, so that both trace
// as many rays.
RecordedRays recordRays(const Scene& scene, const Visibility& vis, const PathTraceOptions& opt, uint64_t seed) {
  const PinholeCamera camera(scene.camera);
  const int w = scene.camera.width, h = scene.camera.height;
  std::vector<RecordedRays> perRow(h);
  tbb::parallel_for(0, h, [&](int y) {
    RecordedRays& out = perRow[y];
    for (int x = 0; x < w; ++x)
      for (int s = 0; s < opt.common.spp; ++s) {
        Rng rng(seed, uint64_t(y) * w + x, s);
        Ray ray = camera.generate(x + rng.uniform(), y + rng.uniform());
        Rgb beta(1.0f);  // the path's throughput, for the path tracer's roulette
        for (int depth = 0; depth < opt.maxDepth; ++depth) {
          out.closest.push_back(ray);
          const Hit hit = vis.intersect(ray);
          if (!hit.found()) break;
          const SurfacePoint sp = surfaceAt(scene, hit.triangle, hit.b1, hit.b2);
          Vec3 n = sp.geometricNormal;
          if (dot(n, ray.direction) > 0) n = -n;
          const LightSample ls = sampleLight(scene, sp.position, rng.uniform(), rng.uniform2());
          if (ls.pdf > 0 && dot(ls.wi, n) > 0) out.shadow.push_back(shadowRay(sp.position, n, ls));
          const Vec3 wi = Frame(n).toWorld(sampleCosineHemisphere(rng.uniform2()));
          ray = {offsetOrigin(sp.position, n, wi), wi};
          // The path tracer's continuation: the cosine-sampled weight is the albedo, a black
          // throughput ends the path, and from the roulette depth on Russian roulette.
          beta *= bsdfAt(scene, sp).diffuse();
          if (beta.isBlack()) break;
          if (depth + 1 >= opt.rouletteDepth && !survivesRussianRoulette(beta, rng.uniform())) break;
        }
      }
  });
  RecordedRays all;
  for (auto& r : perRow) {
    all.closest.insert(all.closest.end(), r.closest.begin(), r.closest.end());
    all.shadow.insert(all.shadow.end(), r.shadow.begin(), r.shadow.end());
  }
  return all;
}

// Seconds to trace every recorded ray, in recorded order, in parallel chunks; shadow rays one at a
// time or, as the path tracer traces them, in packets of 16.
double traceRecorded(const Visibility& vis, const RecordedRays& rays, bool shadowPackets) {
  Stopwatch clock;
  std::atomic<uint64_t> sink{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.closest.size(), 4096), [&](const auto& r) {
    uint64_t found = 0;
    for (size_t i = r.begin(); i != r.end(); ++i) found += vis.intersect(rays.closest[i]).found();
    sink += found;
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.shadow.size(), 4096), [&](const auto& r) {
    uint64_t blocked = 0;
    if (!shadowPackets)
      for (size_t i = r.begin(); i != r.end(); ++i) blocked += vis.occluded(rays.shadow[i]);
    if (shadowPackets)
      occludedInPackets(
          vis, r.size(), [&](size_t i) -> const Ray& { return rays.shadow[r.begin() + i]; },
          [&](size_t, bool occluded) { blocked += occluded; });
    sink += blocked;
  });
  return clock.seconds();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Path tracer throughput against raw Embree"};
  std::vector<std::string> scenes;
  std::string resolution = "256x256";
  int spp = 16, repeats = 3;
  app.add_option("scenes", scenes, "Scene files")->required();
  app.add_option("--resolution", resolution, "WIDTHxHEIGHT")->capture_default_str();
  app.add_option("--spp", spp, "Samples per pixel")->capture_default_str();
  app.add_option("--repeats", repeats, "Timed repetitions (the best is reported)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  int w = 0, h = 0;
  if (std::sscanf(resolution.c_str(), "%dx%d", &w, &h) != 2 || w < 1 || h < 1) {
    std::cerr << "bad --resolution\n";
    return 1;
  }

  for (const auto& path : scenes) {
    Scene scene = loadScene(path, {true});
    scene.camera.width = w;
    scene.camera.height = h;
    nlohmann::json row;
    row["scene"] = path;
    row["resolution"] = resolution;
    row["spp"] = spp;
    // One ray set, one Embree scene; then every repetition runs the path tracer, the raw loop and
    // the raw loop with shadow packets with 1 thread and with 2, in turns, so that a change in the
    // machine's speed between phases does not show up as a speed-up.
    const Visibility vis(scene);
    PathTraceOptions opt;
    opt.common.spp = spp;
    // The raw loop's rays are those of the independent sampler's paths: the path tracer is timed
    // with it, like with like, and with the default Sobol sampler apart (its numbers' cost).
    opt.sampler = SamplerKind::Independent;
    PathTraceOptions sobol = opt;
    sobol.sampler = SamplerKind::Sobol;
    const RecordedRays rays = recordRays(scene, vis, opt, 1);
    const uint64_t rawRays = rays.closest.size() + rays.shadow.size();
    uint64_t ptRays = 0;
    double bestPt[3] = {1e30, 1e30, 1e30}, bestRaw[3] = {1e30, 1e30, 1e30}, bestPackets[3] = {1e30, 1e30, 1e30},
           bestSobol[3] = {1e30, 1e30, 1e30};
    for (int r = 0; r < repeats; ++r)
      for (int threads : {1, 2}) {
        ParallelScope scope(threads);
        const RenderOutput out = renderPathTraced(scene, vis, opt);
        bestPt[threads] = std::min(bestPt[threads], out.stats.stageSeconds.front().second);
        ptRays = out.stats.counter("rays");
        bestRaw[threads] = std::min(bestRaw[threads], traceRecorded(vis, rays, false));
        bestPackets[threads] = std::min(bestPackets[threads], traceRecorded(vis, rays, true));
        bestSobol[threads] =
            std::min(bestSobol[threads], renderPathTraced(scene, vis, sobol).stats.stageSeconds.front().second);
      }
    for (int threads : {1, 2}) {
      const std::string t = std::to_string(threads) + "_threads";
      row[t]["pt_seconds"] = bestPt[threads];
      row[t]["pt_samples_per_second"] = double(w) * h * spp / bestPt[threads];
      row[t]["pt_rays_per_second"] = ptRays / bestPt[threads];
      row[t]["raw_rays_per_second"] = rawRays / bestRaw[threads];
      row[t]["pt_over_raw"] = (ptRays / bestPt[threads]) / (rawRays / bestRaw[threads]);
      row[t]["raw_shadow_packets_rays_per_second"] = rawRays / bestPackets[threads];
      row[t]["pt_over_raw_shadow_packets"] = (ptRays / bestPt[threads]) / (rawRays / bestPackets[threads]);
      row[t]["pt_sobol_seconds_over_independent"] = bestSobol[threads] / bestPt[threads];
    }
    row["embree_isa"] = vis.isa();
    row["pt_speedup_2_over_1"] = bestPt[1] / bestPt[2];
    row["raw_speedup_2_over_1"] = bestRaw[1] / bestRaw[2];
    row["pt_rays"] = ptRays;
    row["raw_rays"] = rawRays;
    std::cout << row.dump() << std::endl;
  }
  return 0;
}
