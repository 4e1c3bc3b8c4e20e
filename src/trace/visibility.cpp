#include "lucent/trace/visibility.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/scene/surface.h"

namespace lucent {

namespace {
struct EmbreeError {
  std::mutex mutex;  // Embree may report from any thread
  std::string message;
  std::string structure;       // what Embree's allocations build, as --memory-limit's message names it
  std::string overMemoryLimit;  // requireMemory's message for the first allocation refused
};
}  // namespace

// The scene's triangles in up to three Embree geometries, by what a ray must ask of them: those
// there for every ray (geometry 0; in a scene of only these, all of them, numbered as the scene
// numbers them, traced without a filter); the single-sided ones (glTF doubleSided false), there for
// every ray but a camera ray from behind (RayKind), which camera queries reject by a filter of their
// context (cullBehind), so that other rays meet them without one; and those with holes (glTF alpha
// masks and blending), whose geometry filter (surfaceFilter) rejects the hits where the surface is
// not, for every query.
enum class TriangleGroup { Everywhere, SingleSided, Holes };

TriangleGroup groupOf(const Material& m) {
  return m.alphaMode != AlphaMode::Opaque ? TriangleGroup::Holes
         : m.culledBehind != 0           ? TriangleGroup::SingleSided
                                         : TriangleGroup::Everywhere;
}

// An Embree geometry's user data: its scene and its triangles.
struct GeometryTriangles {
  const Scene* scene = nullptr;
  bool mayBeSingleSided = false;  // the single-sided and the holes' geometries: cullBehind looks at their hits
  std::vector<uint32_t> triangle;  // the geometry's primitive -> the scene's triangle; empty: the same
  uint32_t sceneTriangle(unsigned primitive) const { return triangle.empty() ? primitive : triangle[primitive]; }
};

// Whether the surface is at barycentrics (u, v) of triangle `tri`, for a ray from `origin` along
// `direction`: where its alpha reaches the cutoff (masks), or with probability alpha, decided by a
// hash of the ray and the triangle (blending: stochastic transparency, the same answer for the same
// ray whatever the thread or packet).
bool surfaceIsThere(const Scene& scene, uint32_t tri, float u, float v, Vec3 origin, Vec3 direction) {
  const Material& m = scene.materials[scene.materialIds[tri]];
  SurfacePoint sp;
  sp.triangle = tri;
  sp.b1 = u;
  sp.b2 = v;
  const float alpha =
      surfaceAlpha(scene, m, m.kdTexture >= 0 ? textureUv(scene, scene.textures[size_t(m.kdTexture)], sp) : Vec2{0, 0}) *
      vertexColourAt(scene, sp).alpha;
  if (m.alphaMode == AlphaMode::Mask) return alpha >= m.alphaCutoff;
  uint32_t bits[6];
  std::memcpy(bits, &origin, 12);
  std::memcpy(bits + 3, &direction, 12);
  uint64_t key = tri;
  for (const uint32_t b : bits) key = hashKey(key, b);
  return float(key >> 40) * 0x1p-24f < alpha;
}

Vec3 directionOf(const RTCFilterFunctionNArguments* args, unsigned i) {
  return {RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
          RTCRayN_dir_z(args->ray, args->N, i)};
}

// The holes' geometry filter, for every query.
void surfaceFilter(const RTCFilterFunctionNArguments* args) {
  const auto& triangles = *static_cast<const GeometryTriangles*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const Vec3 origin{RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                      RTCRayN_org_z(args->ray, args->N, i)};
    if (!surfaceIsThere(*triangles.scene, triangles.sceneTriangle(RTCHitN_primID(args->hit, args->N, i)),
                        RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i), origin,
                        directionOf(args, i)))
      args->valid[i] = 0;
  }
}

// Camera queries' context filter, for every geometry's hits: from behind (or along it), a
// single-sided face is not there.
void cullBehind(const RTCFilterFunctionNArguments* args) {
  const auto& triangles = *static_cast<const GeometryTriangles*>(args->geometryUserPtr);
  if (!triangles.mayBeSingleSided) return;
  const Scene& scene = *triangles.scene;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const uint32_t tri = triangles.sceneTriangle(RTCHitN_primID(args->hit, args->N, i));
    if (scene.materials[scene.materialIds[tri]].culledBehind != 0 &&
        !(dot(directionOf(args, i), scene.geometricNormal(tri)) < 0))
      args->valid[i] = 0;
  }
}

