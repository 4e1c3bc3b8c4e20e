// The table of material kinds: every kind a material can be, one row each. From it come
// MaterialType (scene.h), SurfaceBsdf's tag and union and its one dispatch (bsdf.h), and the names
// scene files and `lucent bsdf` use. A new kind is a header in this folder (its lobe: a plain
// parameter struct with flags, evaluate, sample, albedo; see lambertian.h), a row here and its tests.
//
//   X(enumerator, value, lobe struct, SurfaceBsdf member, name, a scene file's "type" may name it)
#pragma once

#define LUCENT_MATERIAL_KINDS(X)                         \
  X(Diffuse, 0, LambertianLobe, lambertian, "diffuse", 1) \
  X(Phong, 1, PhongLobe, phong, "phong", 1)               \
  X(Mirror, 2, MirrorLobe, mirror, "mirror", 1)           \
  X(Glass, 3, GlassLobe, glass, "glass", 1)               \
  X(Gltf, 4, GltfMetalRoughLobe, gltf, "gltf", 0)
