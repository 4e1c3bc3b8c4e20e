// Embree visibility against brute-force ray-triangle intersection, and packets against single rays,
// with the kernels of every instruction set this CPU runs (those of older CPUs included).
#include <catch2/catch.hpp>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/loader.h"
#include "lucent/trace/visibility.h"

using namespace lucent;

namespace {

// Möller–Trumbore over every triangle that `there` keeps (all by default): the nearest hit in
// (tMin, tMax).
template <class There = bool (*)(uint32_t)>
Hit bruteForce(const Scene& scene, const Ray& ray, There there = [](uint32_t) { return true; }) {
  Hit best;
  best.t = ray.tMax;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    if (!there(t)) continue;
    const Vec3 p0 = scene.vertex(t, 0), e1 = scene.vertex(t, 1) - p0, e2 = scene.vertex(t, 2) - p0;
    const Vec3 pv = cross(ray.direction, e2);
    const double det = dot(e1, pv);
    if (std::abs(det) < 1e-12) continue;
    const Vec3 tv = ray.origin - p0;
    const double u = dot(tv, pv) / det;
    const Vec3 qv = cross(tv, e1);
    const double v = dot(ray.direction, qv) / det;
    const double dist = dot(e2, qv) / det;
    if (u < 0 || v < 0 || u + v > 1 || dist <= ray.tMin || dist >= best.t) continue;
    best = {float(dist), t, float(u), float(v)};
  }
  if (best.triangle == kNoHit) best.t = kInf;
  return best;
}

std::vector<Ray> randomRays(const Scene& scene, int n, uint64_t seed) {
  Rng rng(seed);
  std::vector<Ray> rays;
  const Vec3 lo = scene.bounds.lo, ext = scene.bounds.extent();
  for (int i = 0; i < n; ++i) {
    const Vec3 o{lo.x + ext.x * rng.uniform(), lo.y + ext.y * rng.uniform(), lo.z + ext.z * rng.uniform()};
    Ray r{o, sampleUniformSphere(rng.uniform2())};
    r.tMax = (i % 3 == 0) ? 0.3f * length(ext) : kInf;  // some short rays for any-hit queries
    rays.push_back(r);
  }
  return rays;
}

}  // namespace

TEST_CASE("Closest-hit and any-hit queries agree with brute force", "[visibility]") {
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-glossy.json", {true});
  const std::string isa = GENERATE(from_range(supportedEmbreeIsas()));
  INFO("Embree ISA " << isa);
  const Visibility vis(scene, {.isa = isa});
  REQUIRE(vis.isa() == isa);
  int hits = 0;
  for (const Ray& ray : randomRays(scene, 3000, 1)) {
    const Hit expected = bruteForce(scene, ray);
    const Hit hit = vis.intersect(ray);
    REQUIRE(hit.found() == expected.found());
    REQUIRE(vis.occluded(ray) == expected.found());
    if (!hit.found()) continue;
    ++hits;
    REQUIRE(hit.t == Approx(expected.t).epsilon(1e-4));
    // Rays may cross an edge shared by two triangles: then either is right, at the same distance.
    if (hit.triangle == expected.triangle) {
      REQUIRE(hit.b1 == Approx(expected.b1).margin(1e-4));
      REQUIRE(hit.b2 == Approx(expected.b2).margin(1e-4));
    }
  }
  REQUIRE(hits > 2000);
}

