// Photon map data structures (Purcell et al. 2003, section 2.2-2.3 and 4.4; Jensen's kd-tree): the
// bitonic sort against std::sort, every map's neighbour sets against brute force, stencil routing's
// storage and power redistribution, the progressive kNN-grid search, and determinism.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <vector>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/techniques/photons/kd_tree.h"
#include "methods/photonmap/bitonic_sort.h"
#include "methods/photonmap/estimate_by_cell.h"
#include "methods/photonmap/knn_grid.h"
#include "methods/photonmap/radiance_estimate.h"
#include "methods/photonmap/sorted_grid.h"
#include "methods/photonmap/stencil_grid.h"

using namespace lucent;

namespace {

enum class Cloud { Uniform, Clustered, Flat };

// Photons in [-1, 1]^3; clustered: dense Gaussian blobs, photons on the faces of a box and a
// sprinkling of outliers (varying density, as in a scene); flat: all on the plane y = 0.25.
std::vector<Photon> photonCloud(uint32_t n, Cloud cloud, uint64_t seed, bool equalPower = false) {
  Rng rng(seed);
  std::vector<Photon> photons(n);
  Vec3 centres[4];
  for (Vec3& c : centres) c = {rng.uniform() * 1.6f - 0.8f, rng.uniform() * 1.6f - 0.8f, rng.uniform() * 1.6f - 0.8f};
  for (uint32_t i = 0; i < n; ++i) {
    Vec3 p{rng.uniform() * 2 - 1, rng.uniform() * 2 - 1, rng.uniform() * 2 - 1};
    if (cloud == Cloud::Flat) p.y = 0.25f;
    if (cloud == Cloud::Clustered) {
      const uint32_t kind = rng.below(10);
      if (kind < 5) {  // a blob of width ~0.05
        const Vec3 c = centres[rng.below(4)];
        p = c + 0.05f * Vec3{rng.uniform() + rng.uniform() - 1, rng.uniform() + rng.uniform() - 1,
                             rng.uniform() + rng.uniform() - 1};
      } else if (kind < 9) {  // a face of the box
        p[int(rng.below(3))] = rng.uniform() < 0.5f ? -1.0f : 1.0f;
      }
    }
    const float power = equalPower ? 0.01f : 0.001f + 0.02f * rng.uniform();
    photons[i] = {p, Rgb(power, 0.5f * power, 0.25f * power), encodeOctahedral(normalize(Vec3{0.3f, 1, 0.2f})),
                  i % 5 | photonFacingBits({0, 1, 0})};
  }
  return photons;
}

// A photon arriving from a random direction on a surface facing a random way.
void randomizeSides(Photon& photon, Rng& rng) {
  photon.direction = encodeOctahedral(sampleUniformSphere(rng.uniform2()));
  photon.flags = (photon.flags & ((1u << kPhotonFacingShift) - 1)) | photonFacingBits(sampleUniformSphere(rng.uniform2()));
}

// Queries inside the cloud, at photons, and outside its bounds.
std::vector<Vec3> queryPoints(const std::vector<Photon>& photons, uint32_t count, uint64_t seed) {
  Rng rng(seed);
  std::vector<Vec3> q;
  for (uint32_t i = 0; i < count; ++i) {
    switch (i % 4) {
      case 0: q.push_back({rng.uniform() * 2 - 1, rng.uniform() * 2 - 1, rng.uniform() * 2 - 1}); break;
      case 1: q.push_back(photons[rng.below(uint32_t(photons.size()))].position); break;
      case 2: q.push_back({rng.uniform() * 6 - 3, rng.uniform() * 6 - 3, rng.uniform() * 6 - 3}); break;
      default: q.push_back(photons[rng.below(uint32_t(photons.size()))].position + Vec3(0.01f, -0.02f, 0.005f));
    }
  }
  return q;
}

std::vector<uint32_t> bruteWithin(const std::vector<Photon>& photons, Vec3 p, float r2) {
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < photons.size(); ++i)
    if (distance2(photons[i].position, p) <= r2) ids.push_back(i);
  return ids;
}

// (d2, index) of every photon, nearest first.
std::vector<std::pair<float, uint32_t>> bruteSorted(const std::vector<Photon>& photons, Vec3 p) {
  std::vector<std::pair<float, uint32_t>> all;
  for (uint32_t i = 0; i < photons.size(); ++i) all.push_back({distance2(photons[i].position, p), i});
  std::sort(all.begin(), all.end());
  return all;
}

struct GridResult {
  std::vector<uint32_t> ids;  // in visiting order
  KnnGridSearch search;
  std::vector<uint32_t> sorted() const {
    std::vector<uint32_t> s = ids;
    std::sort(s.begin(), s.end());
    return s;
  }
};

template <class Map>
GridResult gridQuery(const Map& map, Vec3 p, uint32_t k, float maxRadius) {
  GridResult r;
  r.search = knnGrid(map, p, k, maxRadius, [&](uint32_t id, const Photon&, float) { r.ids.push_back(id); });
  return r;
}

