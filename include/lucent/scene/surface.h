// The local geometry and material at a ray hit.
#pragma once
#include "lucent/scene/bsdf.h"
#include "lucent/scene/scene.h"
#include "lucent/scene/texture.h"

namespace lucent {

struct SurfacePoint {
  Vec3 position;
  Vec3 geometricNormal;  // counter-clockwise winding normal (the emitting side)
  Vec3 shadingNormal;    // interpolated normal, on the same side as geometricNormal
  Vec2 uv;
  uint32_t triangle = 0;
  uint32_t materialId = 0;
};

inline SurfacePoint surfaceAt(const Scene& scene, uint32_t tri, float b1, float b2) {
  SurfacePoint sp;
  sp.triangle = tri;
  sp.materialId = scene.materialIds[tri];
  const uint32_t i0 = scene.indices[3 * tri], i1 = scene.indices[3 * tri + 1], i2 = scene.indices[3 * tri + 2];
  const float b0 = 1.0f - b1 - b2;
  sp.position = scene.positions[i0] * b0 + scene.positions[i1] * b1 + scene.positions[i2] * b2;
  sp.geometricNormal = scene.geometricNormal(tri);
  const Vec3 n = scene.normals[i0] * b0 + scene.normals[i1] * b1 + scene.normals[i2] * b2;
  const float len = length(n);
  sp.shadingNormal = len > 0 ? n / len : sp.geometricNormal;
  if (dot(sp.shadingNormal, sp.geometricNormal) < 0) sp.shadingNormal = -sp.shadingNormal;
  const Vec2 t0 = scene.texcoords[i0], t1 = scene.texcoords[i1], t2 = scene.texcoords[i2];
  sp.uv = {t0.x * b0 + t1.x * b1 + t2.x * b2, t0.y * b0 + t1.y * b1 + t2.y * b2};
  return sp;
}

inline SurfaceBsdf bsdfAt(const Scene& scene, const SurfacePoint& sp) {
  const Material& m = scene.materials[sp.materialId];
  return {m.type, diffuseAlbedo(scene, m, sp.uv), m.ks, m.ns, m.ni};
}

// Offsets a ray origin off the surface along the geometric normal, scaled to the coordinates'
// magnitude so that it works for scenes in millimetres and in metres alike.
inline Vec3 offsetOrigin(Vec3 p, Vec3 ng, Vec3 w) {
  const float scale = 1e-4f * std::max({1.0f, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return p + ng * (dot(w, ng) > 0 ? scale : -scale);
}

}  // namespace lucent
