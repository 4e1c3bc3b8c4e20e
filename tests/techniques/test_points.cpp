// The point hierarchy (Ritschel et al. 2009, 2.1 and 3.1): heap numbering and stackless traversal,
// best-candidate sampling (area-proportional, better spaced than uniform, deterministic), the median
// split, bounding spheres and normal cones of float and packed nodes, the packed nodes' error, refit
// against rebuild, the radiance pull, half floats and the sampler's radix sort.
#include <catch2/catch.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include "chi2.h"
#include "lucent/core/morton.h"
#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/surface.h"
#include "lucent/techniques/points/point_hierarchy.h"
#include "lucent/techniques/points/point_radiance.h"
#include "techniques/points/radix_sort.h"
#include "test_scenes.h"

using namespace lucent;

namespace {

const Scene& cornellBox() {
  static const Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + "/scenes/cornell-box.json", LoadOptions(true));
  return scene;
}

// A flat square [0, side]^2 at y = 0 facing up, as two triangles.
Scene planeScene(float side) {
  Scene scene;
  Material m;
  m.kd = Rgb(0.5f);
  test::addMaterial(scene, m, "plane");
  scene.positions = {{0, 0, 0}, {side, 0, 0}, {side, 0, side}, {0, 0, side}};
  scene.normals.assign(4, {0, 0, 0});
  scene.texcoords = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  scene.indices = {0, 2, 1, 0, 3, 2};
  scene.materialIds = {0, 0};
  finalizeScene(scene);
  return scene;
}

// Triangles of widely varying area, scattered and tilted (no two share a plane), so that per-triangle
// counts test the sampler rather than the geometry.
Scene scatteredTriangles(uint32_t count, uint64_t seed) {
  Scene scene;
  Material m;
  test::addMaterial(scene, m, "white");
  Rng rng(seed);
  for (uint32_t t = 0; t < count; ++t) {
    const Vec3 o{rng.uniform() * 100, rng.uniform() * 100, rng.uniform() * 100};
    const float size = 1 + 15 * rng.uniform() * rng.uniform();
    for (int k = 0; k < 3; ++k) {
      scene.positions.push_back(o + Vec3{rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f} * size);
      scene.normals.push_back({0, 0, 0});
      scene.texcoords.push_back({0, 0});
      scene.indices.push_back(3 * t + k);
    }
    scene.materialIds.push_back(0);
  }
  finalizeScene(scene);
  return scene;
}

// A triangle's area in double, for the current vertex positions.
double triangleAreaD(const Scene& scene, uint32_t t) {
  const Vec3 a = scene.vertex(t, 0), b = scene.vertex(t, 1), c = scene.vertex(t, 2);
  const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
  const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
  const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
  return 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
}

double totalArea(const Scene& scene) {
  double a = 0;
  for (float f : scene.faceAreas) a += f;
  return a;
}

std::vector<Vec3> positionsOf(const Scene& scene, const std::vector<PointSample>& points) {
  std::vector<Vec3> p;
  for (const PointSample& s : points) p.push_back(pointPosition(scene, s));
  return p;
}

// Nearest-neighbour distance of every point, brute force.
std::vector<double> nearestDistances(const std::vector<Vec3>& p) {
  std::vector<double> nn(p.size(), 1e30);
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j) {
      const double d = length(p[i] - p[j]);
      nn[i] = std::min(nn[i], d);
      nn[j] = std::min(nn[j], d);
    }
  return nn;
}

// Pearson's chi-square of per-triangle counts against area-proportional expectations.
chi2::Result triangleChi2(const Scene& scene, const std::vector<PointSample>& points) {
  std::vector<double> observed(scene.triangleCount(), 0.0), expected(scene.triangleCount());
  for (const PointSample& s : points) observed[s.triangle] += 1;
  const double area = totalArea(scene);
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) expected[t] = points.size() * scene.faceAreas[t] / area;
  chi2::Result result;
  chi2::pooledChi2(observed, expected, 5, result);
  return result;
}

// Containment checked in double, without tolerance: the merges and the packing are conservative.
bool sphereContains(const Sphere& outer, const Sphere& inner) {
  const double dx = double(outer.center.x) - inner.center.x, dy = double(outer.center.y) - inner.center.y,
               dz = double(outer.center.z) - inner.center.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz) + inner.radius <= outer.radius;
}
double angleD(Vec3 a, Vec3 b) {
  const double cx = double(a.y) * b.z - double(a.z) * b.y, cy = double(a.z) * b.x - double(a.x) * b.z,
               cz = double(a.x) * b.y - double(a.y) * b.x;
  const double la = std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z);
  const double lb = std::sqrt(double(b.x) * b.x + double(b.y) * b.y + double(b.z) * b.z);
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz) / (la * lb),
                    (double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z) / (la * lb));
}
bool coneContains(const NormalCone& outer, const NormalCone& inner) {
  return outer.angle >= kPi || angleD(outer.axis, inner.axis) + inner.angle <= outer.angle;
}

PointHierarchyOptions hierarchyOptions(uint32_t n, NodeEncoding encoding = NodeEncoding::Packed) {
  PointHierarchyOptions o;
  o.pointCount = n;
  o.encoding = encoding;
  return o;
}

}  // namespace

TEST_CASE("Heap numbering: children, levels and the leaves' points", "[points]") {
  STATIC_REQUIRE(firstChild(kRootNode) == 2);
  STATIC_REQUIRE(secondChild(kRootNode) == 3);
  STATIC_REQUIRE(parentNode(7) == 3);
  STATIC_REQUIRE(nodeLevel(1) == 0 && nodeLevel(2) == 1 && nodeLevel(3) == 1 && nodeLevel(8) == 3);
  // n = 8: node 5 (level 2) covers points 2..3; leaf 13 is point 5.
  STATIC_REQUIRE(leavesBelow(5, 8) == 2 && firstLeafPoint(5, 8) == 2);
  STATIC_REQUIRE(leavesBelow(13, 8) == 1 && firstLeafPoint(13, 8) == 5);
  STATIC_REQUIRE(firstLeafPoint(kRootNode, 8) == 0 && leavesBelow(kRootNode, 8) == 8);
  STATIC_REQUIRE(isLeafNode(8, 8) && !isLeafNode(7, 8));
}


