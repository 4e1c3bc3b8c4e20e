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
  float b1 = 0, b2 = 0;  // barycentrics, for texture coordinates when a material needs them
  uint32_t triangle = 0;
  uint32_t materialId = 0;
};

// The functions below that take scalars are the path tracer's lane loop's too (shadeDiffuseLanes):
// written with selects only, so that the compiler vectorizes the very function the one-hit code
// calls, and the two compute the same IEEE operations.

// The vertex normals interpolated at a hit (not yet normalized), normalized and turned to the side
// of the geometric normal ng; ng itself where they cancel.
inline Vec3 orientedShadingNormal(Vec3 interpolated, Vec3 ng) {
  const float len = length(interpolated);
  const Vec3 n = select(len > 0, interpolated / len, ng);
  return select(dot(n, ng) < 0, -n, n);
}

// The normal of a hit's shading frame, seen from wo: the shading normal sn, or the geometric normal
// ng where the two put the viewer on different sides (at silhouettes of smooth meshes); turned to
// the viewer's side for a two-sided material.
inline Vec3 shadingFrameNormal(Vec3 wo, Vec3 sn, Vec3 ng, bool twoSided) {
  const Vec3 n = select(dot(wo, sn) * dot(wo, ng) > 0, sn, ng);
  const bool behind = dot(wo, ng) > 0 ? false : twoSided;
  return select(behind, -n, n);
}

inline SurfacePoint surfaceAt(const Scene& scene, uint32_t tri, float b1, float b2) {
  SurfacePoint sp;
  sp.triangle = tri;
  sp.materialId = scene.materialIds[tri];
  sp.b1 = b1;
  sp.b2 = b2;
  const uint32_t* v = &scene.indices[3 * tri];
  sp.position = barycentric(scene.positions[v[0]], scene.positions[v[1]], scene.positions[v[2]], b1, b2);
  sp.geometricNormal = scene.geometricNormal(tri);
  sp.shadingNormal = sp.geometricNormal;
  // OBJ faces have normals at all their vertices or at none (then they are stored as zero).
  if (!(scene.normals[v[0]] == Vec3{0, 0, 0})) {
    const Vec3 n = barycentric(scene.normals[v[0]], scene.normals[v[1]], scene.normals[v[2]], b1, b2);
    sp.shadingNormal = orientedShadingNormal(n, sp.geometricNormal);
  }
  return sp;
}

inline Vec2 texcoordsAt(const Scene& scene, const SurfacePoint& sp) {
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  const Vec2 t0 = scene.texcoords[v[0]], t1 = scene.texcoords[v[1]], t2 = scene.texcoords[v[2]];
  const float b0 = 1.0f - sp.b1 - sp.b2;
  return {t0.x * b0 + t1.x * sp.b1 + t2.x * sp.b2, t0.y * b0 + t1.y * sp.b1 + t2.y * sp.b2};
}

inline SurfaceBsdf bsdfAt(const Scene& scene, const SurfacePoint& sp) {
  const Material& m = scene.materials[sp.materialId];
  const Rgb kd = m.kdTexture < 0 ? m.kd : diffuseAlbedo(scene, m, texcoordsAt(scene, sp));
  return {m.type, kd, m.ks, m.ns, m.ni};
}


}  // namespace lucent