struct Visibility::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::string isa;
  EmbreeError error;
  std::vector<GeometryTriangles> geometries;  // by Embree's geometry id
  bool culls = false;                         // whether the scene has single-sided faces
  // A hit's triangle in the scene.
  uint32_t triangle(unsigned geometry, unsigned primitive) const {
    return geometries[geometry].sceneTriangle(primitive);
  }
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

// Embree's context of a query: camera queries in a scene with single-sided faces carry cullBehind.
struct QueryContext {
  RTCIntersectContext embree;
  QueryContext(RayKind kind, bool sceneCulls) {
    rtcInitIntersectContext(&embree);
    if (kind == RayKind::Camera && sceneCulls) embree.filter = cullBehind;
  }
};

namespace {
// Embree's allocations (the triangles' buffers and the acceleration structure, the one large
// allocation a render does not make itself), checked against --memory-limit before each is made: a
// refused one fails the build, which reports RTC_ERROR_OUT_OF_MEMORY.
bool monitorMemory(void* user, ssize_t bytes, bool post) {
  if (post || bytes <= 0) return true;
  auto* error = static_cast<EmbreeError*>(user);
  try {
    requireMemory(uint64_t(bytes), error->structure, "render a smaller scene, or raise --memory-limit");
    return true;
  } catch (const MemoryLimitError& e) {
    std::lock_guard lock(error->mutex);
    if (error->overMemoryLimit.empty()) error->overMemoryLimit = e.what();
    return false;
  }
}

void recordError(void* user, RTCError code, const char* message) {
  auto* error = static_cast<EmbreeError*>(user);
  std::lock_guard lock(error->mutex);
  if (error->message.empty())
    error->message = "Embree error " + std::to_string(int(code)) + ": " + (message ? message : "");
}

// The packet in Embree's layout, and the lanes to trace: its active lanes whose rays are traceable.
// Every other lane gets a harmless ray (the origin, an empty interval): Embree's kernels for some
// ISAs (SSE, AVX2) check the rays of masked lanes too and abort on a NaN or infinite one.
template <class RayHitN, int N>
void toEmbree(const RayPacket<N>& rays, RayHitN& rh, int32_t valid[N]) {
  for (int i = 0; i < N; ++i) {
    const Ray ray{{rays.ox[i], rays.oy[i], rays.oz[i]}, {rays.dx[i], rays.dy[i], rays.dz[i]}, rays.tMin[i], rays.tMax[i]};
    valid[i] = traceable(ray) ? rays.valid[i] : 0;
    const Ray harmless{{0, 0, 0}, {0, 0, 1}, 1, 0};
    const Ray& r = valid[i] ? ray : harmless;
    rh.ray.org_x[i] = r.origin.x;
    rh.ray.org_y[i] = r.origin.y;
    rh.ray.org_z[i] = r.origin.z;
    rh.ray.dir_x[i] = r.direction.x;
    rh.ray.dir_y[i] = r.direction.y;
    rh.ray.dir_z[i] = r.direction.z;
    rh.ray.tnear[i] = r.tMin;
    rh.ray.tfar[i] = r.tMax;
    rh.ray.time[i] = 0;
    rh.ray.mask[i] = 0xffffffffu;
    rh.ray.id[i] = 0;
    rh.ray.flags[i] = 0;
  }
}
}  // namespace

