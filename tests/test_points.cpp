// The point hierarchy (Ritschel et al. 2009, 2.1 and 3.1): heap numbering and stackless traversal,
// best-candidate sampling (area-proportional, better spaced than uniform, deterministic), the median
// split, bounding spheres and normal cones of float and packed nodes, the packed nodes' error, refit
// against rebuild, the radiance pull and half floats.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/methods/points/node_tree.h"
#include "lucent/methods/points/point_nodes.h"

using namespace lucent;

namespace {

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