// The kNN-grid's contract against brute force: every photon within the final radius and only those;
// at least k of them, over a radius at least the k-th nearest's; or, with fewer than k within the
// maximum radius, all of those and the maximum radius.
void checkAgainstBruteForce(const std::vector<Photon>& photons, const std::vector<std::pair<float, uint32_t>>& sorted,
                            const GridResult& r, Vec3 p, uint32_t k, float maxRadius) {
  const float maxR2 = maxRadius * maxRadius;
  const size_t withinMax = std::count_if(sorted.begin(), sorted.end(), [&](auto& e) { return e.first <= maxR2; });
  REQUIRE(r.search.done);
  CHECK(r.sorted() == bruteWithin(photons, p, r.search.radius2));
  CHECK(r.ids.size() == r.search.found);
  if (withinMax >= k) {
    CHECK(r.search.found >= k);
    if (k > 0) CHECK(r.search.radius2 >= sorted[k - 1].first);
    CHECK(r.search.radius2 <= maxR2);
    CHECK(knnGridRadius2(r.search) == r.search.radius2);
  } else {
    CHECK(r.search.found == withinMax);
    CHECK(knnGridRadius2(r.search) == maxR2);
  }
}

}  // namespace

TEST_CASE("Bitonic sort equals std::sort for any size", "[photonmap][bitonic]") {
  std::mt19937_64 random(7);
  for (size_t n : {0, 1, 2, 3, 5, 1000, 4097, 100000}) {
    for (int distinct : {0, 3, 1000}) {  // 0: full 64-bit keys; else many equal keys
      std::vector<uint64_t> keys(n);
      for (uint64_t& key : keys) key = distinct ? random() % distinct : random();
      if (n > 2 && !distinct) keys[1] = ~uint64_t(0);  // the padding value itself must sort too
      std::vector<uint64_t> expected = keys;
      std::sort(expected.begin(), expected.end());
      for (uint32_t block : {2u, 64u, kBitonicLocalBlock}) {  // merged locally from distance 1, 32, 2048
        std::vector<uint64_t> sorted = keys;
        bitonicSort(sorted, block);
        INFO("n = " << n << ", distinct = " << distinct << ", block = " << block);
        CHECK(sorted == expected);
      }
    }
  }
}

TEST_CASE("Bitonic sort of (cell, photon index) pairs orders photons by cell, then index", "[photonmap][bitonic]") {
  std::mt19937 random(3);
  std::vector<uint64_t> pairs;
  for (uint32_t i = 0; i < 5001; ++i) pairs.push_back(packSortKey(random() % 17, i));
  for (int threads : {1, 2}) {
    ParallelScope scope(threads);
    std::vector<uint64_t> sorted = pairs;
    bitonicSort(sorted);
    for (size_t i = 1; i < sorted.size(); ++i) {
      const bool ordered = sortKeyOf(sorted[i - 1]) < sortKeyOf(sorted[i]) ||
                           (sortKeyOf(sorted[i - 1]) == sortKeyOf(sorted[i]) &&
                            sortIndexOf(sorted[i - 1]) < sortIndexOf(sorted[i]));
      REQUIRE(ordered);
    }
  }
}

TEST_CASE("kd-tree returns exactly the k nearest photons within the maximum radius", "[photonmap][kdtree]") {
  for (Cloud cloud : {Cloud::Uniform, Cloud::Clustered, Cloud::Flat}) {
    const std::vector<Photon> photons = photonCloud(4000, cloud, 11 + int(cloud));
    const PhotonKdTree tree = buildPhotonKdTree(photons);
    REQUIRE(tree.photons.size() == photons.size());
    std::vector<PhotonDistance> heap(500);
    for (Vec3 p : queryPoints(photons, 40, 5)) {
      const auto nearestFirst = bruteSorted(photons, p);
      for (uint32_t k : {1u, 8u, 50u, 500u}) {
        for (float maxRadius : {0.05f, 0.3f, 10.0f}) {
          const KdTreeResult r = kdTreeNearest(tree, p, k, maxRadius, heap.data());
          std::vector<uint32_t> got;
          for (uint32_t i = 0; i < r.found; ++i) got.push_back(tree.sourceIndex[heap[i].index]);
          std::sort(got.begin(), got.end());
          std::vector<uint32_t> expected;
          float kth2 = 0;
          for (const auto& [d2, id] : nearestFirst)
            if (expected.size() < k && d2 <= maxRadius * maxRadius) expected.push_back(id), kth2 = d2;
          std::sort(expected.begin(), expected.end());
          INFO("k = " << k << ", max radius = " << maxRadius);
          CHECK(got == expected);
          CHECK(r.radius2 == (r.found == k ? kth2 : maxRadius * maxRadius));
          if (r.found == k) CHECK(heap[0].d2 == kth2);  // a max-heap
        }
      }
    }
  }
}

