// Photon map data structures: the bitonic sort against tbb::parallel_sort and std::sort, build
// times of every map, and kNN-grid against kd-tree queries per second at equal k, with 1 and 2
// threads. Prints one JSON object.
//
// The photon cloud is a Cornell-box-like one: photons from a point light below the ceiling of the
// unit box land on its five walls (open at z = 1) with the 1/r^2 cos falloff of direct light, plus a
// caustic-like blob on the floor; queries are points on the walls, uniform by area, as eye-ray hits
// would be. Timings are the best of --repeats runs, interleaved so that all methods see the same load.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/core/stats.h"
#include "lucent/techniques/photons/kd_tree.h"
#include "methods/photonmap/bitonic_sort.h"
#include "methods/photonmap/knn_grid.h"
#include "methods/photonmap/sorted_grid.h"
#include "methods/photonmap/stencil_grid.h"

using namespace lucent;
using nlohmann::json;

namespace {

// Where a ray from inside the unit box leaves it, or nothing through the open side z = 1.
bool hitWall(Vec3 o, Vec3 d, Vec3& hit) {
  float tExit = kInf;
  int axis = 0;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) continue;
    const float t = ((d[a] > 0 ? 1.0f : 0.0f) - o[a]) / d[a];
    if (t < tExit) tExit = t, axis = a;
  }
  hit = o + d * tExit;
  hit[axis] = d[axis] > 0 ? 1.0f : 0.0f;  // exactly on the wall
  return !(axis == 2 && d.z > 0);
}

std::vector<Photon> boxPhotons(uint32_t n, uint64_t seed) {
  std::vector<Photon> photons;
  const Vec3 light{0.5f, 0.95f, 0.5f};
  for (uint32_t i = 0; photons.size() < n; ++i) {
    Rng rng(seed, i);
    Vec3 p;
    if (rng.uniform() < 0.1f) {  // a caustic on the floor
      p = {0.3f + 0.04f * (rng.uniform() + rng.uniform() - 1), 0.0f, 0.4f + 0.04f * (rng.uniform() + rng.uniform() - 1)};
    } else if (!hitWall(light, sampleUniformSphere(rng.uniform2()), p)) {
      continue;
    }
    photons.push_back({p, Rgb(1e-4f), encodeOctahedral(normalize(light - p)), 0});
  }
  return photons;
}