TEST_CASE("With holes and single-sided faces, closest and any hits agree with brute force, camera rays passing "
          "single-sided faces from behind",
          "[visibility]") {
  // The glossy box's triangles in turn: as they were, single-sided, single-sided with a mask that
  // keeps them (alpha 0.8, cutoff 0.5), and masked out (alpha 0.2): the three Embree geometries
  // (plain, single-sided, holes) each hold some, and a hit must name the scene's triangle.
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-glossy.json", {true});
  Material singleSided = scene.materials[0];
  singleSided.culledBehind = 1;
  Material kept = singleSided, cutOut = scene.materials[0];
  kept.alphaMode = cutOut.alphaMode = AlphaMode::Mask;
  kept.baseAlpha = 0.8f;
  cutOut.baseAlpha = 0.2f;
  const auto first = uint32_t(scene.materials.size());
  scene.materials.insert(scene.materials.end(), {singleSided, kept, cutOut});
  for (uint32_t t = 0; t < scene.triangleCount(); ++t)
    if (t % 4 != 0) scene.materialIds[t] = first + t % 4 - 1;
  const auto culled = [&](uint32_t t) { return scene.materials[scene.materialIds[t]].culledBehind != 0; };
  const auto cutAway = [&](uint32_t t) { return scene.materialIds[t] == first + 2; };
  const std::string isa = GENERATE(from_range(supportedEmbreeIsas()));
  INFO("Embree ISA " << isa);
  const Visibility vis(scene, {.isa = isa});
  const std::vector<Ray> rays = randomRays(scene, 3000, 2);
  int passedBehind = 0;
  for (const RayKind kind : {RayKind::Camera, RayKind::Secondary}) {
    INFO((kind == RayKind::Camera ? "camera rays" : "secondary rays"));
    std::vector<Hit> hits(rays.size());
    for (size_t first16 = 0; first16 < rays.size(); first16 += 16) {
      const int count = int(std::min<size_t>(16, rays.size() - first16));
      intersectPacket<16>(vis, count, [&](int j) -> const Ray& { return rays[first16 + size_t(j)]; }, &hits[first16],
                          kind);
    }
    for (size_t i = 0; i < rays.size(); ++i) {
      const Ray& ray = rays[i];
      const Hit expected = bruteForce(scene, ray, [&](uint32_t t) {
        return !cutAway(t) &&
               !(kind == RayKind::Camera && culled(t) && !(dot(ray.direction, scene.geometricNormal(t)) < 0));
      });
      const Hit hit = vis.intersect(ray, kind);
      REQUIRE(hit.found() == expected.found());
      REQUIRE(hits[i].triangle == hit.triangle);
      if (kind == RayKind::Secondary) REQUIRE(vis.occluded(ray) == expected.found());
      if (kind == RayKind::Camera && bruteForce(scene, ray, [&](uint32_t t) { return !cutAway(t); }).t < expected.t)
        ++passedBehind;
      if (!hit.found()) continue;
      REQUIRE(hit.t == Approx(expected.t).epsilon(1e-4));
      if (hit.triangle != expected.triangle) {  // an edge shared by two triangles: either, at the same distance
        REQUIRE_FALSE(cutAway(hit.triangle));
        continue;
      }
      REQUIRE(hit.b1 == Approx(expected.b1).margin(1e-4));
      REQUIRE(hit.b2 == Approx(expected.b2).margin(1e-4));
    }
  }
  CHECK(passedBehind > 100);  // camera rays that passed a single-sided face from behind (158 of 3,000)
}

template <int N>
void checkPackets(const Visibility& vis, const std::vector<Ray>& rays) {
  for (size_t base = 0; base + N <= rays.size(); base += N) {
    RayPacket<N> packet;
    for (int i = 0; i < N; ++i) {
      const Ray& r = rays[base + i];
      packet.ox[i] = r.origin.x, packet.oy[i] = r.origin.y, packet.oz[i] = r.origin.z;
      packet.dx[i] = r.direction.x, packet.dy[i] = r.direction.y, packet.dz[i] = r.direction.z;
      packet.tMin[i] = r.tMin, packet.tMax[i] = r.tMax;
      packet.valid[i] = (i % 5 == 4) ? 0 : -1;  // some inactive lanes
    }
    HitPacket<N> hits;
    bool blocked[N];
    vis.intersect(packet, hits);
    vis.occluded(packet, blocked);
    for (int i = 0; i < N; ++i) {
      const Hit single = vis.intersect(rays[base + i]);
      if (!packet.valid[i]) {
        REQUIRE(hits.triangle[i] == kNoHit);
        REQUIRE_FALSE(blocked[i]);
        continue;
      }
      REQUIRE(hits.triangle[i] == single.triangle);
      REQUIRE(hits.t[i] == single.t);
      REQUIRE(blocked[i] == single.found());
    }
  }
}

