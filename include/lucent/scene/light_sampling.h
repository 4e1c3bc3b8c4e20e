// Next-event estimation: sampling a point or direction on the scene's lights from a receiver, and
// the density with which it would have been chosen (for multiple importance sampling).
#pragma once
#include <algorithm>

#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/scene.h"
#include "lucent/scene/surface.h"
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

// A point, spot or directional light as seen from a receiver: the one direction it arrives from, its
// radiance there, pdf 1 (before the light's selection probability).
inline LightSample deltaLightSample(const Light& light, Vec3 receiver) {
  LightSample s;
  s.delta = true;
  s.pdf = 1;
  if (light.type == LightType::Directional) {
    s.wi = -light.vector;
    s.distance = kInf;
    s.radiance = light.value;
    return s;
  }
  const Vec3 d = light.vector - receiver;
  const float dist2 = dot(d, d);
  s.point = light.vector;
  s.distance = std::sqrt(dist2);
  s.wi = d / s.distance;
  s.radiance = light.value / dist2;
  if (light.type == LightType::Spot) s.radiance = s.radiance * spotFalloff(light, -s.wi);
  return s;
}

// The squared distance from a receiver to a point or spot light, at least 1e-12 of the light's
// position's scale squared (a receiver at the light).
inline double nearbyWeightDistance2(const Light& light, Vec3 receiver) {
  const Vec3 d = light.vector - receiver;
  const double scale = std::max({1.0f, std::abs(light.vector.x), std::abs(light.vector.y), std::abs(light.vector.z)});
  return std::max(double(dot(d, d)), 1e-12 * scale * scale);
}

// A uniformly chosen point on an emitting triangle (vertices q0, q1, q2, unit normal, area) seen
// from receiver, chosen with probability pmf: the point and its barycentrics, the unit direction
// and distance to it, and the density (solid angle, times pmf); the density is 0 where the receiver
// sees the back of a one-sided emitter (twoSided false) or lies on the triangle. Selects only: the
// path tracer's lane loop vectorizes it (shadeDiffuseLanes), and sampleChosenLight calls it.
struct TrianglePointSample {
  Vec3 point, wi;
  float distance, pdf;
  Vec2 b;
};
[[gnu::always_inline]]
inline TrianglePointSample sampleTrianglePoint(Vec3 q0, Vec3 q1, Vec3 q2, Vec3 normal, float area, float pmf,
                                               Vec3 receiver, Vec2 u, bool twoSided = false) {
  const Vec2 b = sampleUniformTriangle(u);
  const Vec3 q = barycentric(q0, q1, q2, b.x, b.y);
  const Vec3 d = q - receiver;
  const float dist2 = dot(d, d);
  const float distance = std::sqrt(dist2);
  const Vec3 wi = d / distance;
  const float facing = -dot(wi, normal);
  const float cosLight = twoSided ? std::abs(facing) : facing;
  const float pdf = cosLight <= 0 ? 0.0f : !(dist2 > 0) ? 0.0f : pmf * dist2 / (cosLight * area);
  return {q, wi, distance, pdf, b};
}

// An emitting triangle as sampleTrianglePoint takes it.
struct EmittingTriangle {
  Vec3 q0, q1, q2, normal;
  float area = 0;
  bool twoSided = false;  // its material emits from its back too (Material::emitsBackFace)
};
inline EmittingTriangle emittingTriangle(const Scene& scene, uint32_t t) {
  return {scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2), scene.geometricNormal(t), scene.triangleArea(t),
          scene.materials[scene.materialIds[t]].emitsBackFace != 0};
}