TEST_CASE("Stackless traversal: skip pointers give depth-first order without a stack", "[points]") {
  for (uint32_t n = 1; n <= 1024; n *= 2) {
    // The recursive depth-first order to compare with.
    std::vector<uint32_t> expected;
    std::function<void(uint32_t)> dfs = [&](uint32_t i) {
      expected.push_back(i);
      if (!isLeafNode(i, n)) dfs(firstChild(i)), dfs(secondChild(i));
    };
    dfs(kRootNode);
    REQUIRE(expected.size() == 2 * n - 1);

    std::vector<uint32_t> visited;
    for (uint32_t i = kRootNode; i != kTraversalEnd; i = nextNodeDescending(i, n)) {
      visited.push_back(i);
      REQUIRE(visited.size() < 2 * n);  // no cycles
    }
    CHECK(visited == expected);

    // Cutting: refine only nodes whose index is not divisible by 3; a cut subtree is skipped whole.
    std::vector<uint32_t> cutExpected;
    std::function<void(uint32_t)> cutDfs = [&](uint32_t i) {
      cutExpected.push_back(i);
      if (!isLeafNode(i, n) && i % 3 != 0) cutDfs(firstChild(i)), cutDfs(secondChild(i));
    };
    cutDfs(kRootNode);
    std::vector<uint32_t> cut;
    for (uint32_t i = kRootNode; i != kTraversalEnd;) {
      cut.push_back(i);
      i = (!isLeafNode(i, n) && i % 3 != 0) ? firstChild(i) : nextNodeSkippingSubtree(i);
    }
    CHECK(cut == cutExpected);
  }
  // The last subtree at every level ends the traversal.
  CHECK(nextNodeSkippingSubtree(kRootNode) == kTraversalEnd);
  CHECK(nextNodeSkippingSubtree(3) == kTraversalEnd);
  CHECK(nextNodeSkippingSubtree(15) == kTraversalEnd);
  CHECK(nextNodeSkippingSubtree(2) == 3);
  CHECK(nextNodeSkippingSubtree(5) == 3);
  CHECK(nextNodeSkippingSubtree(11) == 3);
  CHECK(nextNodeSkippingSubtree(9) == 5);
}


TEST_CASE("Sphere and cone merges: known answers, opposite normals, containment", "[points]") {
  const Sphere a{{0, 0, 0}, 1}, b{{4, 0, 0}, 1};
  const Sphere ab = mergeSpheres(a, b);
  CHECK(ab.center.x == Approx(2));
  CHECK(ab.radius == Approx(3));
  CHECK(mergeSpheres(a, {{0.5f, 0, 0}, 0.25f}).radius == Approx(1));  // containment keeps the outer
  const NormalCone up{{0, 1, 0}, 0}, side{{1, 0, 0}, 0}, down{{0, -1, 0}, 0};
  const NormalCone us = mergeCones(up, side);
  CHECK(us.angle == Approx(kPi / 4).margin(1e-5));
  CHECK(angleBetween(us.axis, normalize(Vec3{1, 1, 0})) < 1e-5f);
  CHECK(mergeCones(up, down).angle >= kPi);  // opposite normals: any direction
  CHECK(mergeCones({{0, 1, 0}, 0.5f}, {{0, -1, 0}, 0.5f}).angle >= kPi);
  CHECK(mergeCones({{0, 1, 0}, 2.5f}, {{1, 0, 0}, 2.5f}).angle >= kPi);  // together more than a sphere
  const NormalCone wide = mergeCones({{0, 1, 0}, 0.5f}, {{1, 0, 0}, 0.25f});
  CHECK(wide.angle == Approx((kPi / 2 + 0.75f) / 2).margin(1e-5));

  // Random pairs: the merge contains both (in double, no tolerance) and is within rounding of the
  // smallest that does, max(r0, r1, (d + r0 + r1) / 2) and likewise for angles.
  Rng rng(17);
  for (int i = 0; i < 20000; ++i) {
    Sphere s[2];
    NormalCone c[2];
    for (Sphere& x : s) x = {{rng.uniform() * 200 - 100, rng.uniform() * 200 - 100, rng.uniform() * 2}, rng.uniform() * 30};
    for (NormalCone& x : c) x = {sampleUniformSphere(rng.uniform2()), rng.uniform() * rng.uniform() * 2};
    const Sphere m = mergeSpheres(s[0], s[1]);
    REQUIRE(sphereContains(m, s[0]));
    REQUIRE(sphereContains(m, s[1]));
    const double d = length(s[1].center - s[0].center);
    const double smallest = std::max({double(s[0].radius), double(s[1].radius), 0.5 * (d + s[0].radius + s[1].radius)});
    REQUIRE(m.radius <= smallest * (1 + 1e-5) + 1e-5);
    const NormalCone k = mergeCones(c[0], c[1]);
    REQUIRE(coneContains(k, c[0]));
    REQUIRE(coneContains(k, c[1]));
    const double phi = angleD(c[0].axis, c[1].axis);
    const double narrowest = std::min(double(kPi), std::max({double(c[0].angle), double(c[1].angle),
                                                             0.5 * (phi + c[0].angle + c[1].angle)}));
    REQUIRE(k.angle <= narrowest + 1e-4);
  }
}


