#include "diffuse_lanes.h"

#include "lucent/core/math.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/sampling.h"

namespace lucent {

namespace {
void store(Vec3 v, float* x, float* y, float* z, uint32_t k) { x[k] = v.x, y[k] = v.y, z[k] = v.z; }
Vec3 select(bool c, Vec3 a, Vec3 b) { return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z}; }
// !Rgb::isBlack, NaN included, as a sum of one-comparison selects: the vectorizer takes neither
// short-circuits nor a chain of selects on different comparisons here.
bool notBlack(Rgb c) { return (c.r != 0 ? 1.0f : 0.0f) + (c.g != 0 ? 1.0f : 0.0f) + (c.b != 0 ? 1.0f : 0.0f) > 0; }
}  // namespace

LUCENT_LANE_LOOP(void, startCameraPaths, (CameraLanes& l, uint32_t first, uint32_t last, SamplerKind sampler,
                  uint64_t seed, const PinholeCamera& camera, bool pixelCentres)) {
  if (sampler == SamplerKind::Sobol) {
    // The pixels' keys and the camera's pair in lanes (PathSampler's arithmetic), the rays, then
    // the samplers.
    alignas(64) float jitterX[kLaneSlots], jitterY[kLaneSlots];
    sobolCameraPairs(seed, l.pixel + first, l.sample + first, last - first, l.pixelKey + first, jitterX + first,
                     jitterY + first);
    for (uint32_t k = first; k < last; ++k) {
      const float jx = pixelCentres ? 0.5f : jitterX[k], jy = pixelCentres ? 0.5f : jitterY[k];
      const Vec3 direction = camera.generate(l.x[k] + jx, l.y[k] + jy).direction;
      l.dirX[k] = direction.x, l.dirY[k] = direction.y, l.dirZ[k] = direction.z;
    }
    for (uint32_t k = first; k < last; ++k) l.sampler[k] = PathSampler::sobol(l.pixelKey[k], l.sample[k]);
    return;
  }
  for (uint32_t k = first; k < last; ++k) {
    PathSampler s(sampler, seed, l.pixel[k], l.sample[k]);
    const Vec2 uniform = s.camera();  // drawn either way: the path's later numbers do not move
    const Vec2 jitter = pixelCentres ? Vec2{0.5f, 0.5f} : uniform;
    const Vec3 direction = camera.generate(l.x[k] + jitter.x, l.y[k] + jitter.y).direction;
    l.sampler[k] = s;
    l.dirX[k] = direction.x, l.dirY[k] = direction.y, l.dirZ[k] = direction.z;
  }
}
LUCENT_LANE_VERSIONS(void, startCameraPaths, (CameraLanes& l, uint32_t first, uint32_t last, SamplerKind sampler,
                  uint64_t seed, const PinholeCamera& camera, bool pixelCentres),
                     (l, first, last, sampler, seed, camera, pixelCentres))

