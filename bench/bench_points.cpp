// The point hierarchy (src/techniques/points): best-candidate sampling, median split, node data and refit
// times for 2^a .. 2^b points, the points' spacing against plain uniform sampling, how much of the
// surface the leaf discs cover for several disc areas, and the packed nodes' quantization error.
// Prints one JSON object. Timings are the best of --repeats runs.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <unordered_map>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/core/stats.h"
#include "lucent/scene/loader.h"
#include "lucent/techniques/points/point_hierarchy.h"

using namespace lucent;
using nlohmann::json;

namespace {

double totalArea(const Scene& scene) {
  double a = 0;
  for (float f : scene.faceAreas) a += f;
  return a;
}

// Points hashed into cubic cells, for neighbour queries within one cell size.
struct PointGrid {
  float cell;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    return uint64_t(x & 0x1fffff) | uint64_t(y & 0x1fffff) << 21 | uint64_t(z & 0x1fffff) << 42;
  }
  PointGrid(const std::vector<Vec3>& p, float cellSize) : cell(cellSize) {
    for (uint32_t i = 0; i < p.size(); ++i) cells[keyOf(p[i])].push_back(i);
  }
  uint64_t keyOf(Vec3 q) const {
    return key(int64_t(std::floor(q.x / cell)), int64_t(std::floor(q.y / cell)), int64_t(std::floor(q.z / cell)));
  }
  template <class F>
  void forNeighbours(Vec3 q, F&& f) const {
    const int64_t x = int64_t(std::floor(q.x / cell)), y = int64_t(std::floor(q.y / cell)), z = int64_t(std::floor(q.z / cell));
    for (int64_t dz = -1; dz <= 1; ++dz)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dx = -1; dx <= 1; ++dx) {
          const auto it = cells.find(key(x + dx, y + dy, z + dz));
          if (it != cells.end())
            for (uint32_t i : it->second) f(i);
        }
  }
};

// Nearest-neighbour distances in units of the mean spacing sqrt(area / n): minimum, 1st percentile, mean.
json spacing(const std::vector<Vec3>& p, double area) {
  const float s = float(std::sqrt(area / p.size()));
  const PointGrid grid(p, 2 * s);
  std::vector<float> nn(p.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 1024), [&](const auto& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      float best = 2 * s;
      grid.forNeighbours(p[i], [&](uint32_t j) {
        if (j != i) best = std::min(best, length(p[j] - p[i]));
      });
      nn[i] = best / s;
    }
  });
  std::vector<float> sorted = nn;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0;
  for (float d : nn) mean += d;
  return {{"min", sorted.front()}, {"p01", sorted[sorted.size() / 100]}, {"mean", mean / nn.size()}};
}

// Fraction of the surface within a leaf disc, for disc area k * (area / n): probes uniform by area,
// each covered by the discs of points on its own plane (coplanar within 1e-4 of the spacing).
json coverage(const Scene& scene, const std::vector<PointSample>& points, double area, uint32_t probes) {
  std::vector<Vec3> p(points.size());
  for (size_t i = 0; i < p.size(); ++i) p[i] = pointPosition(scene, points[i]);
  const float s = float(std::sqrt(area / p.size()));
  const PointGrid grid(p, 2 * s);
  const Distribution1D areas(scene.faceAreas);
  std::vector<float> d(probes);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, probes, 1024), [&](const auto& r) {
    for (uint32_t i = r.begin(); i != r.end(); ++i) {
      Rng rng(99, i);
      const uint32_t t = areas.sampleDiscrete(rng.uniform());
      const Vec2 b = sampleUniformTriangle(rng.uniform2());
      const Vec3 q = pointPosition(scene, {t, b.x, b.y});
      const Vec3 n = scene.faceNormals[t];
      float best = 2 * s;
      grid.forNeighbours(q, [&](uint32_t j) {
        const Vec3 v = p[j] - q;
        const Vec3 nj = scene.faceNormals[points[j].triangle];
        if (std::abs(dot(v, n)) <= 1e-4f * s && std::abs(dot(n, nj)) > 0.9999f) best = std::min(best, length(v));
      });
      d[i] = best / s;
    }
  });
  json out = json::object();
  for (float k : {1.0f, 1.5f, 2.0f, 2.5f, 3.0f, 4.0f}) {
    const float r = std::sqrt(k / kPi);
    size_t covered = 0;
    for (float x : d) covered += x <= r;
    out[std::to_string(k).substr(0, 3)] = double(covered) / probes;
  }
  return out;
}

template <class F>
double bestOf(int repeats, F&& f) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r) {
    Stopwatch clock;
    f();
    best = std::min(best, clock.seconds());
  }
  return best;
}