TEST_CASE("Packed node encoding is conservative: decoded spheres and cones contain the originals", "[points]") {
  NodeQuantization q;
  q.origin = {-100, -50, 0};
  q.step = Vec3{200, 100, 10} / 65535.0f;
  q.radiusStep = 150 / 65535.0f;
  Rng rng(23);
  double worstAxis = 0, worstAlbedo = 0;
  for (int i = 0; i < 20000; ++i) {
    const Sphere s{{rng.uniform() * 200 - 100, rng.uniform() * 100 - 50, rng.uniform() * 10},
                   rng.uniform() < 0.5f ? rng.uniform() * 0.01f : rng.uniform() * 100};
    const NormalCone c{sampleUniformSphere(rng.uniform2()), rng.uniform() < 0.3f ? 0.0f : rng.uniform() * 3.3f};
    const Rgb albedo{rng.uniform(), rng.uniform() * rng.uniform(), 1.0f};
    const PackedNode p = encodeNode(s, c, albedo, q);
    const FloatNode f = decodeNode(p, q);
    REQUIRE(sphereContains(f.sphere, s));
    REQUIRE(f.sphere.radius <= s.radius + length(f.sphere.center - s.center) + 1.01f * q.radiusStep + 1e-5f * s.radius);
    REQUIRE(coneContains(f.cone, c));
    if (c.angle < kPi) worstAxis = std::max(worstAxis, angleD(f.cone.axis, c.axis));
    for (int k = 0; k < 3; ++k) worstAlbedo = std::max(worstAlbedo, double(std::abs(f.albedo[k] - albedo[k])));
    REQUIRE((p.coneFree >> 8) == 0);        // the free bits stay free
    REQUIRE((p.normalAlbedo >> 30) == 0);
  }
  // 5-bit lattice directions are within 3 degrees of any normal; square-root albedo within 0.032.
  CHECK(worstAxis * 180 / kPi < 3.0);
  CHECK(worstAlbedo < 0.032);
  CHECK(decodeNormal(encodeNode({}, {{0, -1, 0}, 0}, {}, q)) == Vec3(0, -1, 0));  // axis-aligned: exact
  CHECK(decodeConeAngle(encodeNode({}, {{0, 0, 1}, 0}, {}, q)) == 0);
  CHECK_THROWS_AS(encodeNode({{0, 0, 0}, 1e6f}, {}, {}, q), std::logic_error);
}


TEST_CASE("Radix sort: stable by key, as std::stable_sort", "[points]") {
  for (uint32_t bits : {1u, 11u, 23u, 40u, 64u}) {
    Rng rng(bits);
    const size_t n = 200000;
    std::vector<uint64_t> keys(n), keyScratch;
    std::vector<uint32_t> values(n), valueScratch;
    for (size_t i = 0; i < n; ++i) {
      // Few distinct keys for the stability check, all bits set for the mask check.
      const uint64_t k = (uint64_t(rng.next()) << 32 | rng.next()) % 5000;
      keys[i] = bits == 64 ? k * 0x9e3779b97f4a7c15ull : k & ((uint64_t(1) << bits) - 1);
      values[i] = uint32_t(i);
    }
    std::vector<std::pair<uint64_t, uint32_t>> expected(n);
    for (size_t i = 0; i < n; ++i) expected[i] = {keys[i], values[i]};
    std::stable_sort(expected.begin(), expected.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    points::radixSortByKey(keys, values, bits, keyScratch, valueScratch);
    uint32_t wrong = 0;
    for (size_t i = 0; i < n; ++i) wrong += keys[i] != expected[i].first || values[i] != expected[i].second;
    CHECK(wrong == 0);
  }
}

TEST_CASE("Point sampling: valid triangles and barycentrics, emitters included, bad input rejected", "[points]") {
  const Scene& scene = cornellBox();
  const std::vector<PointSample> points = samplePoints(scene, 1u << 12);
  REQUIRE(points.size() == 4096);
  uint32_t onEmitters = 0;
  for (const PointSample& s : points) {
    REQUIRE(s.triangle < scene.triangleCount());
    REQUIRE(s.b1 >= 0);
    REQUIRE(s.b2 >= 0);
    REQUIRE(s.b1 + s.b2 <= 1);
    onEmitters += scene.triangleLight[s.triangle] >= 0;
  }
  // The light is 0.8 below the ceiling: it gets its area's share all the same (about 29 points).
  double lightArea = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t)
    if (scene.triangleLight[t] >= 0) lightArea += scene.faceAreas[t];
  const double expectedOnLight = 4096 * lightArea / totalArea(scene);
  CHECK(std::abs(onEmitters - expectedOnLight) < 4 * std::sqrt(expectedOnLight));

  CHECK_THROWS_AS(samplePoints(scene, 0), std::invalid_argument);
  CHECK_THROWS_AS(samplePoints(scene, (1u << 26) + 1), std::invalid_argument);
  PointSamplingOptions bad;
  bad.candidates = 0;
  CHECK_THROWS_AS(samplePoints(scene, 16, bad), std::invalid_argument);
  CHECK_THROWS_AS(samplePoints(Scene{}, 16), std::invalid_argument);
  CHECK_THROWS_AS(buildPointHierarchy(scene, hierarchyOptions(3000)), std::invalid_argument);
  // Every count works, the smallest too; one point is a tree whose root is its leaf.
  CHECK(samplePoints(scene, 1).size() == 1);
  CHECK(samplePoints(scene, 3).size() == 3);
  const PointHierarchy one = buildPointHierarchy(scene, hierarchyOptions(1));
  REQUIRE(one.nodeCount() == 2);
  CHECK(isLeafNode(kRootNode, one.leafCount));
  CHECK(sphereContains(decodeSphere(one.packedNodes[kRootNode], one.quantization), one.floatNodes[kRootNode].sphere));
  CHECK(nextNodeDescending(kRootNode, one.leafCount) == kTraversalEnd);
}


