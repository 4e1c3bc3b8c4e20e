// Next-event estimation: sampling a point or direction on the scene's lights from a receiver, and
// the density with which it would have been chosen (for multiple importance sampling).
#pragma once
#include "lucent/core/sampling.h"
#include "lucent/scene/scene.h"
#include "lucent/scene/texture.h"

namespace lucent {

struct LightSample {
  Vec3 wi;              // unit direction from the receiver towards the light
  Vec3 point;           // the point on the light (area and point lights)
  float distance = 0;   // to the light point; kInf for directional and environment
  Rgb radiance;         // arriving radiance (intensity / d^2 for point lights)
  float pdf = 0;        // solid-angle density times the light's selection probability
  bool delta = false;   // point and directional lights cannot be hit by BSDF sampling
};

inline LightSample sampleLight(const Scene& scene, Vec3 receiver, float uLight, Vec2 u) {
  LightSample s;
  if (scene.lights.empty()) return s;
  float pmf;
  const uint32_t li = scene.lightDistribution.sampleDiscrete(uLight, &pmf);
  const Light& light = scene.lights[li];
  switch (light.type) {
    case LightType::Triangle: {
      const Vec2 b = sampleUniformTriangle(u);
      const uint32_t t = light.triangle;
      const Vec3 q = scene.vertex(t, 0) * (1 - b.x - b.y) + scene.vertex(t, 1) * b.x + scene.vertex(t, 2) * b.y;
      const Vec3 d = q - receiver;
      const float dist2 = dot(d, d);
      s.point = q;
      s.distance = std::sqrt(dist2);
      s.wi = d / s.distance;
      const float cosLight = -dot(s.wi, scene.geometricNormal(t));
      if (cosLight <= 0 || !(dist2 > 0)) return {};  // emitters are one-sided
      s.radiance = scene.materials[scene.materialIds[t]].ke;
      s.pdf = pmf * dist2 / (cosLight * scene.triangleArea(t));
      return s;
    }
    case LightType::Point: {
      const Vec3 d = light.vector - receiver;
      const float dist2 = dot(d, d);
      s.point = light.vector;
      s.distance = std::sqrt(dist2);
      s.wi = d / s.distance;
      s.radiance = light.value / dist2;
      s.pdf = pmf;
      s.delta = true;
      return s;
    }
    case LightType::Directional:
      s.wi = -light.vector;
      s.distance = kInf;
      s.radiance = light.value;
      s.pdf = pmf;
      s.delta = true;
      return s;
    case LightType::Environment: {
      const Environment& env = scene.environment;
      s.distance = kInf;
      if (env.texels.empty()) {
        s.wi = sampleUniformSphere(u);
        s.pdf = pmf * kUniformSpherePdf;
      } else {
        float pdf2;
        const Vec2 uv = env.distribution.sample(u, &pdf2);
        s.wi = latLongToDirection(uv);
        const float sinTheta = std::sin(kPi * uv.y);
        if (!(sinTheta > 0) || !(pdf2 > 0)) return {};
        s.pdf = pmf * pdf2 / (2.0f * kPi * kPi * sinTheta);
      }
      s.radiance = environmentRadiance(env, s.wi);
      return s;
    }
  }
  return s;
}

// A shadow ray from receiver p (geometric normal ng) towards a light sample. Towards a point on a
// light it ends short of that point by the same scale-aware margin by which its origin is offset
// from the receiver, so that it never counts the light itself as an occluder.
inline Ray shadowRay(Vec3 p, Vec3 ng, const LightSample& ls) {
  Ray r{offsetOrigin(p, ng, ls.wi), ls.wi};
  if (std::isfinite(ls.distance)) {
    const Vec3 to = ls.point - r.origin;
    const float d = length(to);
    r.direction = to / d;
    r.tMax = d - selfIntersectionScale(ls.point);
  }
  return r;
}

// Density (solid angle, with selection probability) of choosing direction wi towards emissive
// triangle `tri`, hit at distance `dist`.
inline float triangleLightPdf(const Scene& scene, uint32_t tri, Vec3 wi, float dist) {
  const int32_t li = scene.triangleLight[tri];
  if (li < 0) return 0.0f;
  const float cosLight = -dot(wi, scene.geometricNormal(tri));
  if (cosLight <= 0) return 0.0f;
  return scene.lightDistribution.pmf(uint32_t(li)) * dist * dist / (cosLight * scene.triangleArea(tri));
}

inline float environmentLightPdf(const Scene& scene, Vec3 wi) {
  const Environment& env = scene.environment;
  if (!env.present) return 0.0f;
  const float pmf = scene.lightDistribution.pmf(scene.lightDistribution.size() - 1);
  if (env.texels.empty()) return pmf * kUniformSpherePdf;
  const Vec2 uv = directionToLatLong(wi);
  // Not sqrt(1 - y^2): near the poles it loses the digits that sampleLight's sin(pi v) keeps, and y
  // rounds to 1 within 2.4e-4 rad of +y, where the pdf would be 0 for directions that can be sampled.
  const float sinTheta = std::sqrt(wi.x * wi.x + wi.z * wi.z);
  if (!(sinTheta > 0)) return 0.0f;
  return pmf * env.distribution.pdf(uv) / (2.0f * kPi * kPi * sinTheta);
}

// Emission: a ray leaving a light, for photon tracing and virtual point lights.
struct EmissionSample {
  Ray ray;      // origin on the light (or on a disc upstream of the scene), direction of travel
  Rgb power;    // flux of this one sample: Le cos / (selection pmf * area pdf * direction pdf)
  bool valid = false;
};

// Area lights emit cosine-distributed from a uniform point; point lights uniformly over the sphere;
// directional and environment light enter through a disc of the scene's bounding radius R placed
// upstream of the scene, perpendicular to the direction, so that it covers every surface.
inline EmissionSample sampleEmission(const Scene& scene, float uLight, Vec2 uPosition, Vec2 uDirection) {
  EmissionSample s;
  if (scene.lights.empty()) return s;
  float pmf;
  const Light& light = scene.lights[scene.lightDistribution.sampleDiscrete(uLight, &pmf)];
  if (!(pmf > 0)) return s;
  const Vec3 center = scene.boundingCenter();
  const float radius = std::max(scene.boundingRadius(), 1e-6f);
  // Origin on a disc of radius R, perpendicular to `travel`, a distance R upstream of the centre.
  auto discOrigin = [&](Vec3 travel) {
    const Vec2 d = sampleConcentricDisk(uPosition);
    return center - travel * radius + Frame(travel).toWorld({d.x * radius, d.y * radius, 0});
  };
  const float discArea = kPi * radius * radius;
  switch (light.type) {
    case LightType::Triangle: {
      const uint32_t t = light.triangle;
      const Vec2 b = sampleUniformTriangle(uPosition);
      const Vec3 p = scene.vertex(t, 0) * (1 - b.x - b.y) + scene.vertex(t, 1) * b.x + scene.vertex(t, 2) * b.y;
      const Vec3 n = scene.geometricNormal(t);
      const Vec3 d = Frame(n).toWorld(sampleCosineHemisphere(uDirection));
      s.ray = {offsetOrigin(p, n, d), d};
      s.power = scene.materials[scene.materialIds[t]].ke * (kPi * scene.triangleArea(t) / pmf);
      break;
    }
    case LightType::Point:
      s.ray = {light.vector, sampleUniformSphere(uDirection)};
      s.power = light.value * (4.0f * kPi / pmf);
      break;
    case LightType::Directional:
      s.ray = {discOrigin(light.vector), light.vector};
      s.power = light.value * (discArea / pmf);
      break;
    case LightType::Environment: {
      const Environment& env = scene.environment;
      Vec3 toLight;
      float pdf;
      if (env.texels.empty()) {
        toLight = sampleUniformSphere(uDirection);
        pdf = kUniformSpherePdf;
      } else {
        float pdf2;
        const Vec2 uv = env.distribution.sample(uDirection, &pdf2);
        toLight = latLongToDirection(uv);
        const float sinTheta = std::sin(kPi * uv.y);
        if (!(sinTheta > 0) || !(pdf2 > 0)) return s;
        pdf = pdf2 / (2.0f * kPi * kPi * sinTheta);
      }
      s.ray = {discOrigin(-toLight), -toLight};
      s.power = environmentRadiance(env, toLight) * (discArea / (pmf * pdf));
      break;
    }
  }
  s.valid = !s.power.isBlack() && isFinite(s.power);
  return s;
}

}  // namespace lucent