TEST_CASE("kd-tree is median-ordered and independent of the thread count", "[photonmap][kdtree][determinism]") {
  const std::vector<Photon> photons = photonCloud(10000, Cloud::Clustered, 4);
  PhotonKdTree trees[2];
  for (int threads : {1, 2}) {
    ParallelScope scope(threads);
    trees[threads - 1] = buildPhotonKdTree(photons);
  }
  CHECK(trees[0].sourceIndex == trees[1].sourceIndex);
  const PhotonKdTree& tree = trees[0];
  // Every splitting photon has its left subtree below it and its right subtree above it.
  auto check = [&](auto&& self, uint32_t lo, uint32_t hi) -> void {
    if (hi - lo < 2) return;
    const uint32_t mid = lo + (hi - lo) / 2;
    const int a = photonSplitAxis(tree.photons[mid]);
    for (uint32_t i = lo; i < hi; ++i) {
      if (i < mid) REQUIRE(tree.photons[i].position[a] <= tree.photons[mid].position[a]);
      if (i > mid) REQUIRE(tree.photons[i].position[a] >= tree.photons[mid].position[a]);
    }
    self(self, lo, mid);
    self(self, mid + 1, hi);
  };
  check(check, 0, uint32_t(tree.photons.size()));
  for (uint32_t i = 0; i < tree.photons.size(); ++i) {  // the record is the input's but for the axis
    const Photon& in = photons[tree.sourceIndex[i]];
    CHECK(tree.photons[i].position == in.position);
    CHECK(photonBounce(tree.photons[i]) == photonBounce(in));
  }
}

TEST_CASE("Sorted grid: first photon per cell by binary search (Fig. 4)", "[photonmap][grid]") {
  const std::vector<Photon> photons = photonCloud(3000, Cloud::Clustered, 9);
  const SortedGrid map = buildSortedGrid(photons);
  const uint32_t cells = uint32_t(map.grid.cellCount());
  REQUIRE(map.firstPhoton.size() == cells + 1);
  CHECK(map.firstPhoton.back() == photons.size());
  std::vector<uint32_t> seen;
  for (uint32_t c = 0; c < cells; ++c) {
    REQUIRE(map.firstPhoton[c] <= map.firstPhoton[c + 1]);
    for (uint32_t i = map.firstPhoton[c]; i < map.firstPhoton[c + 1]; ++i) {
      const uint32_t id = map.photonList[i];
      REQUIRE(map.grid.cellIndex(map.grid.cellOf(photons[id].position)) == c);
      if (i > map.firstPhoton[c]) REQUIRE(map.photonList[i - 1] < id);  // index order within a cell
      seen.push_back(id);
    }
  }
  std::sort(seen.begin(), seen.end());
  for (uint32_t i = 0; i < seen.size(); ++i) REQUIRE(seen[i] == i);
  CHECK(seen.size() == photons.size());
}

TEST_CASE("Grid resolution follows the options", "[photonmap][grid]") {
  const std::vector<Photon> photons = photonCloud(8000, Cloud::Uniform, 2);
  GridOptions options;
  options.photonsPerCell = 8;
  const UniformGrid automatic = buildSortedGrid(photons, options).grid;
  // 8000 / 8 = 1000 cubic cells of side s over the cloud's bounds (s^d = the bounds' d-volume /
  // 1000, d the axes thicker than s), each axis rounded up: at least 1000, fewer than the product
  // of (extent / s + 1).
  auto cellBounds = [](const UniformGrid& g, int dims) {
    const Vec3 e = g.hi - g.lo;
    const double volume = dims == 3 ? double(e.x) * e.y * e.z : double(e.x) * e.z;
    const double s = std::pow(volume / 1000, 1.0 / dims);
    return (e.x / s + 1) * (e.z / s + 1) * (dims == 3 ? e.y / s + 1 : 1.0);
  };
  CHECK(automatic.cellCount() >= 1000);
  CHECK(double(automatic.cellCount()) < cellBounds(automatic, 3));
  CHECK(automatic.cellSize.x == automatic.cellSize.y);
  // A flat cloud: one cell across, the cells sized over the plane.
  const UniformGrid flat = buildSortedGrid(photonCloud(8000, Cloud::Flat, 2), options).grid;
  CHECK(flat.res[1] == 1);
  CHECK(flat.cellCount() >= 1000);
  CHECK(double(flat.cellCount()) < cellBounds(flat, 2));
  options.cellSize = 0.25f;
  const UniformGrid bySize = buildSortedGrid(photons, options).grid;
  CHECK(bySize.res[0] == 8);
  CHECK(bySize.cellSize.z == 0.25f);
  options.resolution = {25, 25, 50};  // the paper's Cornell box grid
  const UniformGrid explicitRes = buildSortedGrid(photons, options).grid;
  CHECK(explicitRes.res == std::array<int32_t, 3>{25, 25, 50});
  options.maxCells = 1000;
  CHECK(buildSortedGrid(photons, options).grid.cellCount() <= 1000);
}