std::vector<Vec3> wallPoints(uint32_t n, uint64_t seed) {
  std::vector<Vec3> points(n);
  for (uint32_t i = 0; i < n; ++i) {
    Rng rng(seed, i);
    const uint32_t wall = rng.below(5);  // x = 0, x = 1, y = 0, y = 1, z = 0
    Vec3 p{rng.uniform(), rng.uniform(), rng.uniform()};
    p[int(wall / 2)] = wall == 4 ? 0.0f : float(wall % 2);
    points[i] = p;
  }
  return points;
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

// Seconds to build a map; the map is freed after the clock stops.
template <class Build>
double timeBuild(Build&& build) {
  Stopwatch clock;
  const auto map = build();
  return clock.seconds();
}

json benchSorts(int maxLog2, int repeats) {
  json rows = json::array();
  for (int threads : {1, 2}) {
    ParallelScope scope(threads);
    for (int lg = 16; lg <= maxLog2; ++lg) {
      std::vector<uint64_t> keys(size_t(1) << lg);
      Rng rng{uint64_t(lg)};
      for (uint64_t& k : keys) k = packSortKey(rng.next(), uint32_t(&k - keys.data()));
      double seconds[3] = {1e30, 1e30, 1e30};
      for (int r = 0; r < repeats; ++r) {
        std::vector<uint64_t> a = keys, b = keys, c = keys;
        seconds[0] = std::min(seconds[0], bestOf(1, [&] { bitonicSort(a); }));
        seconds[1] = std::min(seconds[1], bestOf(1, [&] { tbb::parallel_sort(b.begin(), b.end()); }));
        seconds[2] = std::min(seconds[2], bestOf(1, [&] { std::sort(c.begin(), c.end()); }));
        if (a != c || b != c) throw std::runtime_error("sorts disagree");
      }
      rows.push_back({{"threads", threads},
                      {"keys", keys.size()},
                      {"bitonic_ms", seconds[0] * 1e3},
                      {"parallel_sort_ms", seconds[1] * 1e3},
                      {"std_sort_ms", seconds[2] * 1e3},
                      {"bitonic_over_parallel_sort", seconds[0] / seconds[1]}});
    }
  }
  return rows;
}

// Best total and best time per stage of each map's build, over the repeats.
json benchBuilds(const std::vector<Photon>& photons, const GridOptions& options, int repeats) {
  json rows = json::array();
  for (int threads : {1, 2}) {
    ParallelScope scope(threads);
    json row = {{"photons", photons.size()}, {"threads", threads}};
    std::map<std::string, double> best;
    auto keep = [&](const std::string& key, double seconds) {
      auto [it, fresh] = best.emplace(key, seconds);
      if (!fresh) it->second = std::min(it->second, seconds);
    };
    for (int r = 0; r < repeats; ++r) {  // interleaved, so that all maps see the same load
      RenderStats sorted, stencil, hashed, kdtree;
      // The grids take their photons by value: a copy is made first, then moved in.
      keep("sorted_grid", timeBuild([&, copy = photons]() mutable { return buildSortedGrid(std::move(copy), options, &sorted); }));
      keep("stencil_grid", timeBuild([&, copy = photons]() mutable { return buildStencilGrid(std::move(copy), options, &stencil); }));
      keep("hashed_grid", timeBuild([&, copy = photons]() mutable { return buildHashedGrid(std::move(copy), options, &hashed); }));
      keep("kdtree", timeBuild([&] { return buildPhotonKdTree(photons, &kdtree); }));
      for (const auto& [map, stats] : {std::pair{"sorted_grid", &sorted}, std::pair{"stencil_grid", &stencil},
                                       std::pair{"hashed_grid", &hashed}})
        for (const auto& [stage, seconds] : stats->stageSeconds) keep(std::string(map) + "/" + stage, seconds);
    }
    for (const auto& [key, seconds] : best) row["ms"][key] = seconds * 1e3;
    rows.push_back(row);
  }
  return rows;
}

struct QueryRun {
  double seconds = 1e30;
  double photonsPerQuery = 0, cellsPerQuery = 0, shellsPerQuery = 0;
};

// Every query sums the power of the photons it finds, as a radiance estimate would.
template <class Map>
QueryRun runGrid(const Map& map, const std::vector<Vec3>& queries, uint32_t k, float maxRadius, int repeats) {
  QueryRun run;
  std::vector<float> sums(queries.size());
  std::vector<KnnGridSearch> searches(queries.size());
  run.seconds = bestOf(repeats, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, queries.size(), 64), [&](const auto& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        float sum = 0;
        searches[i] = knnGrid(map, queries[i], k, maxRadius, [&](uint32_t, const Photon& p, float) { sum += p.power.r; });
        sums[i] = sum / knnGridRadius2(searches[i]);
      }
    });
  });
  for (const KnnGridSearch& s : searches) {
    run.photonsPerQuery += s.found;
    run.cellsPerQuery += s.cellsVisited;
    run.shellsPerQuery += s.shells;
  }
  run.photonsPerQuery /= queries.size();
  run.cellsPerQuery /= queries.size();
  run.shellsPerQuery /= queries.size();
  return run;
}

QueryRun runKdTree(const PhotonKdTree& tree, const std::vector<Vec3>& queries, uint32_t k, float maxRadius,
                   int repeats, std::vector<float>& radii) {
  QueryRun run;
  std::vector<uint32_t> found(queries.size());
  std::vector<float> sums(queries.size());
  radii.assign(queries.size(), 0);
  run.seconds = bestOf(repeats, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, queries.size(), 64), [&](const auto& r) {
      std::vector<PhotonDistance> heap(k);
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const KdTreeResult res = kdTreeNearest(tree, queries[i], k, maxRadius, heap.data());
        float sum = 0;
        for (uint32_t j = 0; j < res.found; ++j) sum += tree.photons[heap[j].index].power.r;
        found[i] = res.found;
        sums[i] = sum / res.radius2;
        radii[i] = std::sqrt(res.radius2);
      }
    });
  });
  for (uint32_t f : found) run.photonsPerQuery += f;
  run.photonsPerQuery /= queries.size();
  return run;
}