TEST_CASE("Point sampling is proportional to area: chi-square over triangles", "[points]") {
  // Three tests at 1% overall.
  const double significance = chi2::sidak(0.01, 3);
  SECTION("Cornell box, with coincident and nearly coincident faces") {
    const chi2::Result r = triangleChi2(cornellBox(), samplePoints(cornellBox(), 1u << 14));
    INFO(r.summary());
    CHECK(r.passed(significance));
  }
  SECTION("scattered triangles of widely varying area") {
    const Scene scene = scatteredTriangles(400, 5);
    const chi2::Result r = triangleChi2(scene, samplePoints(scene, 1u << 14));
    INFO(r.summary());
    CHECK(r.passed(significance));
    // Best-candidate plays no part in the counts: plain uniform sampling passes as well.
    PointSamplingOptions uniform;
    uniform.candidates = 1;
    const chi2::Result u = triangleChi2(scene, samplePoints(scene, 1u << 14, uniform));
    INFO(u.summary());
    CHECK(u.passed(significance));
  }
  SECTION("low-discrepancy points: every triangle gets its area's share to within two points") {
    // The scrambled Sobol sequence's first coordinate is a (0, 1)-sequence: 2^14 points put one in
    // each interval of 2^-14, so a triangle whose share of the area distribution is p gets p n,
    // give or take a point at each end of its interval.
    const Scene scene = scatteredTriangles(400, 5);
    PointSamplingOptions ld;
    ld.method = PointSampling::LowDiscrepancy;
    const uint32_t n = 1u << 14;
    const std::vector<PointSample> points = samplePoints(scene, n, ld);
    std::vector<double> count(scene.triangleCount(), 0.0);
    for (const PointSample& p : points) {
      REQUIRE(p.b1 >= 0);
      REQUIRE(p.b2 >= 0);
      REQUIRE(p.b1 + p.b2 <= 1);
      count[p.triangle] += 1;
    }
    const double area = totalArea(scene);
    double worst = 0;
    for (uint32_t t = 0; t < scene.triangleCount(); ++t)
      worst = std::max(worst, std::abs(count[t] - n * scene.faceAreas[t] / area));
    INFO("largest departure from a triangle's share: " << worst << " points");
    CHECK(worst <= 2.0);
    // Independent random points depart by their Poisson noise: tens of points here.
    PointSamplingOptions uniform;
    uniform.candidates = 1;
    std::fill(count.begin(), count.end(), 0.0);
    for (const PointSample& p : samplePoints(scene, n, uniform)) count[p.triangle] += 1;
    double uniformWorst = 0;
    for (uint32_t t = 0; t < scene.triangleCount(); ++t)
      uniformWorst = std::max(uniformWorst, std::abs(count[t] - n * scene.faceAreas[t] / area));
    CHECK(uniformWorst > 5.0);
  }
  SECTION("negative control: points sampled by triangle count instead of area fail") {
    Scene wrong = scatteredTriangles(400, 5);
    const Scene right = wrong;
    std::fill(wrong.faceAreas.begin(), wrong.faceAreas.end(), 1.0f);
    const chi2::Result r = triangleChi2(right, samplePoints(wrong, 1u << 14));
    INFO(r.summary());
    CHECK(r.pValue < 1e-6);
  }
}


TEST_CASE("Best-candidate points are better spaced than uniform ones", "[points]") {
  const Scene scene = planeScene(100);
  const uint32_t n = 2048;
  const double s = std::sqrt(totalArea(scene) / n);  // mean spacing
  PointSamplingOptions uniform;
  uniform.candidates = 1;
  const std::vector<double> best = nearestDistances(positionsOf(scene, samplePoints(scene, n)));
  const std::vector<double> plain = nearestDistances(positionsOf(scene, samplePoints(scene, n, uniform)));
  const double bestMin = *std::min_element(best.begin(), best.end()) / s;
  const double plainMin = *std::min_element(plain.begin(), plain.end()) / s;
  double bestMean = 0, plainMean = 0;
  for (double d : best) bestMean += d / s / n;
  for (double d : plain) plainMean += d / s / n;
  INFO("nearest-neighbour distance / spacing: best-candidate min " << bestMin << " mean " << bestMean
                                                                    << "; uniform min " << plainMin << " mean " << plainMean);
  // Uniform points (a Poisson process of density 1 / s^2): nearest distance of mean 0.5 s and
  // standard deviation sqrt((4 - pi) / (4 pi)) s = 0.261 s, so the mean of n within 4.5 x 0.261 /
  // sqrt(n) = 0.026, plus the border's excess (a point on the border sees half the plane: 0.71 s
  // instead of 0.5 s, fading within about half a spacing; four borders of sqrt(n) s = 45 s: at most
  // 4 x 0.5 x 0.21 / 45 = 0.01). Best-candidate's mean lies 35 of those standard errors above 0.5.
  // Pairs closer than t s in a Poisson process are a Poisson count of mean n pi t^2 / 2, so its
  // smallest distance lies below 0.05 s with probability 0.9997 and above 0.15 s with e^-72.
  const double standardError = std::sqrt((4 - kPi) / (4 * kPi)) / std::sqrt(double(n));
  CHECK(std::abs(plainMean - 0.5) <= 4.5 * standardError + 0.01);
  CHECK(bestMean > 0.7);
  CHECK(bestMin > 0.15);
  CHECK(plainMin < 0.05);
}


TEST_CASE("Point sampling and the hierarchy are the same with 1 and 2 threads", "[points]") {
  const Scene& scene = cornellBox();
  PointHierarchy h[2];
  std::vector<PointSample> p[2];
  for (int t = 0; t < 2; ++t) {
    ParallelScope scope(t + 1);
    p[t] = samplePoints(scene, 1u << 15);
    h[t] = buildPointHierarchy(scene, hierarchyOptions(1u << 15));
  }
  REQUIRE(p[0].size() == p[1].size());
  CHECK(std::memcmp(p[0].data(), p[1].data(), p[0].size() * sizeof(PointSample)) == 0);
  CHECK(std::memcmp(h[0].points.data(), h[1].points.data(), h[0].points.size() * sizeof(PointSample)) == 0);
  CHECK(std::memcmp(h[0].floatNodes.data(), h[1].floatNodes.data(), h[0].floatNodes.size() * sizeof(FloatNode)) == 0);
  CHECK(std::memcmp(h[0].packedNodes.data(), h[1].packedNodes.data(), h[0].packedNodes.size() * sizeof(PackedNode)) == 0);
  // A different seed gives different points.
  PointSamplingOptions other;
  other.seed = 7;
  CHECK(std::memcmp(samplePoints(scene, 1u << 15, other).data(), p[0].data(), p[0].size() * sizeof(PointSample)) != 0);
}