TEST_CASE("RayPacket::assign fills the first lanes and leaves the rest inactive", "[visibility]") {
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  const auto rays = randomRays(scene, 160, 5);
  const std::string isa = GENERATE(from_range(supportedEmbreeIsas()));
  INFO("Embree ISA " << isa);
  const Visibility vis(scene, {.isa = isa});
  for (int count = 1; count <= 16; ++count) {
    RayPacket<16> packet;
    packet.assign(count, [&](int i) -> const Ray& { return rays[size_t(count + i)]; });
    bool blocked[16];
    HitPacket<16> hits;
    vis.occluded(packet, blocked);
    vis.intersect(packet, hits);
    for (int i = 0; i < 16; ++i) {
      INFO("count " << count << ", lane " << i);
      const Ray& expected = rays[size_t(count + std::min(i, count - 1))];
      CHECK(packet.valid[i] == (i < count ? -1 : 0));
      CHECK(packet.ox[i] == expected.origin.x);
      CHECK(packet.dz[i] == expected.direction.z);
      CHECK(packet.tMax[i] == expected.tMax);
      if (i >= count) {
        CHECK_FALSE(blocked[i]);
        CHECK(hits.triangle[i] == kNoHit);
        CHECK(hits.t[i] == kInf);
        CHECK(hits.b1[i] == 0.0f);
        CHECK(hits.b2[i] == 0.0f);
        continue;
      }
      CHECK(blocked[i] == vis.occluded(expected));
      CHECK(hits.triangle[i] == vis.intersect(expected).triangle);
    }
  }
}

TEST_CASE("8- and 16-wide packets give the single-ray answers", "[visibility]") {
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  const auto rays = randomRays(scene, 1600, 2);
  const std::string isa = GENERATE(from_range(supportedEmbreeIsas()));
  INFO("Embree ISA " << isa);
  for (bool robust : {false, true}) {
    const Visibility vis(scene, {.robust = robust, .isa = isa});
    checkPackets<8>(vis, rays);
    checkPackets<16>(vis, rays);
  }
  REQUIRE(Visibility::embreeVersion().rfind("3.", 0) == 0);
}

TEST_CASE("Packets of 1 to N rays, some of them untraceable, give the single-ray answers", "[visibility]") {
  // intersectPacket and occludedPacket trace partial packets (the last of a wave or a tile); rays
  // with a NaN, infinite or huge origin or direction, or a NaN interval, miss and are not occluded, alone
  // or in a packet, and do not disturb the packet's other rays.
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  std::vector<Ray> rays = randomRays(scene, 400, 9);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t i = 0; i < rays.size(); i += 7) {
    switch (i % 5) {
      case 0: rays[i].origin.y = nan; break;
      case 1: rays[i].direction.x = kInf; break;
      case 2: rays[i].tMax = nan; break;
      case 3: rays[i].origin.x = 1e20f; break;  // finite, but beyond what Embree's kernels accept
      default: rays[i].direction.z = -kInf; break;
    }
  }
  const std::string isa = GENERATE(from_range(supportedEmbreeIsas()));
  INFO("Embree ISA " << isa);
  const Visibility vis(scene, {.isa = isa});
  REQUIRE(vis.isa() == isa);
  int hitsFound = 0, blockedFound = 0, untraceable = 0;
  for (int count = 1; count <= 16; ++count) {
    for (size_t first = 0; first + size_t(count) <= rays.size(); first += 23) {
      auto rayOf = [&](int j) -> const Ray& { return rays[first + size_t(j)]; };
      Hit hits8[8], hits16[16];
      bool blocked8[8], blocked16[16];
      if (count <= 8) {
        intersectPacket<8>(vis, count, rayOf, hits8);
        occludedPacket<8>(vis, count, rayOf, blocked8);
      }
      intersectPacket<16>(vis, count, rayOf, hits16);
      occludedPacket<16>(vis, count, rayOf, blocked16);
      for (int j = 0; j < count; ++j) {
        INFO("count " << count << ", first " << first << ", lane " << j);
        const Ray& ray = rayOf(j);
        const Hit single = vis.intersect(ray);
        const bool blocked = vis.occluded(ray);
        if (!traceable(ray)) {
          ++untraceable;
          CHECK_FALSE(single.found());
          CHECK_FALSE(blocked);
        }
        hitsFound += single.found(), blockedFound += blocked;
        CHECK(hits16[j].triangle == single.triangle);
        CHECK(hits16[j].t == single.t);
        CHECK(hits16[j].b1 == single.b1);  // a miss's barycentrics are 0, as Hit{}'s
        CHECK(hits16[j].b2 == single.b2);
        CHECK(blocked16[j] == blocked);
        if (count <= 8) {
          CHECK(hits8[j].triangle == single.triangle);
          CHECK(blocked8[j] == blocked);
        }
      }
    }
  }
  CHECK(untraceable > 100);
  CHECK(hitsFound > 1000);
  CHECK(blockedFound > 1000);
}
