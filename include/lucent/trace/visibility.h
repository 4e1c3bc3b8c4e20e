// Visibility queries against the scene's triangles: the only interface to Embree.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/scene/scene.h"

namespace lucent {

inline constexpr uint32_t kNoHit = 0xffffffffu;

struct Hit {
  float t = kInf;
  uint32_t triangle = kNoHit;
  float b1 = 0, b2 = 0;  // barycentrics of vertices 1 and 2
  bool found() const { return triangle != kNoHit; }
};

// Every query traces only rays whose origin and direction components are at most
// kMaxRayComponent in magnitude (so finite) and whose interval is tMin <= tMax (false for NaN):
// any other ray misses and is not occluded, alone or in a packet. Callers that must tell such a
// ray from a miss (to drop the sample) test it themselves.
inline constexpr float kMaxRayComponent = 1.8e18f;  // Embree's kernels abort above 1.844e18
inline bool traceable(const Ray& ray) {
  // Embree's answer for other rays is not defined, and its SSE and AVX2 kernels abort on them.
  // The check costs single rays about 3% of their throughput (bench_pathtrace's raw loop, Cornell
  // box, 1 thread); & rather than && keeps it one branch (a NaN fails every comparison).
  const Vec3 o = ray.origin, d = ray.direction;
  const float m = kMaxRayComponent;
  int ok = std::abs(o.x) <= m;
  ok &= std::abs(o.y) <= m;
  ok &= std::abs(o.z) <= m;
  ok &= std::abs(d.x) <= m;
  ok &= std::abs(d.y) <= m;
  ok &= std::abs(d.z) <= m;
  ok &= ray.tMin <= ray.tMax;
  return ok;
}

struct VisibilityOptions {
  bool robust = false;  // Embree's robust traversal (watertight at edges), slower
  // The instruction set of Embree's kernels: "" for the best this CPU supports, or one of
  // kEmbreeIsas, so that a machine can check the kernels of CPUs older than itself.
  std::string isa;
};

// Who looks along a ray. glTF's doubleSided false is back-face culling, a rasterizer's rule for what
// the camera sees: a single-sided face is not there from behind for camera rays. Every other ray
// (reflected, shadow, photon, gather, link) meets both sides, so that visibility is reciprocal: a
// segment blocked one way is blocked the other, and the methods that follow light from the lights
// (photons, particles' links) see the scene the path tracer sees from the surfaces.
enum class RayKind : uint8_t { Camera, Secondary };

// The instruction sets Embree's kernels can be asked for, oldest first.
inline constexpr const char* kEmbreeIsas[] = {"sse4.2", "avx", "avx2", "avx512"};
// Those of kEmbreeIsas that this CPU runs.
std::vector<std::string> supportedEmbreeIsas();

// Embree's widest packet (native with AVX-512): what camera, photon and shadow rays are traced in.
inline constexpr int kWidestPacket = 16;

// Rays in structure-of-arrays form for the packet queries; N is 8 or 16.
template <int N>
struct alignas(64) RayPacket {
  float ox[N], oy[N], oz[N], dx[N], dy[N], dz[N], tMin[N], tMax[N];
  int32_t valid[N];  // -1 active, 0 inactive

  // Lanes 0 .. count-1 (count >= 1) trace rayOf(lane); the rest are inactive copies of the last.
  template <class RayOf>
  void assign(int count, RayOf rayOf) {
    for (int i = 0; i < N; ++i) {
      const Ray& ray = rayOf(i < count ? i : count - 1);
      ox[i] = ray.origin.x, oy[i] = ray.origin.y, oz[i] = ray.origin.z;
      dx[i] = ray.direction.x, dy[i] = ray.direction.y, dz[i] = ray.direction.z;
      tMin[i] = ray.tMin, tMax[i] = ray.tMax;
      valid[i] = i < count ? -1 : 0;
    }
  }
};
// A miss is as Hit{}: t infinite, no triangle, barycentrics 0.
template <int N>
struct alignas(64) HitPacket {
  float t[N], b1[N], b2[N];
  uint32_t triangle[N];
};

class Visibility {
 public:
  // The scene's triangles; one with holes (a material's alphaMode) or single-sided faces keeps a
  // reference to `scene`, to look its alpha and its faces' sides up at candidate hits, and must
  // outlive this.
  explicit Visibility(const Scene& scene, const VisibilityOptions& options = {});
  ~Visibility();
  Visibility(const Visibility&) = delete;
  Visibility& operator=(const Visibility&) = delete;

  Hit intersect(const Ray& ray, RayKind kind = RayKind::Secondary) const;
  bool occluded(const Ray& ray) const;
  void intersect(const RayPacket<8>& rays, HitPacket<8>& hits, RayKind kind = RayKind::Secondary) const;
  void intersect(const RayPacket<16>& rays, HitPacket<16>& hits, RayKind kind = RayKind::Secondary) const;
  // occluded[i] is true for active, traceable rays that hit something.
  void occluded(const RayPacket<8>& rays, bool occluded[8]) const;
  void occluded(const RayPacket<16>& rays, bool occluded[16]) const;

  static std::string embreeVersion();
  // The instruction set of Embree's kernels: one of kEmbreeIsas, or "sse2" on CPUs older than all.
  std::string isa() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The closest hits of rays rayOf(0) .. rayOf(count - 1), 1 <= count <= N, traced as one packet.
template <int N, class RayOf>
void intersectPacket(const Visibility& vis, int count, RayOf rayOf, Hit hits[], RayKind kind = RayKind::Secondary) {
  RayPacket<N> packet;
  packet.assign(count, rayOf);
  HitPacket<N> h;
  vis.intersect(packet, h, kind);
  for (int j = 0; j < count; ++j) hits[j] = {h.t[j], h.triangle[j], h.b1[j], h.b2[j]};
}

// Whether rays rayOf(0) .. rayOf(count - 1), 1 <= count <= N, are blocked, traced as one packet (a
// lone ray as a single ray: a packet of one would cost a whole packet traversal). An occlusion
// query's answer does not depend on the order of traversal, so it does not depend on the packet's
// other rays. (A closest hit can, where two triangles meet at equal distance, so intersectPacket
// is only used where a packet's rays are fixed by the data, not by threads or tiles.)
template <int N, class RayOf>
void occludedPacket(const Visibility& vis, int count, RayOf rayOf, bool occluded[]) {
  if (count == 1) {
    occluded[0] = vis.occluded(rayOf(0));
    return;
  }
  RayPacket<N> packet;
  packet.assign(count, rayOf);
  vis.occluded(packet, occluded);
}

// Whether rays rayOf(0) .. rayOf(count - 1) are blocked, traced in consecutive packets of
// kWidestPacket; answer(i, blocked) is called for every ray in order.
template <class RayOf, class Answer>
void occludedInPackets(const Visibility& vis, size_t count, RayOf rayOf, Answer answer) {
  bool blocked[kWidestPacket];
  for (size_t first = 0; first < count; first += kWidestPacket) {
    const int n = int(std::min<size_t>(kWidestPacket, count - first));
    occludedPacket<kWidestPacket>(vis, n, [&](int j) -> const Ray& { return rayOf(first + size_t(j)); }, blocked);
    for (int j = 0; j < n; ++j) answer(first + size_t(j), blocked[j]);
  }
}

}  // namespace lucent