TEST_CASE("Median split: each node's halves are split at the median of its largest extent", "[points]") {
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 12;
  const PointHierarchy h = buildPointHierarchy(scene, hierarchyOptions(n, NodeEncoding::Float));
  const std::vector<Vec3> p = positionsOf(scene, h.points);
  // The tree holds the sampled points, each once.
  std::vector<PointSample> sorted = h.points, sampled = samplePoints(scene, n);
  auto byBytes = [](const PointSample& a, const PointSample& b) { return std::memcmp(&a, &b, sizeof a) < 0; };
  std::sort(sorted.begin(), sorted.end(), byBytes);
  std::sort(sampled.begin(), sampled.end(), byBytes);
  CHECK(std::memcmp(sorted.data(), sampled.data(), n * sizeof(PointSample)) == 0);
  uint32_t violations = 0;
  for (uint32_t i = kRootNode; i < n; ++i) {
    const uint32_t first = firstLeafPoint(i, n), count = leavesBelow(i, n);
    Bounds3 box;
    for (uint32_t j = first; j < first + count; ++j) box.extend(p[j]);
    const Vec3 e = box.extent();
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    float leftMax = -kInf, rightMin = kInf;
    for (uint32_t j = first; j < first + count / 2; ++j) leftMax = std::max(leftMax, p[j][axis]);
    for (uint32_t j = first + count / 2; j < first + count; ++j) rightMin = std::min(rightMin, p[j][axis]);
    violations += leftMax > rightMin;
  }
  CHECK(violations == 0);
  // Without ties (the walls' points share coordinates, broken by input index) the order does not
  // depend on the input order.
  Rng rng(11);
  std::vector<Vec3> cloud(1024);
  for (Vec3& v : cloud) v = {rng.uniform(), rng.uniform() * 2, rng.uniform() * 0.5f};
  std::vector<Vec3> reversed(cloud.rbegin(), cloud.rend());
  const std::vector<uint32_t> a = medianSplitOrder(cloud), b = medianSplitOrder(reversed);
  uint32_t mismatches = 0;
  for (uint32_t j = 0; j < cloud.size(); ++j) mismatches += !(cloud[a[j]] == reversed[b[j]]);
  CHECK(mismatches == 0);
  CHECK_THROWS_AS(medianSplitOrder(std::span<const Vec3>(cloud).first(1000)), std::invalid_argument);
}


TEST_CASE("Node bounds: spheres contain their children's, cones their children's normals", "[points]") {
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 13;
  const PointHierarchy h = buildPointHierarchy(scene, hierarchyOptions(n));
  const NodeQuantization& q = h.quantization;
  uint32_t badFloatSphere = 0, badPackedSphere = 0, badFloatCone = 0, badPackedCone = 0, badArea = 0;
  for (uint32_t i = kRootNode; i < n; ++i) {
    for (uint32_t c : {firstChild(i), secondChild(i)}) {
      badFloatSphere += !sphereContains(h.floatNodes[i].sphere, h.floatNodes[c].sphere);
      badPackedSphere += !sphereContains(decodeSphere(h.packedNodes[i], q), decodeSphere(h.packedNodes[c], q));
      badFloatCone += !coneContains(h.floatNodes[i].cone, h.floatNodes[c].cone);
      const NormalCone packed{decodeNormal(h.packedNodes[i]), decodeConeAngle(h.packedNodes[i])};
      badPackedCone += !coneContains(packed, h.floatNodes[c].cone);
    }
    badArea += h.nodeAreas[i] != h.nodeAreas[firstChild(i)] + h.nodeAreas[secondChild(i)];
  }
  // Leaves: the packed disc contains the float disc, the packed cone the true normal.
  for (uint32_t i = n; i < 2 * n; ++i) {
    badPackedSphere += !sphereContains(decodeSphere(h.packedNodes[i], q), h.floatNodes[i].sphere);
    const NormalCone packed{decodeNormal(h.packedNodes[i]), decodeConeAngle(h.packedNodes[i])};
    badPackedCone += !coneContains(packed, h.floatNodes[i].cone);
  }
  CHECK(badFloatSphere == 0);
  CHECK(badPackedSphere == 0);
  CHECK(badFloatCone == 0);
  CHECK(badPackedCone == 0);
  CHECK(badArea == 0);
  // The box's five walls face five ways: the root's cone is the full sphere; a single wall's nodes
  // have a point cone.
  CHECK(h.floatNodes[kRootNode].cone.angle >= kPi);
  CHECK(h.nodeAreas[kRootNode] == Approx(totalArea(scene)).epsilon(1e-5));

}


TEST_CASE("Leaves: position, face normal, radius and albedo of their point", "[points]") {
  // A textured plane: albedo from the texture at the point's uv, as the renderers look it up.
  Scene scene = planeScene(10);
  scene.textures.push_back({0, 2, 2});
  scene.texels = {0xff0000ffu, 0xff00ff00u, 0xffff0000u, 0xffffffffu};
  scene.materials[0].kdTexture = 0;
  scene.materials[0].kd = Rgb(0.8f);
  finalizeScene(scene);
  const uint32_t n = 256;
  PointHierarchyOptions o = hierarchyOptions(n, NodeEncoding::Float);
  o.discAreaScale = 1.5f;
  const PointHierarchy h = buildPointHierarchy(scene, o);
  CHECK(h.restPointArea == Approx(100.0 / n));
  for (uint32_t j = 0; j < n; ++j) {
    const PointSample& s = h.points[j];
    const FloatNode& leaf = h.floatNodes[n + j];
    const SurfacePoint sp = surfaceAt(scene, s.triangle, s.b1, s.b2);
    REQUIRE(leaf.sphere.center == sp.position);
    REQUIRE(leaf.cone.axis == scene.faceNormals[s.triangle]);
    REQUIRE(leaf.cone.angle == 0);
    REQUIRE(leaf.albedo == bsdfAt(scene, sp).diffuse());
    REQUIRE(leaf.sphere.radius == Approx(std::sqrt(1.5 * 100.0 / n / kPi)));
    REQUIRE(h.nodeAreas[n + j] == h.restPointArea);
  }
  // A glTF material whose sheen colour alone is textured: the diffuse term lies under the sheen,
  // scaled by the textured sheen colour there.
  Material& gltf = scene.materials[0];
  gltf.type = MaterialType::Gltf;
  gltf.kdTexture = -1;
  gltf.metallic = 0;
  gltf.sheenColour = Rgb(1.0f);
  gltf.sheenRoughness = 0.5f;
  gltf.sheenColourTexture = 0;
  const PointHierarchy sheen = buildPointHierarchy(scene, o);
  for (uint32_t j = 0; j < n; ++j) {
    const PointSample& s = sheen.points[j];
    REQUIRE(sheen.floatNodes[n + j].albedo == bsdfAt(scene, surfaceAt(scene, s.triangle, s.b1, s.b2)).diffuse());
  }
  // Specular materials have no diffuse albedo.
  scene.materials[0].type = MaterialType::Mirror;
  const PointHierarchy mirror = buildPointHierarchy(scene, o);
  CHECK(mirror.floatNodes[n].albedo == Rgb(0.0f));
}


