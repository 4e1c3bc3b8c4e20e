#include "lucent/scene/scene.h"

#include <algorithm>
#include <cstring>

#include "lucent/core/rng.h"

namespace lucent {

namespace {
template <class T>
uint64_t hashArray(uint64_t h, const std::vector<T>& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
  const size_t n = v.size() * sizeof(T);
  for (size_t i = 0; i < n; i += 8) {
    uint64_t word = 0;
    std::memcpy(&word, bytes + i, std::min<size_t>(8, n - i));
    h = mix64(h ^ word) + i;
  }
  return mix64(h ^ n);
}
}  // namespace

void finalizeScene(Scene& scene) {
  scene.bounds = {};
  for (const Vec3& p : scene.positions) scene.bounds.extend(p);
  const uint32_t n = scene.triangleCount();
  scene.faceNormals.resize(n);
  scene.faceAreas.resize(n);
  for (uint32_t t = 0; t < n; ++t) {
    const Vec3 c = cross(scene.vertex(t, 1) - scene.vertex(t, 0), scene.vertex(t, 2) - scene.vertex(t, 0));
    scene.faceAreas[t] = 0.5f * length(c);
    scene.faceNormals[t] = normalize(c);
  }

  // Light power estimates decide how often next-event estimation picks each light.
  scene.lights.erase(std::remove_if(scene.lights.begin(), scene.lights.end(),
                                    [](const Light& l) { return l.type == LightType::Triangle ||
                                                                l.type == LightType::Environment; }),
                     scene.lights.end());
  std::vector<Light> lights;
  std::vector<float> power;
  scene.triangleLight.assign(scene.triangleCount(), -1);
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    const Rgb ke = scene.materials[scene.materialIds[t]].ke;
    if (ke.isBlack()) continue;
    scene.triangleLight[t] = static_cast<int32_t>(lights.size());
    lights.push_back({LightType::Triangle, t, {}, {}});
    power.push_back(ke.luminance() * scene.triangleArea(t) * kPi);
  }
  const float r = scene.boundingRadius();
  for (const Light& l : scene.lights) {
    lights.push_back(l);
    power.push_back(l.type == LightType::Point ? 4 * kPi * l.value.luminance()
                                               : kPi * r * r * l.value.luminance());
  }
  if (scene.environment.present) {
    Light env;
    env.type = LightType::Environment;
    lights.push_back(env);
    const Environment& e = scene.environment;
    float mean = e.radiance.luminance();
    if (!e.texels.empty()) {
      // distribution total = sum of luminance * sin(theta): mean radiance over the sphere ~ total * pi/(2 w h)
      mean = e.distribution.total() * kPi / (2.0f * e.width * e.height);
    }
    power.push_back(kPi * kPi * r * r * mean);  // flux through the scene's cross-section
  }
  scene.lights = std::move(lights);
  if (!power.empty()) scene.lightDistribution = Distribution1D(power);

  scene.contentHash = sceneContentHash(scene);
}

uint64_t sceneContentHash(const Scene& scene) {
  const Environment& env = scene.environment;
  uint64_t h = 0x10CE47ull;
  h = hashArray(h, scene.positions);
  h = hashArray(h, scene.normals);
  h = hashArray(h, scene.texcoords);
  h = hashArray(h, scene.indices);
  h = hashArray(h, scene.materialIds);
  h = hashArray(h, scene.materials);
  h = hashArray(h, scene.textures);
  h = hashArray(h, scene.texels);
  h = hashArray(h, scene.lights);
  h = hashArray(h, env.texels);
  h = hashArray(h, std::vector<uint32_t>{env.present, env.width, env.height});
  h = hashArray(h, std::vector<Rgb>{env.radiance});
  h = hashArray(h, std::vector<Camera>{scene.camera});
  return h;
}

}  // namespace lucent
