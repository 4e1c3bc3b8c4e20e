// Next-event estimation: sampling a point or direction on the scene's lights from a receiver, and
// the density with which it would have been chosen (for multiple importance sampling).
#pragma once
#include "lucent/core/sampling.h"
#include "lucent/scene/scene.h"
#include "lucent/scene/texture.h"

namespace lucent {

struct LightSample {
  Vec3 wi;              // unit direction from the receiver towards the light
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

}  // namespace lucent