TEST_CASE("Packed nodes: quantization error on the Cornell box within its bounds", "[points]") {
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 14;
  const PointHierarchy h = buildPointHierarchy(scene, hierarchyOptions(n));
  const NodeQuantization& q = h.quantization;
  const double step = std::max({q.step.x, q.step.y, q.step.z});
  double leafPos = 0, leafRadius = 0, leafNormal = 0, maxAlbedo = 0, interiorGrowth = 0,
         leafCone = 0, interiorCone = 0;
  double leastGrowth = 1e30;  // packed radius less float radius, over every node
  uint32_t albedoOutOfBound = 0;
  for (uint32_t i = kRootNode; i < 2 * n; ++i) {
    const FloatNode f = h.floatNodes[i], p = decodeNode(h.packedNodes[i], q);
    leastGrowth = std::min(leastGrowth, double(p.sphere.radius) - double(f.sphere.radius));
    if (i >= n) {
      leafPos = std::max(leafPos, double(length(p.sphere.center - f.sphere.center)));
      leafRadius = std::max(leafRadius, double(p.sphere.radius - f.sphere.radius));
      leafNormal = std::max(leafNormal, angleD(p.cone.axis, f.cone.axis));
      leafCone = std::max(leafCone, double(p.cone.angle));
    } else {
      interiorGrowth = std::max(interiorGrowth, double(p.sphere.radius - f.sphere.radius));
      if (f.cone.angle < kPi) interiorCone = std::max(interiorCone, double(p.cone.angle - f.cone.angle));
    }
    for (int c = 0; c < 3; ++c) {
      maxAlbedo = std::max(maxAlbedo, double(std::abs(p.albedo[c] - f.albedo[c])));
      // Square-root coding rounds sqrt(a) to the nearest 1/31: the error bound at a.
      const double root = std::sqrt(double(f.albedo[c]));
      const double bound = std::max(std::pow(root + 0.5 / 31, 2) - f.albedo[c], f.albedo[c] - std::pow(std::max(0.0, root - 0.5 / 31), 2));
      albedoOutOfBound += std::abs(double(p.albedo[c]) - f.albedo[c]) > bound + 1e-6;
    }
  }
  const double leafR = h.floatNodes[n].sphere.radius;
  INFO("position step " << step << ", leaf radius " << leafR << "; leaves: position error " << leafPos
                        << ", radius growth " << leafRadius << ", normal error " << leafNormal * 180 / kPi
                        << " deg, cone " << leafCone * 180 / kPi << " deg; interior: radius growth "
                        << interiorGrowth << ", cone growth " << interiorCone * 180 / kPi << " deg; albedo "
                        << maxAlbedo << " absolute");
  // Centres round to the nearest step: at most half a step per axis.
  CHECK(leafPos <= 0.5 * std::sqrt(3.0) * step * 1.001);
  // Radii grow, so that a packed sphere holds its subtree whatever the centre's rounding, by the
  // centre's displacement and one radius step at most.
  CHECK(leastGrowth >= 0);
  CHECK(leafRadius <= leafPos + q.radiusStep * 1.001 + 1e-5 * leafR);
  // The Cornell box's normals are axis-aligned but for the tilted blocks: 5-bit lattice directions
  // are exact for the former and within 2 degrees for the latter; cone angles round up by 0.7 deg.
  CHECK(leafNormal * 180 / kPi < 2.0);
  CHECK(leafCone <= leafNormal + kPi / 255 + 1e-5);
  // Interior spheres carry the rounding of every level below (14 here): a few steps.
  CHECK(interiorGrowth < 14 * 3 * step);
  CHECK(interiorCone * 180 / kPi < 3.0 + 0.71);  // lattice error (< 3 deg, tested above) plus one code
  // 5-bit square-root albedo: within the coding's bound at every value, (sqrt(a) + 1/62)^2 - a, so
  // within 0.028 for the box's albedos (0.725 at most) and 0.032 for any.
  CHECK(maxAlbedo < 0.028);
  CHECK(albedoOutOfBound == 0);
}


TEST_CASE("Refit after moving vertices equals a rebuild of the node data in the same order", "[points]") {
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 12;
  for (NodeEncoding encoding : {NodeEncoding::Float, NodeEncoding::Packed}) {
    PointHierarchy refitted = buildPointHierarchy(scene, hierarchyOptions(n, encoding));
    // Deform: a smooth displacement of every vertex, which stretches and tilts the triangles.
    Scene moved = scene;
    for (Vec3& v : moved.positions) v += Vec3{20 * std::sin(v.y * 0.01f), 5 * std::cos(v.x * 0.02f), 10 * std::sin(v.x * 0.01f)};
    const PointHierarchy before = refitted;
    refitPointHierarchy(refitted, moved);
    // The rebuild: the same points in the same order and rest state, node data computed afresh.
    PointHierarchy rebuilt = before;
    rebuilt.floatNodes.assign(rebuilt.floatNodes.size(), FloatNode{{{kInf, kInf, kInf}, kInf}, {}, {}});
    rebuilt.nodeAreas.clear();
    rebuilt.packedNodes.clear();
    refitPointHierarchy(rebuilt, moved);
    // Node 0 is unused; nodes 1 .. 2n - 1 must match bit for bit.
    const size_t count = 2 * n - 1;
    CHECK(std::memcmp(&refitted.floatNodes[1], &rebuilt.floatNodes[1], count * sizeof(FloatNode)) == 0);
    CHECK(std::memcmp(&refitted.nodeAreas[1], &rebuilt.nodeAreas[1], count * sizeof(float)) == 0);
    if (encoding == NodeEncoding::Packed)
      CHECK(std::memcmp(&refitted.packedNodes[1], &rebuilt.packedNodes[1], count * sizeof(PackedNode)) == 0);
    // And the refit did move the nodes: leaves to the deformed surface, with the triangles' stretch.
    uint32_t stale = 0, wrongArea = 0;
    for (uint32_t j = 0; j < n; ++j) {
      const PointSample& s = refitted.points[j];
      stale += !(refitted.floatNodes[n + j].sphere.center == pointPosition(moved, s));
      const double expected = double(before.restPointArea) * triangleAreaD(moved, s.triangle) / scene.faceAreas[s.triangle];
      wrongArea += std::abs(refitted.nodeAreas[n + j] - expected) > 1e-4 * expected;
    }
    CHECK(stale == 0);
    CHECK(wrongArea == 0);
    // Bounds still hold after the refit.
    uint32_t bad = 0;
    for (uint32_t i = kRootNode; i < n; ++i)
      for (uint32_t c : {firstChild(i), secondChild(i)}) {
        bad += !sphereContains(refitted.floatNodes[i].sphere, refitted.floatNodes[c].sphere);
        bad += !coneContains(refitted.floatNodes[i].cone, refitted.floatNodes[c].cone);
        if (encoding == NodeEncoding::Packed)
          bad += !sphereContains(decodeSphere(refitted.packedNodes[i], refitted.quantization),
                                 decodeSphere(refitted.packedNodes[c], refitted.quantization));
      }
    CHECK(bad == 0);
  }
}