// The rest of surfaceAt (the shading normal), the start of PathTracer::shade for a two-sided
// material, then next-event estimation as PathTracer::sampleDirect (the emitting triangle's sample
// as sampleLight takes it) and sampleBsdf's Lambertian case, with shadowRay and offsetOrigin.
LUCENT_LANE_LOOP(void, shadeDiffuseLanes, (DiffuseLanes& l)) {
  const bool lightOnly = l.strategy == PathStrategy::LightSampling, bsdfOnly = l.strategy == PathStrategy::BsdfSampling;
  for (uint32_t k = 0; k < l.count; ++k) {
    const Vec3 ng = Vec3{l.ngx[k], l.ngy[k], l.ngz[k]};
    const Vec3 interpolated{l.normalX[k], l.normalY[k], l.normalZ[k]};
    const float len = length(interpolated);
    Vec3 sn = select(len > 0, interpolated / len, ng);
    sn = select(dot(sn, ng) < 0, -sn, sn);
    sn = select(l.hasNormals[k] != 0, sn, ng);

    const Vec3 woWorld = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]};
    const bool frontFace = dot(woWorld, ng) > 0;
    Vec3 shadingN = select(dot(woWorld, sn) * dot(woWorld, ng) > 0, sn, ng);
    shadingN = select(frontFace, shadingN, -shadingN);
    const Frame frame(shadingN);
    store(sn, l.snX, l.snY, l.snZ, k);
    l.frontFace[k] = frontFace;

    const Vec3 position = Vec3{l.posX[k], l.posY[k], l.posZ[k]};
    const Vec3 s = frame.s, t = frame.t, n = frame.n;
    const Vec3 wo = frame.toLocal(woWorld);
    const Rgb kd{l.kdR[k], l.kdG[k], l.kdB[k]};

    // The light sample: a uniform point on the emitting triangle, or the one fetched.
    const Vec2 b = sampleUniformTriangle({l.uLightX[k], l.uLightY[k]});
    const Vec3 q = barycentric(Vec3{l.q0x[k], l.q0y[k], l.q0z[k]}, Vec3{l.q1x[k], l.q1y[k], l.q1z[k]},
                               Vec3{l.q2x[k], l.q2y[k], l.q2z[k]}, b.x, b.y);
    const Vec3 toLight = q - position;
    const float dist2 = dot(toLight, toLight);
    const float triangleDistance = std::sqrt(dist2);
    const Vec3 triangleWi = toLight / triangleDistance;
    const float cosLight = -dot(triangleWi, Vec3{l.lightNx[k], l.lightNy[k], l.lightNz[k]});
    // sampleLight returns no sample (pdf 0) for the triangle's back or a zero distance.
    const float trianglePdf =
        cosLight <= 0 ? 0.0f : !(dist2 > 0) ? 0.0f : l.lightPmf[k] * dist2 / (cosLight * l.lightArea[k]);
    const bool onTriangle = l.lightIsTriangle[k] != 0;
    const Vec3 wi = select(onTriangle, triangleWi, Vec3{l.wiX[k], l.wiY[k], l.wiZ[k]});
    const float fetchedDistance = l.lightDistance[k], fetchedPdf = l.lightPdf[k];
    const float distance = onTriangle ? triangleDistance : fetchedDistance;
    const Vec3 point = select(onTriangle, q, Vec3{l.pointX[k], l.pointY[k], l.pointZ[k]});
    const float pdf = onTriangle ? trianglePdf : fetchedPdf;
    const Rgb le{l.leR[k], l.leG[k], l.leB[k]};

    // evalBsdf and bsdfPdf: zero unless both directions are above the surface. Conditions are
    // chained selects, not boolean algebra, which the vectorizer does not take.
    const Vec3 wiLocal{dot(wi, s), dot(wi, t), dot(wi, n)};  // Frame::toLocal
    const float bothAbove = wo.z <= 0 ? 0.0f : wiLocal.z <= 0 ? 0.0f : 1.0f;
    const Rgb f{bothAbove == 0 ? 0.0f : kd.r * kInvPi, bothAbove == 0 ? 0.0f : kd.g * kInvPi,
                bothAbove == 0 ? 0.0f : kd.b * kInvPi};
    const float lambertPdf = bothAbove == 0 ? 0.0f : cosineHemispherePdf(wiLocal.z);
    // Point and directional lights cannot be hit: weight 1, as with light sampling alone. BSDF
    // sampling alone samples only them (a pdf of 0 queues no shadow ray). Selects chained on one
    // comparison each, for the vectorizer.
    const float mis = powerHeuristic(pdf, lambertPdf);
    const float misWeight = lightOnly ? 1.0f : mis;
    const float w = onTriangle ? misWeight : l.lightDelta[k] != 0 ? 1.0f : misWeight;
    const float deltaLight = onTriangle ? 0.0f : l.lightDelta[k] != 0 ? 1.0f : 0.0f;
    const float queuedPdf = pdf * (bsdfOnly ? deltaLight : 1.0f);
    const Rgb direct = f * le * (wiLocal.z * w / pdf);
    // sampleDirect's tests, in its order.
    l.shadowQueued[k] = !(queuedPdf > 0)                ? 0
                        : !notBlack(le)                 ? 0
                        : wiLocal.z <= 0                ? 0
                        : dot(wi, ng) * dot(n, ng) <= 0 ? 0
                        : notBlack(f)                   ? 1
                                                        : 0;
    const Vec3 origin = offsetOrigin(position, ng, wi);
    const Vec3 toPoint = point - origin;
    const float pointDistance = length(toPoint);
    const bool finite = distance < kInf;
    store(origin, l.shadowOx, l.shadowOy, l.shadowOz, k);
    store(select(finite, toPoint / pointDistance, wi), l.shadowDx, l.shadowDy, l.shadowDz, k);
    l.shadowTMax[k] = finite ? pointDistance - selfIntersectionScale(point) : kInf;
    l.directR[k] = direct.r, l.directG[k] = direct.g, l.directB[k] = direct.b;

    // The next direction, cosine-distributed.
    const Vec3 wiNext = sampleCosineHemisphere({l.uBsdfX[k], l.uBsdfY[k]});
    // sampleBsdf: no sample unless both directions are above the surface and the pdf is positive.
    const float scatterPdf = wo.z <= 0 ? 0.0f : wiNext.z <= 0 ? 0.0f : cosineHemispherePdf(wiNext.z);
    const Rgb weight = kd * kInvPi * (wiNext.z / scatterPdf);
    const Vec3 wiWorld = s * wiNext.x + t * wiNext.y + n * wiNext.z;  // Frame::toWorld
    // shade's test against leaks; with both local directions above the surface nothing transmits.
    l.scattered[k] = scatterPdf > 0 ? (dot(wiWorld, ng) * dot(woWorld, ng) < 0 ? 0 : 1) : 0;
    l.weightR[k] = weight.r, l.weightG[k] = weight.g, l.weightB[k] = weight.b;
    l.scatterPdf[k] = scatterPdf;
    store(offsetOrigin(position, ng, wiWorld), l.nextOx, l.nextOy, l.nextOz, k);
    store(wiWorld, l.nextDx, l.nextDy, l.nextDz, k);
  }
}
LUCENT_LANE_VERSIONS(void, shadeDiffuseLanes, (DiffuseLanes& l), (l))

}  // namespace lucent