// A sample of light `li`, chosen with probability `pmf` (its pdf includes it).
inline LightSample sampleChosenLight(const Scene& scene, uint32_t li, float pmf, Vec3 receiver, Vec2 u) {
  LightSample s;
  const Light& light = scene.lights[li];
  switch (light.type) {
    case LightType::Triangle: {
      const uint32_t t = light.triangle;
      const EmittingTriangle e = emittingTriangle(scene, t);
      const TrianglePointSample q = sampleTrianglePoint(e.q0, e.q1, e.q2, e.normal, e.area, pmf, receiver, u, e.twoSided);
      if (!(q.pdf > 0)) return {};
      s.point = q.point, s.wi = q.wi, s.distance = q.distance, s.pdf = q.pdf;
      s.radiance = emittedRadiance(scene, t, q.b.x, q.b.y, -q.wi);
      return s;
    }
    case LightType::Point:
    case LightType::Spot:
    case LightType::Directional:
      s = deltaLightSample(light, receiver);
      s.pdf = pmf;
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

// A light for a receiver, and the probability of choosing it.
struct LightChoice {
  uint32_t light = 0;
  float pmf = 0;
};

// The light a receiver samples (of a scene with lights), by the scene's light distribution (by
// power): the grid cell of u picks it (Distribution1D). Where the scene has two or more point and
// spot lights (Scene::nearbyLights), their cells together are shared out again for each receiver, in
// proportion to each one's power over its squared distance from the receiver, its unoccluded
// light's share there, and at least one cell each (a point light is never lost, however far): in
// the maze, the light beyond a corridor's wall takes most of the samples where it is near, not half
// everywhere. The other lights keep their cells, so their probabilities, which MIS reads back at
// emitter hits (triangleLightPdf, environmentLightPdf). `remapped`, if given, receives u rescaled to
// [0, 1) within the chosen light's cells: a number as uniform as u, and independent of the choice.
inline LightChoice chooseLight(const Scene& scene, Vec3 receiver, float u, float* remapped = nullptr) {
  const Distribution1D& power = scene.lightDistribution;
  const uint32_t cell = Distribution1D::cellOf(u);
  const uint32_t li = power.pickCell(cell);
  const bool nearby = std::binary_search(scene.nearbyLights.begin(), scene.nearbyLights.end(), li);
  double weights[kMostNearbyLights], total = 0;
  uint32_t cells = 0, place = 0, owners = 0;
  const size_t count = nearby ? scene.nearbyLights.size() : 0;
  for (size_t k = 0; k < count; ++k) {  // u's place among the nearby lights' cells laid side by side
    const uint32_t i = scene.nearbyLights[k];
    if (i == li) place = cells + (cell - power.firstCell(i));
    cells += power.cellCount(i);
    total += weights[k] = power.pmf(i) / nearbyWeightDistance2(scene.lights[i], receiver);
    owners += weights[k] > 0;
  }
  if (!(total > 0)) {  // a far light, or no nearby light weighs anything here: by power alone
    if (remapped) *remapped = power.remap(li, u);
    return {li, power.pmf(li)};
  }
  double before = 0;
  uint32_t ownersBefore = 0, first = 0;
  for (size_t k = 0; k < count; ++k) {
    const uint32_t last = k + 1 == count ? cells
                                         : Distribution1D::sharedCell(before + weights[k], total,
                                                                      ownersBefore + (weights[k] > 0), owners, cells);
    if (place < last) {
      if (remapped) {
        const double position = double(place) + (double(u) * Distribution1D::kCells - cell);
        *remapped = std::clamp(float((position - first) / (last - first)), 0.0f, 0x1.fffffep-1f);
      }
      return {scene.nearbyLights[k], float(last - first) * 0x1p-24f};
    }
    before += weights[k], ownersBefore += weights[k] > 0, first = last;
  }
  return {li, power.pmf(li)};  // not reached: `place` lies below `cells`
}

// chooseLight by the distribution `choice` over the scene's lights (the path tracer's learnt one,
// PathTracer::useLightChoice) where the scene has no nearby lights; by the scene's where it has.
inline LightChoice chooseLight(const Scene& scene, const Distribution1D& choice, Vec3 receiver, float u,
                               float* remapped = nullptr) {
  if (!scene.nearbyLights.empty()) return chooseLight(scene, receiver, u, remapped);
  const uint32_t li = choice.pick(u);
  if (remapped) *remapped = choice.remap(li, u);
  return {li, choice.pmf(li)};
}

// A light chosen for the receiver (chooseLight), and a sample of it.
inline LightSample sampleLight(const Scene& scene, Vec3 receiver, float uLight, Vec2 u) {
  if (scene.lights.empty()) return {};
  const LightChoice choice = chooseLight(scene, receiver, uLight);
  return sampleChosenLight(scene, choice.light, choice.pmf, receiver, u);
}

// A shadow ray from receiver p (geometric normal ng) towards a light sample. Towards a point on a
// light it ends short of that point by the same scale-aware margin by which its origin is offset
// from the receiver, so that it never counts the light itself as an occluder.
// Selects only: the path tracer's lane loop vectorizes it (shadeDiffuseLanes).
[[gnu::always_inline]] inline Ray shadowRay(Vec3 p, Vec3 ng, Vec3 wi, Vec3 lightPoint, float lightDistance) {
  const Vec3 origin = offsetOrigin(p, ng, wi);
  const Vec3 to = lightPoint - origin;
  const float d = length(to);
  const bool finite = lightDistance < kInf;
  Ray r{origin, select(finite, to / d, wi)};
  r.tMax = finite ? d - selfIntersectionScale(lightPoint) : kInf;
  return r;
}
inline Ray shadowRay(Vec3 p, Vec3 ng, const LightSample& ls) { return shadowRay(p, ng, ls.wi, ls.point, ls.distance); }

// Density (solid angle, with selection probability) of choosing direction wi towards emissive
// triangle `tri`, hit at distance `dist`.
inline float triangleLightPdf(const Scene& scene, const Distribution1D& choice, uint32_t tri, Vec3 wi, float dist) {
  const int32_t li = scene.triangleLight[tri];
  if (li < 0) return 0.0f;
  const float facing = -dot(wi, scene.geometricNormal(tri));
  const float cosLight = scene.materials[scene.materialIds[tri]].emitsBackFace != 0 ? std::abs(facing) : facing;
  if (cosLight <= 0) return 0.0f;
  return choice.pmf(uint32_t(li)) * dist * dist / (cosLight * scene.triangleArea(tri));
}
inline float triangleLightPdf(const Scene& scene, uint32_t tri, Vec3 wi, float dist) {
  return triangleLightPdf(scene, scene.lightDistribution, tri, wi, dist);
}

inline float environmentLightPdf(const Scene& scene, const Distribution1D& choice, Vec3 wi) {
  const Environment& env = scene.environment;
  if (!env.present) return 0.0f;
  const float pmf = choice.pmf(choice.size() - 1);
  if (env.texels.empty()) return pmf * kUniformSpherePdf;
  const Vec2 uv = directionToLatLong(wi);
  // Not sqrt(1 - y^2): near the poles it loses the digits that sampleLight's sin(pi v) keeps, and y
  // rounds to 1 within 2.4e-4 rad of +y, where the pdf would be 0 for directions that can be sampled.
  const float sinTheta = std::sqrt(wi.x * wi.x + wi.z * wi.z);
  if (!(sinTheta > 0)) return 0.0f;
  return pmf * env.distribution.pdf(uv) / (2.0f * kPi * kPi * sinTheta);
}
inline float environmentLightPdf(const Scene& scene, Vec3 wi) {
  return environmentLightPdf(scene, scene.lightDistribution, wi);
}

// Emission: a ray leaving a light, for photon tracing and virtual point lights.
struct EmissionSample {
  Ray ray;      // origin on the light (or on a disc upstream of the scene), direction of travel
  Rgb power;    // flux of this one sample: Le cos / (selection pmf * area pdf * direction pdf)
  bool valid = false;
};

// A sphere that emission can be aimed at: Jensen's projection maps reduced to one bounding sphere
// of the specular objects. A caustic path's first hit is specular, so its direction from the light
// lies in the cone the sphere subtends, and emitting only into that cone (with the cone's density)
// samples every caustic path at a fraction of the cost.
//
// A point light's emission is aimed more tightly by a projection map (Jensen 1996): the plane
// z = 1 in front of the light, about the sphere's axis, divided into cells, of which those that a
// specular triangle's projection (gnomonic, which keeps triangles triangles) may touch are marked.
// Directions are drawn through a uniformly chosen marked cell, uniformly over its area: the
// density per solid angle is 1 / (marked cells x cell area x cos^3 theta). The sphere alone lets
// through the ring of RING's hole and its surroundings (2 in 5 of its photons reach the ring).
struct ProjectionMap {
  Frame frame;                  // z towards the target, from the light
  float extent = 0;             // the plane's square [-extent, extent]^2 holds the target's cone
  uint32_t resolution = 0;      // cells per side
  std::vector<uint32_t> cells;  // marked cells, y * resolution + x; none: the map is not used
  float cellSide() const { return 2 * extent / float(resolution); }
};

struct EmissionTarget {
  Vec3 center;
  float radius = 0;
  std::vector<ProjectionMap> pointLightMaps;  // per light (a point light's may have cells)
};

// The cone of directions from x towards the target; false when x lies inside the sphere.
struct TargetCone {
  Frame frame;       // axis towards the centre
  float cosMax = 1;  // cosine of the half-angle
  float solidAngle = 0;
};
inline bool coneTowards(const EmissionTarget& target, Vec3 x, TargetCone& cone) {
  const Vec3 d = target.center - x;
  const float dist2 = dot(d, d), sin2 = target.radius * target.radius / dist2;
  if (!(sin2 < 1)) return false;
  cone.cosMax = std::sqrt(1 - sin2);
  cone.solidAngle = 2 * kPi * sin2 / (1 + cone.cosMax);  // 2 pi (1 - cosMax), without cancellation
  cone.frame = Frame(d / std::sqrt(dist2));
  return true;
}

// Area lights emit cosine-distributed from a uniform point; point lights uniformly over the sphere;
// directional and environment light enter through a disc of the scene's bounding radius R placed
// upstream of the scene, perpendicular to the direction, so that it covers every surface.
// With a target, area and point lights emit uniformly into the target's cone (when the emitting
// point lies outside the sphere; a point light with a projection map through its marked cells)
// and directional and environment light enter through a disc of the target's radius in front of
// it: only paths whose first hit lies in the sphere are sampled.
// targetBits, 32 random bits, pick a projection map's cell (with a bias of cells / 2^32 at most:
// a float's 24 bits would give cells / 2^24).
// (A target comes with its bits: no default that a caller could forget, sending every photon
// through the first marked cell.)
inline EmissionSample sampleEmission(const Scene& scene, float uLight, Vec2 uPosition, Vec2 uDirection,
                                     const EmissionTarget* target, uint32_t targetBits) {
  EmissionSample s;
  if (scene.lights.empty()) return s;
  float pmf;
  const uint32_t lightIndex = scene.lightDistribution.sampleDiscrete(uLight, &pmf);
  const Light& light = scene.lights[lightIndex];
  if (!(pmf > 0)) return s;
  const Vec3 sceneCenter = scene.boundingCenter();
  const float sceneRadius = std::max(scene.boundingRadius(), 1e-6f);
  // The disc that directional and environment light enter through: the scene's, or the target's
  // moved upstream until it lies outside the scene's bounding sphere.
  const Vec3 discCenter = target ? target->center : sceneCenter;
  const float discRadius = target ? target->radius : sceneRadius;
  const float upstream = target ? length(target->center - sceneCenter) + sceneRadius : sceneRadius;
  auto discOrigin = [&](Vec3 travel) {
    const Vec2 d = sampleConcentricDisk(uPosition);
    return discCenter - travel * upstream + Frame(travel).toWorld({d.x * discRadius, d.y * discRadius, 0});
  };
  const float discArea = kPi * discRadius * discRadius;
  TargetCone cone;
  switch (light.type) {
    case LightType::Triangle: {
      const uint32_t t = light.triangle;
      const Vec2 b = sampleUniformTriangle(uPosition);
      const Vec3 p = barycentric(scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2), b.x, b.y);
      const Vec3 n = scene.geometricNormal(t);
      const bool twoSided = scene.materials[scene.materialIds[t]].emitsBackFace != 0;
      if (target && coneTowards(*target, p, cone)) {
        const Vec3 d = cone.frame.toWorld(sampleUniformCone(uDirection, cone.cosMax));
        const float cosTheta = std::abs(dot(d, n));
        const Rgb le = emittedRadiance(scene, t, b.x, b.y, d);  // black behind a one-sided emitter
        if (!(cosTheta > 0) || le.isBlack()) return s;
        s.ray = {offsetOrigin(p, n, d), d};
        s.power = le * (cosTheta * cone.solidAngle * scene.triangleArea(t) / pmf);
        break;
      }
      // A two-sided emitter: a face chosen by the first direction number's upper half, which is
      // then rescaled to [0, 1) for the cosine sample (each face emits pi A Le).
      Vec2 u = uDirection;
      bool front = true;
      if (twoSided) {
        front = u.x < 0.5f;
        u.x = std::min(2.0f * u.x - (front ? 0.0f : 1.0f), 0x1.fffffep-1f);
      }
      const Vec3 d = Frame(front ? n : -n).toWorld(sampleCosineHemisphere(u));
      s.ray = {offsetOrigin(p, n, d), d};
      s.power = emittedRadiance(scene, t, b.x, b.y, d) * ((twoSided ? 2.0f : 1.0f) * kPi * scene.triangleArea(t) / pmf);
      break;
    }
    case LightType::Point:
      if (target && lightIndex < target->pointLightMaps.size() && !target->pointLightMaps[lightIndex].cells.empty()) {
        const ProjectionMap& map = target->pointLightMaps[lightIndex];
        const uint32_t marked = uint32_t(map.cells.size());
        const uint32_t cell = map.cells[uniformBelow(targetBits, marked)];
        const float side = map.cellSide();
        const float x = -map.extent + (float(cell % map.resolution) + uDirection.x) * side;
        const float y = -map.extent + (float(cell / map.resolution) + uDirection.y) * side;
        const float cosTheta = 1.0f / std::sqrt(1 + x * x + y * y);
        s.ray = {light.vector, map.frame.toWorld(Vec3(x * cosTheta, y * cosTheta, cosTheta))};
        s.power = light.value * (float(marked) * side * side * cosTheta * cosTheta * cosTheta / pmf);
        break;
      }
      if (target && coneTowards(*target, light.vector, cone)) {
        s.ray = {light.vector, cone.frame.toWorld(sampleUniformCone(uDirection, cone.cosMax))};
        s.power = light.value * (cone.solidAngle / pmf);
        break;
      }
      s.ray = {light.vector, sampleUniformSphere(uDirection)};
      s.power = light.value * (4.0f * kPi / pmf);
      break;
    case LightType::Spot: {
      // Uniformly within the cone where the falloff is not 0, weighted by it.
      const float cosOuter = light.angleScale > 0 ? -light.angleOffset / light.angleScale : -1.0f;
      const Vec3 d = Frame(light.axis).toWorld(sampleUniformCone(uDirection, cosOuter));
      s.ray = {light.vector, d};
      s.power = light.value * (spotFalloff(light, d) * 2.0f * kPi * (1.0f - cosOuter) / pmf);
      break;
    }
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

// Without a target: every light emits over its whole range.
inline EmissionSample sampleEmission(const Scene& scene, float uLight, Vec2 uPosition, Vec2 uDirection) {
  return sampleEmission(scene, uLight, uPosition, uDirection, nullptr, 0);
}

}  // namespace lucent
