#include "lucent/trace/visibility.h"

#include <embree3/rtcore.h>

#include <cstring>
#include <mutex>
#include <stdexcept>

#include "lucent/core/parallel.h"

namespace lucent {

namespace {
struct EmbreeError {
  std::mutex mutex;  // Embree may report from any thread
  std::string message;
};
}  // namespace

struct Visibility::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  EmbreeError error;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

namespace {
void recordError(void* user, RTCError code, const char* message) {
  auto* error = static_cast<EmbreeError*>(user);
  std::lock_guard lock(error->mutex);
  if (error->message.empty())
    error->message = "Embree error " + std::to_string(int(code)) + ": " + (message ? message : "");
}

// The packet in Embree's layout, and the lanes to trace: its active lanes whose rays are traceable.
template <class RayHitN, int N>
void toEmbree(const RayPacket<N>& rays, RayHitN& rh, int32_t valid[N]) {
  for (int i = 0; i < N; ++i) {
    const Ray ray{{rays.ox[i], rays.oy[i], rays.oz[i]}, {rays.dx[i], rays.dy[i], rays.dz[i]}, rays.tMin[i], rays.tMax[i]};
    valid[i] = traceable(ray) ? rays.valid[i] : 0;
    rh.ray.org_x[i] = rays.ox[i];
    rh.ray.org_y[i] = rays.oy[i];
    rh.ray.org_z[i] = rays.oz[i];
    rh.ray.dir_x[i] = rays.dx[i];
    rh.ray.dir_y[i] = rays.dy[i];
    rh.ray.dir_z[i] = rays.dz[i];
    rh.ray.tnear[i] = rays.tMin[i];
    rh.ray.tfar[i] = rays.tMax[i];
    rh.ray.time[i] = 0;
    rh.ray.mask[i] = 0xffffffffu;
    rh.ray.id[i] = 0;
    rh.ray.flags[i] = 0;
  }
}
}  // namespace

Visibility::Visibility(const Scene& scene, const VisibilityOptions& options) : impl_(std::make_unique<Impl>()) {
  flushDenormals();
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create device");
  rtcSetDeviceErrorFunction(impl_->device, recordError, &impl_->error);
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, options.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);

  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), scene.positions.size()));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(uint32_t), scene.triangleCount()));
  if (vertices && indices) {
    std::memcpy(vertices, scene.positions.data(), scene.positions.size() * sizeof(Vec3));
    std::memcpy(indices, scene.indices.data(), scene.indices.size() * sizeof(uint32_t));
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(impl_->scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(impl_->scene);
  if (!impl_->error.message.empty()) throw std::runtime_error(impl_->error.message);
}

Visibility::~Visibility() = default;

Hit Visibility::intersect(const Ray& ray) const {
  if (!traceable(ray)) return Hit{};
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
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
  rtcIntersect1(impl_->scene, &context, &rh);
  Hit hit;
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    hit.t = rh.ray.tfar;
    hit.triangle = rh.hit.primID;
    hit.b1 = rh.hit.u;
    hit.b2 = rh.hit.v;
  }
  return hit;
}

bool Visibility::occluded(const Ray& ray) const {
  if (!traceable(ray)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
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
  rtcOccluded1(impl_->scene, &context, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

#define LUCENT_PACKET_QUERIES(N)                                                                   \
  void Visibility::intersect(const RayPacket<N>& rays, HitPacket<N>& hits) const {                 \
    RTCIntersectContext context;                                                                   \
    rtcInitIntersectContext(&context);                                                             \
    RTCRayHit##N rh;                                                                               \
    int32_t valid[N];                                                                              \
    toEmbree(rays, rh, valid);                                                                     \
    for (int i = 0; i < N; ++i) rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;                        \
    rtcIntersect##N(valid, impl_->scene, &context, &rh);                                           \
    for (int i = 0; i < N; ++i) {                                                                  \
      const bool found = valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;                  \
      hits.t[i] = found ? rh.ray.tfar[i] : kInf;                                                   \
      hits.triangle[i] = found ? rh.hit.primID[i] : kNoHit;                                        \
      hits.b1[i] = found ? rh.hit.u[i] : 0.0f;                                                     \
      hits.b2[i] = found ? rh.hit.v[i] : 0.0f;                                                     \
    }                                                                                              \
  }                                                                                                \
  void Visibility::occluded(const RayPacket<N>& rays, bool occluded[N]) const {                    \
    RTCIntersectContext context;                                                                   \
    rtcInitIntersectContext(&context);                                                             \
    RTCRayHit##N rh;                                                                               \
    int32_t valid[N];                                                                              \
    toEmbree(rays, rh, valid);                                                                     \
    rtcOccluded##N(valid, impl_->scene, &context, &rh.ray);                                        \
    for (int i = 0; i < N; ++i) occluded[i] = valid[i] && rh.ray.tfar[i] < 0;                      \
  }
LUCENT_PACKET_QUERIES(8)
LUCENT_PACKET_QUERIES(16)
#undef LUCENT_PACKET_QUERIES

std::string Visibility::embreeVersion() {
  return std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
         std::to_string(RTC_VERSION_PATCH);
}

std::string Visibility::isa() const {
  if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) return "avx512";
  if (rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED))
    return __builtin_cpu_supports("avx2") ? "avx2" : "avx";
  return "sse4.2";
}

}  // namespace lucent