TEST_CASE("kNN-grid on the sorted, hashed and stencil grids finds every photon within its radius",
          "[photonmap][knn]") {
  struct Setup {
    Cloud cloud;
    GridOptions options;
  };
  GridOptions coarse, fine, boxes, flat;
  coarse.photonsPerCell = 40;
  fine.cellSize = 0.08f;  // many shells per search
  boxes.resolution = {7, 3, 13};
  flat.photonsPerCell = 4;
  uint8_t boxesRead = 0;
  for (const Setup& setup : {Setup{Cloud::Uniform, coarse}, Setup{Cloud::Clustered, GridOptions{}},
                             Setup{Cloud::Clustered, fine}, Setup{Cloud::Clustered, boxes}, Setup{Cloud::Flat, flat}}) {
    const std::vector<Photon> photons = photonCloud(3000, setup.cloud, 21 + int(setup.cloud));
    GridOptions options = setup.options;
    options.hashBuckets = 64;  // few buckets: many collisions to skip
    const SortedGrid sorted = buildSortedGrid(photons, options);
    // Room for every photon of a cell: stencil routing drops none.
    uint32_t fullest = 0;
    for (size_t c = 0; c + 1 < sorted.firstPhoton.size(); ++c)
      fullest = std::max(fullest, sorted.firstPhoton[c + 1] - sorted.firstPhoton[c]);
    options.stencilSide = uint32_t(std::ceil(std::sqrt(double(fullest))));
    options.maxStencilSlots = sorted.grid.cellCount() * options.stencilSide * options.stencilSide;
    const HashedGrid hashed = buildHashedGrid(photons, options);
    const StencilGrid stencil = buildStencilGrid(photons, options);
    REQUIRE(stencil.grid.res == sorted.grid.res);
    REQUIRE(hashed.grid.res == sorted.grid.res);
    for (uint32_t c = 0; c < stencil.arrived.size(); ++c) REQUIRE(stencil.arrived[c] <= stencil.capacity());
    uint64_t collisions = 0;
    for (Vec3 p : queryPoints(photons, 24, 8)) {
      const auto nearestFirst = bruteSorted(photons, p);
      for (uint32_t k : {1u, 16u, 64u}) {
        for (float maxRadius : {0.08f, 0.4f, 4.0f}) {
          INFO("cloud " << int(setup.cloud) << ", k = " << k << ", max radius = " << maxRadius << ", res "
                        << sorted.grid.res[0] << "x" << sorted.grid.res[1] << "x" << sorted.grid.res[2]);
          const GridResult a = gridQuery(sorted, p, k, maxRadius);
          checkAgainstBruteForce(photons, nearestFirst, a, p, k, maxRadius);
          // The same search: the stencil grid step by step; the hashed grid goes shell by shell
          // from the start, where the others take the first shells whose photons are all accepted
          // as one box (acceptedCube), so it meets the same photons in another order, and the
          // same radius says the box changed nothing the order decides.
          const GridResult b = gridQuery(hashed, p, k, maxRadius);
          const GridResult c = gridQuery(stencil, p, k, maxRadius);
          CHECK(b.sorted() == a.sorted());
          CHECK(c.ids == a.ids);
          CHECK(b.search.radius2 == a.search.radius2);
          CHECK(c.search.radius2 == a.search.radius2);
          collisions += b.search.collisionsSkipped;
          CHECK(b.search.boxesRead == 0);
          boxesRead |= a.search.boxesRead | c.search.boxesRead;
        }
      }
    }
    CHECK(collisions > 0);
  }
  // Each way of reading boxes of rows was compared with shell by shell.
  CHECK(boxesRead == (kReadShortSearch | kReadAcceptedCube | kReadBeyondCube));
}

TEST_CASE("kNN-grid's boxes and rows stop where shell by shell stops, at any number of shells",
          "[photonmap][knn]") {
  // The sorted and stencil grids read boxes and rows where the order cannot matter
  // (exploreShortSearch, acceptedCube, exploreBeyondCube); the hashed grid goes shell by shell.
  // After the same number of shells, and at the extremes of k and of the maximum radius, both
  // must hold the same photons, radius and count, and agree on whether the search is over.
  GridOptions fine;
  fine.cellSize = 0.06f;
  fine.hashBuckets = 256;
  const std::vector<Photon> photons = photonCloud(3000, Cloud::Clustered, 5);
  const SortedGrid sorted = buildSortedGrid(photons, fine);
  const HashedGrid hashed = buildHashedGrid(photons, fine);
  uint64_t compared = 0, unfinished = 0;
  uint8_t boxesRead = 0;
  for (Vec3 p : queryPoints(photons, 32, 17))
    for (uint32_t k : {1u, 20u, 200u, 4000u})
      for (float maxRadius : {0.0f, 0.1f, 0.5f, 1e30f})
        for (uint32_t budget : {1u, 2u, 3u, 5u, 8u, UINT32_MAX}) {
          INFO("k = " << k << ", max radius " << maxRadius << ", shells " << budget);
          GridResult a, b;
          a.search = beginKnnGrid(p, k, maxRadius), b.search = a.search;
          advanceKnnGrid(sorted, a.search, budget, [&](uint32_t id, const Photon&, float) { a.ids.push_back(id); });
          advanceKnnGrid(hashed, b.search, budget, [&](uint32_t id, const Photon&, float) { b.ids.push_back(id); });
          REQUIRE(a.sorted() == b.sorted());
          CHECK(a.search.radius2 == b.search.radius2);
          CHECK(a.search.found == b.search.found);
          // The hashed grid has no cell counts to see that the rest is empty, so it may take
          // another call to notice the end; its photons are final either way.
          if (a.search.done != b.search.done) {
            CHECK(a.search.done);
            advanceKnnGrid(hashed, b.search, UINT32_MAX, [&](uint32_t id, const Photon&, float) { b.ids.push_back(id); });
            CHECK(a.sorted() == b.sorted());
          }
          CHECK(knnGridRadius2(a.search) == knnGridRadius2(b.search));
          unfinished += !a.search.done;
          ++compared;
          boxesRead |= a.search.boxesRead;
        }
  CHECK(compared == 32 * 4 * 4 * 6);
  CHECK(unfinished > 100);  // limited budgets did stop searches midway
  CHECK(boxesRead == (kReadShortSearch | kReadAcceptedCube | kReadBeyondCube));
}

