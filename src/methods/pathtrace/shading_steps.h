// The steps of shading a hit that PathTracer::shade (one path at a time, every material) and the
// lanes (shadeDiffuseLanes, Lambertian hits many at a time) share, beside the scene layer's
// orientedShadingNormal, shadingFrameNormal, leaksThroughSurface, lambertianValue, sampleLambertian,
// sampleTrianglePoint and shadowRay. Each is written once, with selects only, so that the compiler
// vectorizes in the lane loop the very function the one-path code calls.
#pragma once
#include "lucent/core/math.h"
#include "lucent/core/path_sampler.h"
#include "lucent/core/sampling.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/bsdf.h"

namespace lucent {

// !Rgb::isBlack, NaN included, as a sum of one-comparison selects: the vectorizer takes neither
// short-circuits nor a chain of selects on different comparisons here.
inline bool anyNonZero(Rgb c) {
  return (c.r != 0 ? 1.0f : 0.0f) + (c.g != 0 ? 1.0f : 0.0f) + (c.b != 0 ? 1.0f : 0.0f) > 0;
}

// Next-event estimation's light sample at a hit, weighed: the light's density lightPdf (with its
// selection probability), a delta light (point or directional: BSDF sampling cannot hit it) or
// not, its radiance le from direction wi (wiLocal in the shading frame of normal n, geometric
// normal ng), and the BSDF's value and density there. What it brings if its shadow ray is
// unoccluded (before the path's throughput), and whether that ray is worth tracing: not when the
// sample or the BSDF is zero, when wi is below the shading or the geometric surface (unless the lobe
// transmits and wi is below both), or when the strategy is BSDF sampling alone and the light could
// be hit by it. Conditions are float or int
// selects, each on one comparison, and the BSDF's weight is computed before it is selected: the
// vectorizer left the lane loop scalar with bool chains or a call inside a select's arm.
struct NextEventSample {
  Rgb contribution;
  bool queued;
};
[[gnu::always_inline]]
inline NextEventSample weighLightSample(PathStrategy strategy, float lightPdf, bool lightDelta, Rgb le, Vec3 wi,
                                        Vec3 wiLocal, Vec3 n, Vec3 ng, BsdfValue bsdf, bool transmits = false) {
  const float delta = lightDelta ? 1.0f : 0.0f;
  const float mis = powerHeuristic(lightPdf, bsdf.pdf);
  const float misWeight = strategy == PathStrategy::LightSampling ? 1.0f : mis;
  const float w = delta != 0 ? 1.0f : misWeight;
  const float queuedPdf = lightPdf * (strategy == PathStrategy::BsdfSampling ? delta : 1.0f);
  const float cosine = receivingCosine(wi, wiLocal, n, ng, transmits);
  const int queued = !(queuedPdf > 0)     ? 0
                     : !anyNonZero(le)    ? 0
                     : cosine <= 0        ? 0
                     : anyNonZero(bsdf.f) ? 1
                                          : 0;
  return {bsdf.f * le * (cosine * w / lightPdf), queued != 0};
}

// The numbers a bounce at a surface draws, in the one order that PathTracer::shade (every material)
// and fetchLane (Lambertian hits, for the lanes) both take them in: the light point's pair
// where the surface takes a light sample (not at a mirror or glass), the lobe's choice, the BSDF
// direction's pair. With the independent sampler this is the order of the path's generator.
struct BounceNumbers {
  Vec2 lightPoint;
  float lobe = 0;
  Vec2 bsdfDirection;
};

inline BounceNumbers drawBounceNumbers(PathSampler& sampler, int bounce, bool samplesLight) {
  BounceNumbers u;
  if (samplesLight) u.lightPoint = sampler.uniform2(bounce, SampleUse::LightPoint);
  u.lobe = sampler.uniform(bounce, SampleUse::Lobe);
  u.bsdfDirection = sampler.uniform2(bounce, SampleUse::BsdfDirection);
  return u;
}

}  // namespace lucent