TEST_CASE("Refit under a rigid translation moves every sphere and keeps radii", "[points]") {
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 10;
  PointHierarchy h = buildPointHierarchy(scene, hierarchyOptions(n, NodeEncoding::Float));
  const PointHierarchy before = h;
  Scene moved = scene;
  const Vec3 shift{100, -50, 25};
  for (Vec3& v : moved.positions) v += shift;
  refitPointHierarchy(h, moved);
  double worstCentre = 0, worstRadius = 0;
  for (uint32_t i = kRootNode; i < 2 * n; ++i) {
    worstCentre = std::max(worstCentre, double(length(h.floatNodes[i].sphere.center - before.floatNodes[i].sphere.center - shift)));
    worstRadius = std::max(worstRadius, std::abs(double(h.floatNodes[i].sphere.radius) / before.floatNodes[i].sphere.radius - 1));
  }
  CHECK(worstCentre < 1e-3);  // float rounding of coordinates about 600
  CHECK(worstRadius < 1e-3);
  // A triangle stretched to twice its area doubles its points' areas: radius times sqrt(2).
  Scene plane = planeScene(10);
  PointHierarchy p = buildPointHierarchy(plane, hierarchyOptions(64, NodeEncoding::Float));
  const float r0 = p.floatNodes[64].sphere.radius;
  for (Vec3& v : plane.positions) v.x *= 2;
  refitPointHierarchy(p, plane);
  CHECK(p.floatNodes[64].sphere.radius == Approx(r0 * std::sqrt(2.0f)));
  CHECK(p.nodeAreas[kRootNode] == Approx(200));
}


TEST_CASE("Radiance pull: interior nodes hold their leaves' area-weighted average", "[points]") {
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 10;
  PointHierarchy h = buildPointHierarchy(scene, hierarchyOptions(n));
  // Deform so that leaf areas differ, then give leaves distinct radiance.
  Scene moved = scene;
  for (Vec3& v : moved.positions) v.y *= 1 + v.x * 0.002f;
  refitPointHierarchy(h, moved);
  std::vector<Rgb> radiance(h.nodeCount(), Rgb(-1.0f));
  for (uint32_t j = 0; j < n; ++j) radiance[n + j] = Rgb(float(j % 7), float(j % 3), 1.0f);
  pullRadiance(h, radiance);
  for (uint32_t i : {kRootNode, 2u, 3u, 5u, 37u, n / 2 + 3}) {
    double sum[3] = {0, 0, 0}, area = 0;
    for (uint32_t j = firstLeafPoint(i, n); j < firstLeafPoint(i, n) + leavesBelow(i, n); ++j) {
      area += h.nodeAreas[n + j];
      for (int c = 0; c < 3; ++c) sum[c] += double(h.nodeAreas[n + j]) * radiance[n + j][c];
    }
    for (int c = 0; c < 3; ++c) CHECK(radiance[i][c] == Approx(sum[c] / area).epsilon(1e-5));
  }
  CHECK(radiance[kRootNode].b == Approx(1.0f));
  // Half floats for the packed layout.
  const std::vector<HalfRgb> half = packRadiance(radiance);
  REQUIRE(half.size() == radiance.size());
  CHECK(toFloat(half[kRootNode]).r == Approx(radiance[kRootNode].r).epsilon(1.0 / 2048));
  CHECK_THROWS_AS(pullRadiance(h, std::span<Rgb>(radiance).first(n)), std::invalid_argument);
}