TEST_CASE("The estimate's runs of photons summed eight at a time equal one photon at a time", "[photonmap][knn]") {
  // photon_columns.h: the lanes must accept the photons examinePhotons accepts, grow the radius to
  // the same bits and subtract the same farthest photon; only the order of the power sums differs.
  // Photons come from random directions and lie on surfaces facing random ways (so both tests of
  // photonLights matter), and a third of them repeat an
  // earlier photon's position with another power and direction, so that the farthest distance is
  // often shared and the tie goes to the first photon in search order.
  Rng rng(77);
  std::vector<Photon> photons = photonCloud(3000, Cloud::Clustered, 31);
  for (uint32_t i = 0; i < photons.size(); ++i) {
    randomizeSides(photons[i], rng);
    if (i > 0 && rng.below(3) == 0) photons[i].position = photons[rng.below(i)].position;
  }
  GridOptions fine, coarse;
  fine.cellSize = 0.08f;
  coarse.photonsPerCell = 40;
  uint64_t ties = 0, runs = 0, glossyRuns = 0;
  uint8_t boxesRead = 0;
  for (const GridOptions& options : {fine, coarse}) {
    const SortedGrid sorted = buildSortedGrid(photons, options);
    const StencilGrid stencil = buildStencilGrid(photons, options);
    auto compare = [&](const auto& map, Vec3 p, Vec3 n, uint32_t k, float maxRadius, uint32_t shells) {
      EstimatePoint q;
      q.position = p;
      q.frame = Frame(n);
      q.facingNormal = n;
      q.bsdf = LambertianLobe{Rgb(0.5f)};
      estimate_detail::Accumulator one(q), eight(q);
      KnnGridSearch a = beginKnnGrid(p, k, maxRadius), b = a;
      advanceKnnGrid(map, a, shells, [&](uint32_t, const Photon& photon, float d2) { one.add(photon, d2); });
      estimate_detail::GridVisitor lanes{eight, {}};
      advanceKnnGrid(map, b, shells, lanes);
      CHECK(eight.used == 0);  // every run went through the lanes, none photon by photon
      lanes.finish();
      INFO("k = " << k << ", max radius " << maxRadius << ", shells " << shells);
      REQUIRE(b.found == a.found);
      REQUIRE(b.radius2 == a.radius2);
      CHECK(b.photonsExamined == a.photonsExamined);
      CHECK(b.shells == a.shells);
      CHECK(b.done == a.done);
      CHECK(eight.used == one.used);
      CHECK(eight.farthestD2 == one.farthestD2);
      CHECK((eight.farthest == one.farthest));
      // Positive terms summed in two orders: each sum is within (n - 1) 2^-24 of the exact one.
      const float tolerance = 2.0f * float(a.found) * 0x1p-24f;
      for (int c = 0; c < 3; ++c) CHECK(std::abs(eight.sum[c] - one.sum[c]) <= tolerance * one.sum[c]);
      ties += one.farthestD2 >= 0 && std::count_if(photons.begin(), photons.end(), [&](const Photon& ph) {
                                       return distance2(ph.position, p) == one.farthestD2;
                                     }) > 1;
      runs += b.cellsVisited;
      boxesRead |= b.boxesRead;
      if (shells != UINT32_MAX) return;
      // A glossy surface's photons need the BRDF each: the visitor declines the runs, and the
      // estimate is that of one photon at a time, to the bit.
      EstimatePoint glossy = q;
      glossy.bsdf = PhongLobe{Rgb(0.2f), Rgb(0.5f), 30};
      glossy.woLocal = normalize(Vec3{0.3f, -0.2f, 1.0f});
      estimate_detail::Accumulator glossyOne(glossy), glossyVisited(glossy);
      KnnGridSearch c = beginKnnGrid(p, k, maxRadius), d = c;
      advanceKnnGrid(map, c, shells, [&](uint32_t, const Photon& photon, float d2) { glossyOne.add(photon, d2); });
      estimate_detail::GridVisitor glossyLanes{glossyVisited, {}};
      advanceKnnGrid(map, d, shells, glossyLanes);
      glossyLanes.finish();
      CHECK((glossyVisited.sum == glossyOne.sum));
      CHECK(glossyVisited.used == glossyOne.used);
      glossyRuns += glossyOne.used > 0;
    };
    for (Vec3 p : queryPoints(photons, 40, 9)) {
      const Vec3 n = sampleUniformSphere(rng.uniform2());
      for (uint32_t k : {1u, 7u, 8u, 9u, 33u, 200u, 5000u})
        for (float maxRadius : {0.08f, 0.4f, 4.0f})
          for (uint32_t shells : {1u, 2u, UINT32_MAX}) {
            compare(sorted, p, n, k, maxRadius, shells);
            compare(stencil, p, n, k, maxRadius, shells);
          }
    }
  }
  CHECK(ties > 100);
  CHECK(runs > 10000);
  CHECK(glossyRuns > 100);
  CHECK(boxesRead == (kReadShortSearch | kReadAcceptedCube | kReadBeyondCube));
}

