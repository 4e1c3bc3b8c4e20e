#include "diffuse_lanes.h"

#include "lucent/core/math.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/surface.h"
#include "methods/pathtrace/shading_steps.h"

namespace lucent {

namespace {
void store(Vec3 v, float* x, float* y, float* z, uint32_t k) { x[k] = v.x, y[k] = v.y, z[k] = v.z; }
}  // namespace

LUCENT_LANE_LOOP(void, startCameraPaths, (CameraLanes& l, uint32_t first, uint32_t last, SamplerKind sampler,
                  uint64_t seed, const PinholeCamera& camera, const PixelFilter& filter, bool pixelCentres)) {
  if (sampler == SamplerKind::Sobol) {
    // The pixels' keys and the camera's pair in lanes (PathSampler's arithmetic), the rays, then
    // the samplers.
    alignas(64) float jitterX[kLaneSlots], jitterY[kLaneSlots];
    sobolCameraPairs(seed, l.streamPixel + first, l.sample + first, last - first, l.pixelKey + first, jitterX + first,
                     jitterY + first);
    for (uint32_t k = first; k < last; ++k) {
      const Vec2 at = pixelCentres ? Vec2{0.5f, 0.5f} : filter.position({jitterX[k], jitterY[k]}, l.filterWeight[k]);
      if (pixelCentres) l.filterWeight[k] = 1;
      const Vec3 direction = camera.generate(l.x[k] + at.x, l.y[k] + at.y).direction;
      l.dirX[k] = direction.x, l.dirY[k] = direction.y, l.dirZ[k] = direction.z;
    }
    for (uint32_t k = first; k < last; ++k) l.sampler[k] = PathSampler::sobol(l.pixelKey[k], l.sample[k]);
    return;
  }
  for (uint32_t k = first; k < last; ++k) {
    PathSampler s(sampler, seed, l.streamPixel[k], l.sample[k]);
    const Vec2 uniform = s.camera();  // drawn either way: the path's later numbers do not move
    const Vec2 at = pixelCentres ? Vec2{0.5f, 0.5f} : filter.position(uniform, l.filterWeight[k]);
    if (pixelCentres) l.filterWeight[k] = 1;
    const Vec3 direction = camera.generate(l.x[k] + at.x, l.y[k] + at.y).direction;
    l.sampler[k] = s;
    l.dirX[k] = direction.x, l.dirY[k] = direction.y, l.dirZ[k] = direction.z;
  }
}
LUCENT_LANE_VERSIONS(void, startCameraPaths, (CameraLanes& l, uint32_t first, uint32_t last, SamplerKind sampler,
                  uint64_t seed, const PinholeCamera& camera, const PixelFilter& filter, bool pixelCentres),
                     (l, first, last, sampler, seed, camera, filter, pixelCentres))

// What PathTracer::shade does at a Lambertian hit, with the functions it calls: the shading
// normal (surfaceAt's) and frame, next-event estimation (sampleDirect, with sampleLight's triangle
// case where the light is an emitting triangle), and the next direction (sampleBsdf).
LUCENT_LANE_LOOP(void, shadeDiffuseLanes, (DiffuseLanes& l)) {
  const PathStrategy strategy = l.strategy;
  for (uint32_t k = 0; k < l.count; ++k) {
    const Vec3 ng{l.ngx[k], l.ngy[k], l.ngz[k]};
    const Vec3 sn = select(l.hasNormals[k] != 0, orientedShadingNormal({l.normalX[k], l.normalY[k], l.normalZ[k]}, ng), ng);
    const Vec3 woWorld = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]};
    const Frame frame(shadingFrameNormal(woWorld, sn, ng, true));
    store(sn, l.snX, l.snY, l.snZ, k);
    l.frontFace[k] = dot(woWorld, ng) > 0;
    const Vec3 position{l.posX[k], l.posY[k], l.posZ[k]};
    const Vec3 wo = frame.toLocal(woWorld);
    const Rgb kd{l.kdR[k], l.kdG[k], l.kdB[k]};

    // The light sample: a point on the emitting triangle, or the one fetched.
    const TrianglePointSample q = sampleTrianglePoint(
        {l.q0x[k], l.q0y[k], l.q0z[k]}, {l.q1x[k], l.q1y[k], l.q1z[k]}, {l.q2x[k], l.q2y[k], l.q2z[k]},
        {l.lightNx[k], l.lightNy[k], l.lightNz[k]}, l.lightArea[k], l.lightPmf[k], position, {l.uLightX[k], l.uLightY[k]});
    const bool onTriangle = l.lightIsTriangle[k] != 0;
    const Vec3 wi = select(onTriangle, q.wi, {l.wiX[k], l.wiY[k], l.wiZ[k]});
    const Vec3 point = select(onTriangle, q.point, {l.pointX[k], l.pointY[k], l.pointZ[k]});
    const float distance = onTriangle ? q.distance : l.lightDistance[k];
    const float pdf = onTriangle ? q.pdf : l.lightPdf[k];
    const bool delta = l.lightDelta[k] != 0;
    const Rgb le{l.leR[k], l.leG[k], l.leB[k]};
    const Vec3 wiLocal = frame.toLocal(wi);
    const NextEventSample direct =
        weighLightSample(strategy, pdf, delta, le, wi, wiLocal, frame.n, ng, lambertianValue(kd, wo.z, wiLocal.z));
    l.shadowQueued[k] = direct.queued;
    const Ray shadow = shadowRay(position, ng, wi, point, distance);
    store(shadow.origin, l.shadowOx, l.shadowOy, l.shadowOz, k);
    store(shadow.direction, l.shadowDx, l.shadowDy, l.shadowDz, k);
    l.shadowTMax[k] = shadow.tMax;
    l.directR[k] = direct.contribution.r, l.directG[k] = direct.contribution.g, l.directB[k] = direct.contribution.b;

    // The next direction.
    const BsdfSample next = sampleLambertian(kd, wo.z, {l.uBsdfX[k], l.uBsdfY[k]});
    const Vec3 wiWorld = frame.toWorld(next.wi);
    l.scattered[k] = next.valid ? !leaksThroughSurface(woWorld, wiWorld, ng, false) : false;
    l.weightR[k] = next.weight.r, l.weightG[k] = next.weight.g, l.weightB[k] = next.weight.b;
    l.scatterPdf[k] = next.pdf;
    store(offsetOrigin(position, ng, wiWorld), l.nextOx, l.nextOy, l.nextOz, k);
    store(wiWorld, l.nextDx, l.nextDy, l.nextDz, k);
  }
}
LUCENT_LANE_VERSIONS(void, shadeDiffuseLanes, (DiffuseLanes& l), (l))

}  // namespace lucent