Visibility::Visibility(const Scene& scene, const VisibilityOptions& options) : impl_(std::make_unique<Impl>()) {
  flushDenormals();
  // Embree runs the requested ISA's kernels, or this CPU's best where it lacks the requested one.
  const auto rank = [](const std::string& isa) {
    return std::find(std::begin(kEmbreeIsas), std::end(kEmbreeIsas), isa) - std::begin(kEmbreeIsas);
  };
  if (!options.isa.empty() && rank(options.isa) == std::ssize(kEmbreeIsas))
    throw std::invalid_argument("Embree ISA '" + options.isa + "': expected sse4.2, avx, avx2 or avx512");
  const std::vector<std::string> supported = supportedEmbreeIsas();
  impl_->isa = supported.empty() ? "sse2" : supported.back();
  if (!options.isa.empty() && rank(options.isa) < rank(impl_->isa)) impl_->isa = options.isa;
  const std::string config = options.isa.empty() ? std::string() : "isa=" + options.isa;
  impl_->device = rtcNewDevice(config.c_str());
  if (!impl_->device) throw std::runtime_error("Embree: cannot create device (" + config + ")");
  rtcSetDeviceErrorFunction(impl_->device, recordError, &impl_->error);
  impl_->error.structure = "the acceleration structure of the scene's " + std::to_string(scene.triangleCount()) +
                           " triangles (Embree's BVH)";
  rtcSetDeviceMemoryMonitorFunction(impl_->device, monitorMemory, &impl_->error);
  impl_->scene = rtcNewScene(impl_->device);
  // Camera queries' culling is a filter of their context, which Embree calls only in a scene that
  // asks for it.
  const bool culls = std::any_of(scene.materialIds.begin(), scene.materialIds.end(),
                                 [&](uint32_t m) { return scene.materials[m].culledBehind != 0; });
  rtcSetSceneFlags(impl_->scene, RTCSceneFlags((options.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE) |
                                               (culls ? RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION : RTC_SCENE_FLAG_NONE)));
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);

  // The groups' geometries in order, empty ones left out (but for a scene of no triangles).
  std::vector<uint32_t> groups[3];
  for (uint32_t t = 0; t < scene.triangleCount(); ++t)
    groups[int(groupOf(scene.materials[scene.materialIds[t]]))].push_back(t);
  const bool allEverywhere = groups[int(TriangleGroup::Everywhere)].size() == scene.triangleCount();
  impl_->geometries.reserve(3);  // their addresses are the geometries' user data
  // One copy of the vertices for all geometries, 4 bytes over: Embree reads each vertex as 16 bytes.
  static_assert(sizeof(Vec3) == 3 * sizeof(float), "scene.positions is Embree's RTC_FORMAT_FLOAT3");
  const size_t vertexBytes = scene.positions.size() * sizeof(Vec3);
  RTCBuffer vertexBuffer = rtcNewBuffer(impl_->device, vertexBytes + sizeof(float));
  if (void* vertices = vertexBuffer ? rtcGetBufferData(vertexBuffer) : nullptr)
    std::memcpy(vertices, scene.positions.data(), vertexBytes);
  for (const TriangleGroup group : {TriangleGroup::Everywhere, TriangleGroup::SingleSided, TriangleGroup::Holes}) {
    std::vector<uint32_t>& triangles = groups[int(group)];
    if (triangles.empty() && !(allEverywhere && group == TriangleGroup::Everywhere)) continue;
    RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (vertexBuffer)
      rtcSetGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertexBuffer, 0, sizeof(Vec3),
                           scene.positions.size());
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), triangles.size()));
    if (indices)
      for (size_t i = 0; i < triangles.size(); ++i)
        std::memcpy(indices + 3 * i, &scene.indices[3 * size_t(triangles[i])], 3 * sizeof(uint32_t));
    GeometryTriangles& user = impl_->geometries.emplace_back();
    user.scene = &scene;
    user.mayBeSingleSided = group != TriangleGroup::Everywhere;
    if (!allEverywhere) user.triangle = std::move(triangles);
    rtcSetGeometryUserData(geom, &user);
    if (group == TriangleGroup::Holes) {
      rtcSetGeometryIntersectFilterFunction(geom, surfaceFilter);
      rtcSetGeometryOccludedFilterFunction(geom, surfaceFilter);
    }
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(impl_->scene, geom);
    rtcReleaseGeometry(geom);
    if (id + 1 != impl_->geometries.size()) throw std::logic_error("Embree numbered the geometries out of order");
  }
  if (vertexBuffer) rtcReleaseBuffer(vertexBuffer);  // the geometries hold it
  impl_->culls = culls;
  rtcCommitScene(impl_->scene);
  if (!impl_->error.overMemoryLimit.empty()) throw MemoryLimitError(impl_->error.overMemoryLimit);
  if (!impl_->error.message.empty()) throw std::runtime_error(impl_->error.message);
}