TEST_CASE("A sphere's sum does not depend on the runs that hold its photons", "[photonmap][knn]") {
  // sumWithinRadius sums entry i in lane i mod 8: the same photons read as one run, as runs split
  // anywhere, or with runs of rejected photons between, give the same bits.
  Rng rng(3);
  std::vector<Photon> photons = photonCloud(2000, Cloud::Uniform, 8);
  for (Photon& photon : photons) randomizeSides(photon, rng);
  size_t accepted = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 q = photons[rng.below(2000)].position, n = sampleUniformSphere(rng.uniform2());
    const float r2 = 0.05f + 0.3f * rng.uniform();
    // Only entries [100, 1900) lie within the sphere (the others are pushed away below).
    std::vector<Photon> moved = photons;
    for (uint32_t i = 0; i < 2000; ++i)
      if (i < 100 || i >= 1900) moved[i].position = q + Vec3(10, 0, 0);
    const PhotonColumns c = photonColumns(moved);
    const ColumnRun whole{0, 2000}, inner{100, 1800};
    const SphereSum reference = sumWithinRadius(c, {&whole, 1}, q, {n, n}, r2);
    std::vector<ColumnRun> split;
    for (uint32_t at = 100; at < 1900;) {
      const uint32_t length = std::min<uint32_t>(1900 - at, 1 + rng.below(40));
      split.push_back({at, length});
      at += length;
    }
    for (const auto& runs : {std::vector<ColumnRun>{inner}, split}) {
      const SphereSum sum = sumWithinRadius(c, runs, q, {n, n}, r2);
      CHECK((sum.sum == reference.sum));
      CHECK(sum.found == reference.found);
      CHECK(sum.used == reference.used);
      CHECK(sum.farthestD2 == reference.farthestD2);
    }
    accepted += reference.found;
  }
  CHECK(accepted > 10000);
}

TEST_CASE("Estimates taken cell by cell equal one search per point", "[photonmap][knn]") {
  // estimate_by_cell.h: a cell's queries share its shells. Every point's estimate must be its own
  // search's (the same photons, radius and left-out farthest photon; the sums in another order) on
  // the sorted and stencil grids, fine and coarse, for dense and sparse cells, maximum radii that
  // cut into a cell's first k photons, fewer than k photons within reach, points outside the
  // grid and glossy points; and must not depend on which other points share the cell.
  Rng rng(5);
  std::vector<Photon> photons = photonCloud(3000, Cloud::Clustered, 41);
  for (Photon& photon : photons) randomizeSides(photon, rng);
  // Several points per cell: each query point and jittered copies of it.
  std::vector<ShadingPoint> points;
  for (Vec3 p : queryPoints(photons, 120, 13))
    for (int copy = 0; copy < 4; ++copy) {
      ShadingPoint sp{};
      sp.position = p + (copy == 0 ? Vec3() : 0.03f * Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f));
      sp.normal = sampleUniformSphere(rng.uniform2());
      sp.geometricNormal = sp.normal;
      sp.wo = sp.normal;
      sp.bsdf = LambertianLobe{Rgb(0.5f, 0.4f, 0.3f)};
      if (points.size() % 7 == 3) sp.bsdf = PhongLobe{Rgb(0.5f, 0.4f, 0.3f), Rgb(0.4f), 20};
      sp.pixel = uint32_t(points.size());
      points.push_back(sp);
    }
  GridOptions fine, coarse, boxes;
  fine.cellSize = 0.05f;
  coarse.photonsPerCell = 40;
  boxes.resolution = {40, 3, 25};  // cells of three shapes, as the paper's 250 x 1 x 250
  size_t compared = 0, lit = 0;
  auto check = [&](const auto& map, uint32_t k, float maxRadius) {
    const EstimateSettings settings{k, maxRadius, 0};
    std::vector<Rgb> byCell(points.size());
    tbb::enumerable_thread_specific<EstimateCounters> counters;
    estimateAtPoints(&map, std::span<const ShadingPoint>(points), settings, std::span<Rgb>(byCell), counters);
    EstimateCounters total;
    for (const EstimateCounters& c : counters) total += c;
    CHECK(total.queries == points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const EstimatePoint q = estimatePoint(points[i]);
      EstimateCounters one;
      const Rgb searched = estimateRadiance(map, q, settings, nullptr, one);
      INFO("k " << k << ", max radius " << maxRadius << ", point " << i);
      if (!q.bsdf.onlyDiffuse()) {
        CHECK((byCell[i] == searched));  // searched on its own
        continue;
      }
      // The same photons summed in two orders: each sum of n positive terms is within (n - 1)
      // 2^-24 of the exact one; the farthest photon's share, left out of both, is the same.
      estimate_detail::Accumulator acc(q);
      const KnnGridSearch search = knnGrid(map, q.position, k, maxRadius, [&](uint32_t, const Photon& p, float d2) { acc.add(p, d2); });
      const float radius2 = knnGridRadius2(search);
      if (!(radius2 > 0)) {  // a point on its nearest photon, k = 1: no disc, no estimate
        CHECK((byCell[i] == Rgb() && searched == Rgb()));
        continue;
      }
      const float scale = float(q.bsdf.diffuse().maxComponent() * kInvPi / (kPi * radius2));
      for (int c = 0; c < 3; ++c)
        CHECK(std::abs(byCell[i][c] - searched[c]) <= 2.0f * float(search.found) * 0x1p-24f * acc.sum[c] * scale + 1e-30f);
      ++compared;
      lit += searched.maxComponent() > 0;
    }
    // The estimate of a point does not depend on the others in its cell: every other point alone.
    std::vector<ShadingPoint> half;
    for (size_t i = 0; i < points.size(); i += 2) half.push_back(points[i]);
    std::vector<Rgb> halfOut(half.size());
    estimateAtPoints(&map, std::span<const ShadingPoint>(half), settings, std::span<Rgb>(halfOut), counters);
    for (size_t i = 0; i < half.size(); ++i) CHECK((halfOut[i] == byCell[2 * i]));
  };
  for (const GridOptions& options : {fine, coarse, boxes}) {
    const SortedGrid sorted = buildSortedGrid(photons, options);
    const StencilGrid stencil = buildStencilGrid(photons, options);
    for (uint32_t k : {1u, 9u, 64u, 5000u})
      for (float maxRadius : {0.06f, 0.3f, 4.0f, 1e10f}) {  // the last beyond any cell count
        check(sorted, k, maxRadius);
        check(stencil, k, maxRadius);
      }
  }
  CHECK(lit > compared / 2);
}