// The quantization error of the packed nodes against the float ones, leaves and interior apart.
json quantizationError(const PointHierarchy& h) {
  json out;
  for (int leaves = 1; leaves >= 0; --leaves) {
    double maxPos = 0, sumPos = 0, maxRad = 0, sumRad = 0, maxAng = 0, sumAng = 0, maxAlb = 0, sumAlb = 0,
           maxCone = 0, radius = 0;
    uint32_t count = 0;
    const uint32_t b = leaves ? h.leafCount : 1, e = leaves ? 2 * h.leafCount : h.leafCount;
    for (uint32_t i = b; i < e; ++i) {
      const FloatNode f = h.floatNodes[i], p = decodeNode(h.packedNodes[i], h.quantization);
      const double dp = length(p.sphere.center - f.sphere.center), dr = p.sphere.radius - f.sphere.radius;
      const double da = angleBetween(p.cone.axis, f.cone.axis), dc = p.cone.angle - f.cone.angle;
      double dal = 0;
      for (int c = 0; c < 3; ++c) dal = std::max(dal, double(std::abs(p.albedo[c] - f.albedo[c])));
      maxPos = std::max(maxPos, dp), sumPos += dp;
      maxRad = std::max(maxRad, dr), sumRad += dr;
      maxAng = std::max(maxAng, da), sumAng += da;
      maxAlb = std::max(maxAlb, dal), sumAlb += dal;
      maxCone = std::max(maxCone, dc);
      radius += f.sphere.radius;
      ++count;
    }
    if (count == 0) continue;
    out[leaves ? "leaves" : "interior"] = {{"mean_float_radius", radius / count},
                                           {"position_max", maxPos}, {"position_mean", sumPos / count},
                                           {"radius_growth_max", maxRad}, {"radius_growth_mean", sumRad / count},
                                           {"normal_deg_max", maxAng * 180 / kPi}, {"normal_deg_mean", sumAng / count * 180 / kPi},
                                           {"cone_growth_deg_max", maxCone * 180 / kPi},
                                           {"albedo_max", maxAlb}, {"albedo_mean", sumAlb / count}};
  }
  out["position_step"] = {h.quantization.step.x, h.quantization.step.y, h.quantization.step.z};
  out["radius_step"] = h.quantization.radiusStep;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Point hierarchy benchmark"};
  std::string scenePath = "scenes/cornell-box.json";
  int minLog2 = 16, maxLog2 = 21, repeats = 3, threads = 2;
  uint32_t candidates = 8;
  float tileScale = 2.0f;
  bool quality = true;
  app.add_option("scene", scenePath);
  app.add_option("--min-log2", minLog2);
  app.add_option("--max-log2", maxLog2);
  app.add_option("--repeats", repeats);
  app.add_option("--threads", threads);
  app.add_option("--candidates", candidates);
  app.add_option("--tile-scale", tileScale);
  app.add_flag("!--no-quality", quality, "skip spacing, coverage and quantization measurements");
  CLI11_PARSE(app, argc, argv);

  ParallelScope scope(threads);
  const Scene scene = loadScene(scenePath, LoadOptions(true));
  const double area = totalArea(scene);
  json result = {{"scene", scenePath}, {"triangles", scene.triangleCount()}, {"threads", threads},
                 {"candidates", candidates}, {"tile_scale", tileScale}, {"rows", json::array()}};
  for (int lg = minLog2; lg <= maxLog2; ++lg) {
    const uint32_t n = 1u << lg;
    PointHierarchyOptions options;
    options.pointCount = n;
    options.sampling.candidates = candidates;
    options.sampling.tileScale = tileScale;
    std::vector<PointSample> points;
    std::map<std::string, double> best;
    json counters;
    auto keep = [&](const RenderStats& stats) {
      for (const auto& [name, value] : stats.counters) counters[name] = value;
      for (const auto& [stage, seconds] : stats.stageSeconds) {
        auto [it, fresh] = best.emplace(stage, seconds);
        if (!fresh) it->second = std::min(it->second, seconds);
      }
    };
    PointHierarchy h;
    for (int r = 0; r < repeats; ++r) {
      RenderStats stats;
      points = samplePoints(scene, n, options.sampling, &stats);
      h = buildPointHierarchy(scene, points, options, &stats);
      keep(stats);
    }
    // Refit after a deformation: every vertex moved by a smooth displacement.
    Scene moved = scene;
    for (Vec3& v : moved.positions) v += Vec3{3 * std::sin(v.y * 0.01f), 0, 2 * std::cos(v.x * 0.01f)};
    std::map<std::string, double> refitBest;
    const double refit = bestOf(repeats, [&] {
      RenderStats stats;
      refitPointHierarchy(h, moved, &stats);
      for (const auto& [stage, seconds] : stats.stageSeconds) {
        auto [it, fresh] = refitBest.emplace(stage, seconds);
        if (!fresh) it->second = std::min(it->second, seconds);
      }
    });
    json row = {{"points", n}, {"refit_ms", refit * 1e3}, {"counters", counters}};
    for (const auto& [stage, seconds] : refitBest) row["refit_stage_ms"][stage] = seconds * 1e3;
    for (const auto& [stage, seconds] : best) row["ms"][stage] = seconds * 1e3;
    if (quality) {
      std::vector<Vec3> p(n);
      for (uint32_t i = 0; i < n; ++i) p[i] = pointPosition(scene, points[i]);
      row["spacing_best_candidate"] = spacing(p, area);
      PointSamplingOptions uniform = options.sampling;
      uniform.candidates = 1;
      const std::vector<PointSample> u = samplePoints(scene, n, uniform);
      for (uint32_t i = 0; i < n; ++i) p[i] = pointPosition(scene, u[i]);
      row["spacing_uniform"] = spacing(p, area);
      row["coverage_best_candidate"] = coverage(scene, points, area, 1u << 20);
      row["coverage_uniform"] = coverage(scene, u, area, 1u << 20);
      refitPointHierarchy(h, scene);
      row["quantization"] = quantizationError(h);
    }
    result["rows"].push_back(row);
    std::cerr << "2^" << lg << " done\n";
  }
  std::cout << result.dump(1) << "\n";
  return 0;
}
