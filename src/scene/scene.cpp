#include "lucent/scene/scene.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "lucent/core/rng.h"
#include "lucent/scene/texture.h"

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

TriangleGeometry triangleGeometry(Vec3 p0, Vec3 p1, Vec3 p2) {
  const Vec3 c = cross(p1 - p0, p2 - p0);
  const float len = length(c);
  if (std::isfinite(len)) return {c / len, 0.5f * len};
  // The area itself (at most about 1e31 with coordinates up to 1e15) fits a float.
  const double e1[3] = {double(p1.x) - p0.x, double(p1.y) - p0.y, double(p1.z) - p0.z};
  const double e2[3] = {double(p2.x) - p0.x, double(p2.y) - p0.y, double(p2.z) - p0.z};
  const double d[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const double dl = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  return {{float(d[0] / dl), float(d[1] / dl), float(d[2] / dl)}, float(0.5 * dl)};
}

namespace {
// A light's power as the float product, where finite (ordinary scenes keep their exact weights),
// else the double one.
double lightPower(float asFloat, double asDouble) { return std::isfinite(asFloat) ? double(asFloat) : asDouble; }

// What multiplies an emitter's ke into its power per unit of pi times its area: its faces, times
// its emissive texture's mean luminance (over the whole image: positive wherever any texel is, so
// that light selection never leaves out a triangle that emits).
std::vector<float> emissionScales(const Scene& scene) {
  std::vector<float> scales(scene.materials.size());
  for (size_t i = 0; i < scales.size(); ++i) {
    const Material& m = scene.materials[i];
    double textureMean = 1;
    if (m.emissiveTexture >= 0) {
      const Texture& t = scene.textures[size_t(m.emissiveTexture)];
      double sum = 0;
      for (size_t k = 0; k < size_t(t.width) * t.height; ++k) sum += decodeTexel(scene.texels[t.offset + k]).luminance();
      textureMean = sum / std::max(1.0, double(t.width) * t.height);
    }
    scales[i] = float((m.emitsBackFace != 0 ? 2.0 : 1.0) * textureMean);
  }
  return scales;
}
}  // namespace

void finalizeScene(Scene& scene) {
  scene.bounds = {};
  for (const Vec3& p : scene.positions) scene.bounds.extend(p);
  const uint32_t n = scene.triangleCount();
  scene.faceNormals.resize(n);
  scene.faceAreas.resize(n);
  for (uint32_t t = 0; t < n; ++t) {
    const TriangleGeometry g = triangleGeometry(scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2));
    scene.faceAreas[t] = g.area;
    scene.faceNormals[t] = g.normal;
  }

  // Light power estimates decide how often next-event estimation picks each light.
  scene.lights.erase(std::remove_if(scene.lights.begin(), scene.lights.end(),
                                    [](const Light& l) { return l.type == LightType::Triangle ||
                                                                l.type == LightType::Environment; }),
                     scene.lights.end());
  std::vector<Light> lights;
  std::vector<double> power;  // in double: an area of 1e31 times a radiance of 1e15 is beyond float
  scene.triangleLight.assign(scene.triangleCount(), -1);
  const std::vector<float> scales = emissionScales(scene);
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    const Rgb ke = scene.materials[scene.materialIds[t]].ke;
    if (ke.isBlack()) continue;
    const float scale = scales[scene.materialIds[t]];
    scene.triangleLight[t] = static_cast<int32_t>(lights.size());
    lights.push_back({LightType::Triangle, t, {}, {}});
    power.push_back(lightPower(ke.luminance() * scene.triangleArea(t) * kPi * scale,
                               double(ke.luminance()) * scene.triangleArea(t) * kPi * scale));
  }
  const double r = scene.boundingRadius();
  for (const Light& l : scene.lights) {
    lights.push_back(l);
    power.push_back(l.type == LightType::Point
                        ? lightPower(4 * kPi * l.value.luminance(), 4 * kPi * double(l.value.luminance()))
                    : l.type == LightType::Spot
                        ? lightPower(spotSolidAngle(l) * l.value.luminance(), spotSolidAngle(l) * double(l.value.luminance()))
                        : lightPower(kPi * float(r) * float(r) * l.value.luminance(),
                                     kPi * r * r * double(l.value.luminance())));
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
    // The flux through the scene's cross-section.
    power.push_back(lightPower(kPi * kPi * float(r) * float(r) * mean, kPi * kPi * r * r * mean));
  }
  scene.lights = std::move(lights);
  // As floats; where the largest is beyond a float's range, all scaled by the same power of two
  // (a light with any power keeps a chance to be picked).
  if (!power.empty()) {
    const double largest = *std::max_element(power.begin(), power.end());
    const double scale = largest > 0x1p100 ? std::exp2(100 - std::ceil(std::log2(largest))) : 1.0;
    std::vector<float> weights(power.size());
    for (size_t i = 0; i < power.size(); ++i)
      weights[i] = power[i] > 0 ? std::max(float(power[i] * scale), FLT_MIN) : 0.0f;
    scene.lightDistribution = lightChoiceOf(scene.lights, weights);
  }
  std::vector<uint32_t> nearby;
  for (uint32_t i = 0; i < uint32_t(scene.lights.size()); ++i)
    if (scene.lights[i].type == LightType::Point || scene.lights[i].type == LightType::Spot) nearby.push_back(i);
  scene.nearbyLights.clear();
  if (nearby.size() >= 2 && nearby.size() <= kMostNearbyLights) scene.nearbyLights = std::move(nearby);

  scene.contentHash = sceneContentHash(scene);
}

Distribution1D lightChoiceOf(std::span<const Light> lights, std::span<const float> weights) {
  std::vector<uint8_t> delta(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) delta[i] = isDeltaLight(lights[i]);
  return Distribution1D(weights, delta);
}

uint64_t sceneContentHash(const Scene& scene) {
  const Environment& env = scene.environment;
  uint64_t h = 0x10CE47ull;
  h = hashArray(h, scene.positions);
  h = hashArray(h, scene.normals);
  h = hashArray(h, scene.texcoords);
  if (!scene.tangents.empty()) h = hashArray(h, scene.tangents);  // absent: the hash of scenes without them unchanged
  if (!scene.texcoords1.empty()) h = hashArray(h, scene.texcoords1);
  if (!scene.colours.empty()) h = hashArray(h, scene.colours);
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

std::string contentHashText(const Scene& scene) {
  char text[17];
  std::snprintf(text, sizeof text, "%llx", static_cast<unsigned long long>(scene.contentHash));
  return text;
}

}  // namespace lucent