Visibility::~Visibility() = default;

Hit Visibility::intersect(const Ray& ray, RayKind kind) const {
  if (!traceable(ray)) return Hit{};
  QueryContext context(kind, impl_->culls);
  RTCRayHit rh;
  rh.ray.org_x = ray.origin.x;
  rh.ray.org_y = ray.origin.y;
  rh.ray.org_z = ray.origin.z;
  rh.ray.dir_x = ray.direction.x;
  rh.ray.dir_y = ray.direction.y;
  rh.ray.dir_z = ray.direction.z;
  rh.ray.tnear = ray.tMin;
  rh.ray.tfar = ray.tMax;
  rh.ray.time = 0;
  rh.ray.mask = 0xffffffffu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context.embree, &rh);
  Hit hit;
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    hit.t = rh.ray.tfar;
    hit.triangle = impl_->triangle(rh.hit.geomID, rh.hit.primID);
    hit.b1 = rh.hit.u;
    hit.b2 = rh.hit.v;
  }
  return hit;
}

bool Visibility::occluded(const Ray& ray) const {
  if (!traceable(ray)) return false;
  QueryContext context(RayKind::Secondary, impl_->culls);
  RTCRay r;
  r.org_x = ray.origin.x;
  r.org_y = ray.origin.y;
  r.org_z = ray.origin.z;
  r.dir_x = ray.direction.x;
  r.dir_y = ray.direction.y;
  r.dir_z = ray.direction.z;
  r.tnear = ray.tMin;
  r.tfar = ray.tMax;
  r.time = 0;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
  rtcOccluded1(impl_->scene, &context.embree, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

#define LUCENT_PACKET_QUERIES(N)                                                                   \
  void Visibility::intersect(const RayPacket<N>& rays, HitPacket<N>& hits, RayKind kind) const {  \
    QueryContext context(kind, impl_->culls);                                                      \
    RTCRayHit##N rh;                                                                               \
    alignas(64) int32_t valid[N];                                                                  \
    toEmbree(rays, rh, valid);                                                                     \
    for (int i = 0; i < N; ++i) rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;                        \
    rtcIntersect##N(valid, impl_->scene, &context.embree, &rh);                                    \
    for (int i = 0; i < N; ++i) {                                                                  \
      const bool found = valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;                  \
      hits.t[i] = found ? rh.ray.tfar[i] : kInf;                                                   \
      hits.triangle[i] = found ? impl_->triangle(rh.hit.geomID[i], rh.hit.primID[i]) : kNoHit;     \
      hits.b1[i] = found ? rh.hit.u[i] : 0.0f;                                                     \
      hits.b2[i] = found ? rh.hit.v[i] : 0.0f;                                                     \
    }                                                                                              \
  }                                                                                                \
  void Visibility::occluded(const RayPacket<N>& rays, bool occluded[N]) const {                    \
    QueryContext context(RayKind::Secondary, impl_->culls);                                        \
    RTCRayHit##N rh;                                                                               \
    alignas(64) int32_t valid[N];                                                                  \
    toEmbree(rays, rh, valid);                                                                     \
    rtcOccluded##N(valid, impl_->scene, &context.embree, &rh.ray);                                 \
    for (int i = 0; i < N; ++i) occluded[i] = valid[i] && rh.ray.tfar[i] < 0;                      \
  }
LUCENT_PACKET_QUERIES(8)
LUCENT_PACKET_QUERIES(16)
#undef LUCENT_PACKET_QUERIES

std::vector<std::string> supportedEmbreeIsas() {
  __builtin_cpu_init();
  const bool runs[] = {
      __builtin_cpu_supports("sse4.2") != 0, __builtin_cpu_supports("avx") != 0,
      __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2"),
      // Embree's AVX-512 kernels are Skylake-X's.
      __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
          __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl")};
  std::vector<std::string> isas;
  for (size_t i = 0; i < std::size(kEmbreeIsas); ++i)
    if (runs[i]) isas.push_back(kEmbreeIsas[i]);
  return isas;
}

std::string Visibility::embreeVersion() {
  return std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
         std::to_string(RTC_VERSION_PATCH);
}

std::string Visibility::isa() const { return impl_->isa; }

}  // namespace lucent