TEST_CASE("kNN-grid and kd-tree agree on a cloud with one photon and on an empty one", "[photonmap][knn]") {
  for (uint32_t n : {0u, 1u}) {
    const std::vector<Photon> photons = photonCloud(n, Cloud::Uniform, 1);
    const SortedGrid sorted = buildSortedGrid(photons);
    const HashedGrid hashed = buildHashedGrid(photons);
    const StencilGrid stencil = buildStencilGrid(photons);
    const PhotonKdTree tree = buildPhotonKdTree(photons);
    PhotonDistance heap[4];
    for (Vec3 p : {Vec3(0.0f), Vec3(5.0f)}) {
      const KdTreeResult kd = kdTreeNearest(tree, p, 4, 100.0f, heap);
      const GridResult a = gridQuery(sorted, p, 4, 100.0f), b = gridQuery(hashed, p, 4, 100.0f),
                       c = gridQuery(stencil, p, 4, 100.0f);
      CHECK(kd.found == n);
      CHECK(a.ids.size() == n);
      CHECK(b.ids == a.ids);
      CHECK(c.ids == a.ids);
      CHECK(knnGridRadius2(a.search) == kd.radius2);
    }
  }
}

TEST_CASE("Progressive kNN-grid: shell by shell to the full search", "[photonmap][knn]") {
  const std::vector<Photon> photons = photonCloud(5000, Cloud::Clustered, 13);
  GridOptions options;
  options.cellSize = 0.05f;
  const SortedGrid map = buildSortedGrid(photons, options);
  uint32_t maxShells = 0;
  for (Vec3 p : queryPoints(photons, 40, 2)) {
    for (uint32_t k : {8u, 100u}) {
      const GridResult full = gridQuery(map, p, k, 1.0f);
      GridResult step;
      step.search = beginKnnGrid(p, k, 1.0f);
      auto visit = [&](uint32_t id, const Photon&, float) { step.ids.push_back(id); };
      advanceKnnGrid(map, step.search, 0, visit);  // 0 shells: nothing explored
      CHECK(step.ids.empty());
      CHECK(step.search.found == 0);
      CHECK(step.search.radius2 == 0);
      CHECK_FALSE(step.search.done);
      advanceKnnGrid(map, step.search, 1, visit);  // 1 shell: the query's cell only
      const CellCoord cell = map.grid.cellOf(p);
      for (uint32_t id : step.ids) {
        const CellCoord c = map.grid.cellOf(photons[id].position);
        CHECK((c.x == cell.x && c.y == cell.y && c.z == cell.z));
      }
      float lastRadius2 = step.search.radius2;
      while (!step.search.done) {
        advanceKnnGrid(map, step.search, 1, visit);
        CHECK(step.search.radius2 >= lastRadius2);  // the running radius only grows
        lastRadius2 = step.search.radius2;
      }
      // The whole search may settle a search short of k as one run (exploreShortSearch), take its
      // first shells as one box (acceptedCube) and its last ones as rows (exploreBeyondCube): the
      // same photons, in another order. These count every shell of the reach box, which reaches
      // one cell beyond the sphere's cells, where shell by shell stops at the last with photons.
      CHECK(step.sorted() == full.sorted());
      CHECK(step.search.radius2 == full.search.radius2);
      CHECK(step.search.shells <= full.search.shells);
      advanceKnnGrid(map, step.search, 5, visit);  // a finished search stays finished
      CHECK(step.sorted() == full.sorted());
      maxShells = std::max(maxShells, full.search.shells);
    }
  }
  CHECK(maxShells > 2);  // the test did explore several shells
}