TEST_CASE("Directional radiance: a node's sums over its leaves, read back towards a direction", "[points]") {
  // Every interior node's six sums equal the brute-force sums over its leaves (area x radiance x
  // max(0, n . e_k) and area x max(0, n . e_k)); towards an axis direction a node sends the mean of
  // the leaves that face it; a flat node (one normal) sends its mean every way it faces.
  const Scene& scene = cornellBox();
  const uint32_t n = 1u << 10;
  const PointHierarchy h = buildPointHierarchy(scene, hierarchyOptions(n, NodeEncoding::Float));
  std::vector<Rgb> radiance(h.nodeCount());
  for (uint32_t j = 0; j < n; ++j) radiance[n + j] = Rgb(float(j % 7), float(j % 3), 1.0f);
  pullRadiance(h, radiance);
  const std::vector<DirectionalRadiance> d = directionalRadiance(h, radiance);
  REQUIRE(d.size() == n);
  const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  int flatChecked = 0, octantChecked = 0;
  for (uint32_t i = kRootNode; i < n; ++i) {
    double shown[6][3] = {}, area[6] = {};
    bool flat = true;
    const uint32_t first = firstLeafPoint(i, n), count = leavesBelow(i, n);
    for (uint32_t j = first; j < first + count; ++j) {
      const Vec3 normal = h.floatNodes[n + j].cone.axis;
      flat &= dot(normal, h.floatNodes[n + first].cone.axis) > 0.99999f;
      for (int k = 0; k < 6; ++k) {
        const double a = double(h.nodeAreas[n + j]) * std::max(0.0f, dot(normal, axes[k]));
        area[k] += a;
        for (int c = 0; c < 3; ++c) shown[k][c] += a * radiance[n + j][c];
      }
    }
    INFO("node " << i);
    for (int k = 0; k < 6; ++k) {
      REQUIRE(d[i].area[k] == Approx(area[k]).epsilon(1e-4).margin(1e-6 * h.nodeAreas[i]));
      for (int c = 0; c < 3; ++c)
        REQUIRE(d[i].shown[k][c] == Approx(shown[k][c]).epsilon(1e-4).margin(1e-5 * h.nodeAreas[i]));
      if (area[k] > 0) {
        const Rgb towards = radianceTowards(d[i], axes[k], Rgb(-1.0f));
        for (int c = 0; c < 3; ++c) REQUIRE(towards[c] == Approx(shown[k][c] / area[k]).epsilon(1e-4));
      } else {
        REQUIRE(radianceTowards(d[i], axes[k], Rgb(-1.0f)).r == -1.0f);  // no leaf faces that way
      }
    }
    // Towards the mean of its leaves' normals, when every normal lies in that direction's octant,
    // the blend is exact: sum(A L max(0, n . w)) / sum(A max(0, n . w)).
    Vec3 mean;
    for (uint32_t j = first; j < first + count; ++j) mean += h.floatNodes[n + j].cone.axis;
    if (length(mean) > 0.1f) {
      const Vec3 w = normalize(mean);
      bool inOctant = true;
      double shownW[3] = {}, areaW = 0;
      for (uint32_t j = first; j < first + count; ++j) {
        const Vec3 normal = h.floatNodes[n + j].cone.axis;
        inOctant &= normal.x * w.x >= 0 && normal.y * w.y >= 0 && normal.z * w.z >= 0;
        const double a = double(h.nodeAreas[n + j]) * std::max(0.0f, dot(normal, w));
        areaW += a;
        for (int c = 0; c < 3; ++c) shownW[c] += a * radiance[n + j][c];
      }
      if (inOctant && areaW > 0) {
        ++octantChecked;
        const Rgb towards = radianceTowards(d[i], w, Rgb(-1.0f));
        for (int c = 0; c < 3; ++c) REQUIRE(towards[c] == Approx(shownW[c] / areaW).epsilon(1e-4));
      }
    }
    if (!flat) continue;
    ++flatChecked;
    const Vec3 facing = normalize(h.floatNodes[n + first].cone.axis + Vec3{0.2f, -0.3f, 0.1f});
    const Rgb towards = radianceTowards(d[i], facing, Rgb(-1.0f));
    for (int c = 0; c < 3; ++c) REQUIRE(towards[c] == Approx(radiance[i][c]).epsilon(1e-4));
  }
  CHECK(flatChecked > 100);
  CHECK(octantChecked > flatChecked);  // also nodes over corners (normals along two or three axes)
  CHECK_THROWS_AS(directionalRadiance(h, std::span<const Rgb>(radiance).first(n)), std::invalid_argument);
}

TEST_CASE("Half floats: exact round trip and round-to-nearest-even", "[points]") {
  for (uint32_t h = 0; h < 65536; ++h) {
    const bool nan = (h & 0x7c00u) == 0x7c00u && (h & 0x3ffu) != 0;
    if (nan) {
      REQUIRE(std::isnan(halfToFloat(uint16_t(h))));
      continue;
    }
    REQUIRE(floatToHalf(halfToFloat(uint16_t(h))) == h);
  }
  CHECK(halfToFloat(floatToHalf(65504.0f)) == 65504.0f);
  CHECK(std::isinf(halfToFloat(floatToHalf(65520.0f))));
  CHECK(halfToFloat(floatToHalf(65519.0f)) == 65504.0f);
  CHECK(halfToFloat(floatToHalf(1.0f + 0x1p-11f)) == 1.0f);             // tie to even (down)
  CHECK(halfToFloat(floatToHalf(1.0f + 3 * 0x1p-11f)) == 1.0f + 0x1p-9f);  // tie to even (up)
  CHECK(halfToFloat(floatToHalf(0x1p-24f)) == 0x1p-24f);                  // smallest subnormal
  // Random values: the nearest half, checked against its neighbours.
  Rng rng(3);
  for (int i = 0; i < 100000; ++i) {
    const float f = std::ldexp(rng.uniform() + 0.5f, int(rng.below(40)) - 26) * (rng.uniform() < 0.5f ? -1 : 1);
    const uint16_t h = floatToHalf(f);
    const double err = std::abs(double(halfToFloat(h)) - f);
    for (int d : {-1, 1}) {
      const uint16_t other = uint16_t(h + d);
      if ((other & 0x7c00u) == 0x7c00u || ((other ^ h) & 0x8000u)) continue;
      REQUIRE(err <= std::abs(double(halfToFloat(other)) - f));
    }
  }
}

TEST_CASE("facingMortonKey orders work by the side a normal faces, then by Morton code", "[points][morton]") {
  // Six classes of facing, each above every Morton code of the classes before it (a z-facing
  // point must not sort among x-facing ones), and Morton order within a class.
  Bounds3 bounds;
  bounds.extend({0, 0, 0}), bounds.extend({1, 1, 1});
  const Vec3 normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int facing = 0; facing < 6; ++facing) {
    const uint64_t lowest = facingMortonKey({0, 0, 0}, normals[facing], bounds);
    const uint64_t highest = facingMortonKey({1, 1, 1}, normals[facing], bounds);
    CAPTURE(facing);
    REQUIRE(lowest >> 30 == uint64_t(facing));
    REQUIRE(highest >> 30 == uint64_t(facing));
    REQUIRE(highest - lowest == mortonCode({1, 1, 1}, bounds));
    if (facing > 0) REQUIRE(lowest > facingMortonKey({1, 1, 1}, normals[facing - 1], bounds));
  }
  // The largest component decides; ties go to the first axis.
  REQUIRE(facingMortonKey({0, 0, 0}, normalize(Vec3{0.3f, -0.9f, 0.2f}), bounds) >> 30 == 3);
  REQUIRE(facingMortonKey({0, 0, 0}, Vec3{0.5f, 0.5f, 0.5f}, bounds) >> 30 == 0);
  // A NaN position takes the lowest code.
  REQUIRE(facingMortonKey({std::nanf(""), 0, 0}, normals[2], bounds) == uint64_t(2) << 30);
}
