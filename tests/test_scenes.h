// Scenes built in code for tests with analytic answers.
#pragma once
#include <array>
#include <cmath>
#include <vector>

#include "lucent/scene/scene.h"

namespace lucent::test {

// Adds an axis-aligned box of 12 triangles whose counter-clockwise normals face inward (for an
// enclosure) or outward (for an object).
inline void addBox(Scene& scene, Vec3 lo, Vec3 hi, uint32_t material, bool inward) {
  const auto base = static_cast<uint32_t>(scene.positions.size());
  for (int i = 0; i < 8; ++i) {
    scene.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
    scene.normals.push_back({0, 0, 0});
    scene.texcoords.push_back({0, 0});
  }
  // Each face as a quad (a, b, c, d), counter-clockwise seen from outside.
  const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    const uint32_t tris[2][3] = {{f[0], f[1], f[2]}, {f[0], f[2], f[3]}};
    for (const auto& t : tris) {
      if (inward) {
        scene.indices.insert(scene.indices.end(), {base + t[0], base + t[2], base + t[1]});
      } else {
        scene.indices.insert(scene.indices.end(), {base + t[0], base + t[1], base + t[2]});
      }
      scene.materialIds.push_back(material);
    }
  }
}

// Adds the quad (a, b, c, d), counter-clockwise seen from the side its normal faces, as two
// triangles with its own vertices; `shading` is their shading normal (zero: the geometric one).
inline void addQuad(Scene& scene, Vec3 a, Vec3 b, Vec3 c, Vec3 d, uint32_t material, Vec3 shading = {0, 0, 0}) {
  const auto base = static_cast<uint32_t>(scene.positions.size());
  for (const Vec3& v : {a, b, c, d}) {
    scene.positions.push_back(v);
    scene.normals.push_back(shading);
    scene.texcoords.push_back({0, 0});
  }
  scene.indices.insert(scene.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  scene.materialIds.insert(scene.materialIds.end(), {material, material});
}

// Adds a UV sphere of `rings` x `segments` quads (triangles at the poles), its vertex normals exact,
// wound counter-clockwise seen from outside.
inline void addSphere(Scene& scene, Vec3 centre, float radius, int rings, int segments, uint32_t material) {
  const auto base = static_cast<uint32_t>(scene.positions.size());
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const float theta = kPi * float(i) / float(rings), phi = 2 * kPi * float(j) / float(segments);
      const Vec3 n{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
      scene.positions.push_back(centre + n * radius);
      scene.normals.push_back(n);
      scene.texcoords.push_back({0, 0});
    }
  const auto at = [&](int i, int j) { return base + uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      if (i > 0) scene.indices.insert(scene.indices.end(), {at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      if (i < rings - 1) scene.indices.insert(scene.indices.end(), {at(i, j), at(i + 1, j + 1), at(i + 1, j)});
      scene.materialIds.insert(scene.materialIds.end(), size_t(int(i > 0) + int(i < rings - 1)), material);
    }
}

inline uint32_t addMaterial(Scene& scene, const Material& m, const std::string& name) {
  scene.materials.push_back(m);
  scene.materialNames.push_back(name);
  return static_cast<uint32_t>(scene.materials.size() - 1);
}

inline Camera testCamera(Vec3 eye, Vec3 lookAt, int width, int height, float fovY = 60.0f) {
  Camera c;
  c.eye = eye;
  c.lookAt = lookAt;
  c.up = {0, 1, 0};
  c.fovY = fovY;
  c.width = width;
  c.height = height;
  return c;
}

// The closed furnace: a 2 x 2 x 2 box whose inward-facing walls have albedo rho and emit le, so that
// the radiance everywhere inside is le / (1 - rho).
inline Scene furnaceBox(Rgb rho, Rgb le, const Camera& camera) {
  Scene scene;
  Material m;
  m.kd = rho;
  m.ke = le;
  addBox(scene, {-1, -1, -1}, {1, 1, 1}, addMaterial(scene, m, "walls"), true);
  scene.camera = camera;
  finalizeScene(scene);
  return scene;
}

// Adds a texture of opaque texels given by their 8-bit codes (R, G, B), row-major from the top
// row: its index.
inline int32_t addTexture(Scene& scene, uint32_t width, uint32_t height, const std::vector<std::array<uint32_t, 3>>& codes) {
  Texture t;
  t.offset = static_cast<uint32_t>(scene.texels.size());
  t.width = width;
  t.height = height;
  for (const auto& c : codes) scene.texels.push_back(0xffu << 24 | c[2] << 16 | c[1] << 8 | c[0]);
  scene.textures.push_back(t);
  return static_cast<int32_t>(scene.textures.size() - 1);
}

// The emitter of a two-sided emission test: a square of half-side `half` at height y whose front
// faces up, of radiance le (black as a reflector), emitting from its back face too when twoSided,
// times `texture` (-1: none), its u running along x from 0 to 1 and v along z.
inline void addCeilingEmitter(Scene& scene, float half, float y, Rgb le, bool twoSided, int32_t texture) {
  Material m;
  m.kd = Rgb(0.0f);
  m.ke = le;
  m.emitsBackFace = twoSided ? 1 : 0;
  m.emissiveTexture = texture;
  const auto base = static_cast<uint32_t>(scene.positions.size());
  addQuad(scene, {-half, y, -half}, {-half, y, half}, {half, y, half}, {half, y, -half}, addMaterial(scene, m, "emitter"));
  const Vec2 uv[4] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  for (int k = 0; k < 4; ++k) scene.texcoords[base + k] = uv[k];
}

}  // namespace lucent::test