json queryRow(const char* map, const QueryRun& run, size_t queries) {
  return {{"map", map},
          {"queries_per_second", queries / run.seconds},
          {"photons_per_query", run.photonsPerQuery},
          {"cells_per_query", run.cellsPerQuery},
          {"shells_per_query", run.shellsPerQuery}};
}

json benchQueries(const std::vector<Photon>& photons, const std::vector<Vec3>& queries, float maxRadius,
                  int repeats) {
  json rows = json::array();
  const PhotonKdTree tree = buildPhotonKdTree(photons);
  for (uint32_t k : {32u, 64u, 500u}) {
    for (int threads : {1, 2}) {
      ParallelScope scope(threads);
      std::vector<float> radii;
      const QueryRun kd = runKdTree(tree, queries, k, maxRadius, repeats, radii);
      std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
      const float medianRadius = radii[radii.size() / 2];
      json row = {{"k", k}, {"threads", threads}, {"max_radius", maxRadius}, {"median_kdtree_radius", medianRadius}};
      row["results"].push_back(queryRow("kdtree", kd, queries.size()));
      // The default resolution (about 8 photons per cell of the bounding box; the stencil grid is
      // capped at the paper's 1024 x 1024 slots), and cells half as wide as the typical radius.
      GridOptions automatic, byRadius;
      byRadius.cellSize = medianRadius * 0.5f;
      for (const auto& [label, options] : {std::pair{"", automatic}, std::pair{"_cell_half_radius", byRadius}}) {
        auto add = [&](const char* name, const auto& map) {
          const QueryRun run = runGrid(map, queries, k, maxRadius, repeats);
          json r = queryRow((std::string(name) + label).c_str(), run, queries.size());
          r["grid"] = std::to_string(map.grid.res[0]) + "x" + std::to_string(map.grid.res[1]) + "x" +
                      std::to_string(map.grid.res[2]);
          r["speed_over_kdtree"] = kd.seconds / run.seconds;
          row["results"].push_back(r);
        };
        add("sorted_grid", buildSortedGrid(photons, options));
        add("stencil_grid", buildStencilGrid(photons, options));
        add("hashed_grid", buildHashedGrid(photons, options));
      }
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Photon map data structures: sorts, builds, kNN-grid against kd-tree queries"};
  uint32_t photonCount = 65000, queryCount = 20000;
  int maxLog2 = 22, repeats = 3;
  float maxRadius = 0.25f;
  app.add_option("--photons", photonCount, "Photons in the box cloud (the paper's Cornell box: 65,000)")->capture_default_str();
  app.add_option("--queries", queryCount, "kNN queries per measurement")->capture_default_str();
  app.add_option("--max-log2", maxLog2, "Largest sort size, log2 (from 16)")->capture_default_str();
  app.add_option("--max-radius", maxRadius, "Maximum search radius (the box is 1 wide)")->capture_default_str();
  app.add_option("--repeats", repeats, "Timed repetitions (the best is reported)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  retainFreedMemory();  // repeated builds reuse memory, as a renderer rebuilding its maps would
  json out;
  out["machine_note"] = "shared machine: compare ratios within one run; warm heap (mallopt)";
  out["sort"] = benchSorts(maxLog2, repeats);
  const std::vector<Photon> photons = boxPhotons(photonCount, 1);
  out["photons"] = photonCount;
  out["build"] = benchBuilds(photons, GridOptions{}, repeats);
  for (const json& row : benchBuilds(boxPhotons(1u << 20, 1), GridOptions{}, repeats)) out["build"].push_back(row);
  out["queries"] = benchQueries(photons, wallPoints(queryCount, 2), maxRadius, repeats);
  std::cout << out.dump(1) << std::endl;
  return 0;
}