TEST_CASE("Stencil routing stores the first m^2 arrivals and conserves every cell's power",
          "[photonmap][stencil]") {
  for (PowerRedistribution mode : {PowerRedistribution::Count, PowerRedistribution::Power}) {
    // The paper's count ratio conserves power for photons of equal power, as it assumes.
    const bool equalPower = mode == PowerRedistribution::Count;
    const std::vector<Photon> photons = photonCloud(20000, Cloud::Clustered, 17, equalPower);
    GridOptions options;
    options.stencilSide = 4;  // 16 per cell: dense blobs overflow
    options.photonsPerCell = 16;
    options.redistribution = mode;
    StencilGrid maps[2];
    for (int threads : {1, 2}) {
      ParallelScope scope(threads);
      maps[threads - 1] = buildStencilGrid(photons, options);
    }
    const StencilGrid& map = maps[0];
    CHECK(maps[1].slots == map.slots);
    CHECK(std::memcmp(maps[1].photons.data(), map.photons.data(), photons.size() * sizeof(Photon)) == 0);

    std::vector<std::vector<uint32_t>> arrivals(map.grid.cellCount());
    for (uint32_t i = 0; i < photons.size(); ++i) arrivals[map.grid.cellIndex(map.grid.cellOf(photons[i].position))].push_back(i);
    uint32_t overflowing = 0;
    for (uint32_t c = 0; c < arrivals.size(); ++c) {
      const std::vector<uint32_t>& in = arrivals[c];
      REQUIRE(map.arrived[c] == in.size());
      const uint32_t stored = std::min<uint32_t>(uint32_t(in.size()), map.capacity());
      REQUIRE(map.stored(c) == stored);
      const uint32_t* slots = map.slots.data() + size_t(c) * map.capacity();
      double arrivedPower[3] = {0, 0, 0}, storedPower[3] = {0, 0, 0};
      for (uint32_t i = 0; i < in.size(); ++i)
        for (int ch = 0; ch < 3; ++ch) arrivedPower[ch] += photons[in[i]].power[ch];
      for (uint32_t s = 0; s < map.capacity(); ++s) {
        if (s < stored) {
          REQUIRE(slots[s] == in[s]);  // the first arrivals, in arrival order
          for (int ch = 0; ch < 3; ++ch) storedPower[ch] += map.photons[slots[s]].power[ch];
        } else {
          REQUIRE(slots[s] == StencilGrid::kEmptySlot);
        }
      }
      for (int ch = 0; ch < 3; ++ch) REQUIRE(storedPower[ch] == Approx(arrivedPower[ch]).epsilon(1e-5));
      overflowing += in.size() > stored;
    }
    CHECK(overflowing > 10);
    // Photons that were dropped keep their power; they are in no footprint.
    uint64_t storedTotal = 0;
    for (uint32_t c = 0; c < arrivals.size(); ++c) storedTotal += map.stored(c);
    CHECK(storedTotal < photons.size());
  }
}

TEST_CASE("Grid maps do not depend on the thread count", "[photonmap][grid][determinism]") {
  const std::vector<Photon> photons = photonCloud(30000, Cloud::Clustered, 5);
  SortedGrid sorted[2];
  HashedGrid hashed[2];
  for (int threads : {1, 2}) {
    ParallelScope scope(threads);
    sorted[threads - 1] = buildSortedGrid(photons);
    hashed[threads - 1] = buildHashedGrid(photons);
  }
  CHECK(sorted[0].photonList == sorted[1].photonList);
  CHECK(sorted[0].firstPhoton == sorted[1].firstPhoton);
  CHECK(hashed[0].photonList == hashed[1].photonList);
  CHECK(hashed[0].firstPhoton == hashed[1].firstPhoton);
  CHECK(hashed[0].cellKeys == hashed[1].cellKeys);
}

TEST_CASE("Cell count table counts the photons of any box of cells", "[photonmap][grid]") {
  GridOptions options;
  options.resolution = {9, 4, 7};
  const SortedGrid map = buildSortedGrid(photonCloud(2000, Cloud::Clustered, 5), options);
  const auto& res = map.grid.res;
  Rng rng(3);
  for (int trial = 0; trial < 500; ++trial) {
    int32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const auto u = int32_t(rng.next() % uint32_t(res[a])), v = int32_t(rng.next() % uint32_t(res[a]));
      lo[a] = std::min(u, v), hi[a] = std::max(u, v);
    }
    uint32_t brute = 0;
    for (int32_t z = lo[2]; z <= hi[2]; ++z)
      for (int32_t y = lo[1]; y <= hi[1]; ++y)
        for (int32_t x = lo[0]; x <= hi[0]; ++x) brute += map.cellPhotons({x, y, z}).count;
    REQUIRE(map.cellCounts.count(lo, hi) == brute);
  }
  const int32_t all[3] = {res[0] - 1, res[1] - 1, res[2] - 1}, origin[3] = {0, 0, 0}, empty[3] = {1, 0, 0};
  CHECK(map.cellCounts.count(origin, all) == 2000);
  CHECK(map.cellCounts.count(empty, origin) == 0);
}

TEST_CASE("kNN-grid skips the empty cells of a sparse map", "[photonmap][knn]") {
  // Two photons at opposite corners of a fine grid: a query at one corner finds its photon, and the
  // search over the empty cells out to the maximum radius costs no cell visits.
  std::vector<Photon> photons(2);
  photons[0].position = {0, 0, 0};
  photons[1].position = {1, 1, 1};
  GridOptions options;
  options.resolution = {200, 200, 200};
  const SortedGrid map = buildSortedGrid(photons, options);
  const KnnGridSearch s = knnGrid(map, {0.001f, 0.001f, 0.001f}, 4, 0.9f, [](uint32_t, const Photon&, float) {});
  CHECK(s.found == 1);
  CHECK(s.done);
  CHECK(s.cellsVisited <= 1);
  CHECK(knnGridRadius2(s) == Approx(0.81f));
}
