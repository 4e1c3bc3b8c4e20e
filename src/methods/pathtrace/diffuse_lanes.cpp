#include "diffuse_lanes.h"

#include "lucent/core/math.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/sampling.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/texture.h"
#include "lucent/scene/surface.h"
#include "methods/pathtrace/shading_steps.h"

namespace lucent {

namespace {
void storeLane(Vec3 v, float* x, float* y, float* z, uint32_t k) { x[k] = v.x, y[k] = v.y, z[k] = v.z; }
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

void fetchLambertianSurface(const Scene& s, const Hit& hit, Vec3 direction, DiffuseLanes& l, uint32_t k,
                            std::vector<TexturedLane>& textured) {
  const uint32_t* v = &s.indices[3 * size_t(hit.triangle)];
  storeLane(direction, l.dirX, l.dirY, l.dirZ, k);
  // surfaceAt's arithmetic, up to the normalization of the interpolated normal.
  storeLane(barycentric(s.positions[v[0]], s.positions[v[1]], s.positions[v[2]], hit.b1, hit.b2), l.posX, l.posY, l.posZ, k);
  storeLane(barycentric(s.normals[v[0]], s.normals[v[1]], s.normals[v[2]], hit.b1, hit.b2), l.normalX, l.normalY,
        l.normalZ, k);
  l.hasNormals[k] = !(s.normals[v[0]] == Vec3{0, 0, 0});
  storeLane(s.faceNormals[hit.triangle], l.ngx, l.ngy, l.ngz, k);
  const Material& m = s.materials[s.materialIds[hit.triangle]];
  l.emits[k] = !m.ke.isBlack();
  SurfacePoint sp;
  sp.triangle = hit.triangle, sp.b1 = hit.b1, sp.b2 = hit.b2;
  const Rgb factor = baseFactorAt(s, m, sp);
  if (m.kdTexture < 0) {
    l.kdR[k] = factor.r, l.kdG[k] = factor.g, l.kdB[k] = factor.b;
    return;
  }
  const Texture& t = s.textures[size_t(m.kdTexture)];
  const BilinearFootprint f = bilinearFootprint(t, s.texels.data(), textureUv(s, t, sp));
  for (const uint32_t* texel : {f.row0 + f.x0, f.row0 + f.x1, f.row1 + f.x0, f.row1 + f.x1}) __builtin_prefetch(texel);
  textured.push_back({k, f, factor});
}

void readLaneTextures(DiffuseLanes& l, std::span<const TexturedLane> textured) {
  for (const TexturedLane& t : textured) {
    const Rgb kd = t.kd * bilinear(t.footprint);
    l.kdR[t.lane] = kd.r, l.kdG[t.lane] = kd.g, l.kdB[t.lane] = kd.b;
  }
}

LaneLight laneLight(const Scene& scene, uint32_t light) {
  const Light& l = scene.lights[light];
  if (l.type != LightType::Triangle) return {};
  const Material& m = scene.materials[scene.materialIds[l.triangle]];
  const EmittingTriangle e = emittingTriangle(scene, l.triangle);
  return {e, m.ke, !e.twoSided && m.emissiveTexture < 0 && !(m.clearcoat > 0)};
}

void fetchLaneLight(const LaneLight& light, DiffuseLanes& l, uint32_t k) {
  const EmittingTriangle& e = light.triangle;
  storeLane(e.q0, l.q0x, l.q0y, l.q0z, k);
  storeLane(e.q1, l.q1x, l.q1y, l.q1z, k);
  storeLane(e.q2, l.q2x, l.q2y, l.q2z, k);
  storeLane(e.normal, l.lightNx, l.lightNy, l.lightNz, k);
  l.lightArea[k] = e.area;
  l.leR[k] = light.le.r, l.leG[k] = light.le.g, l.leB[k] = light.le.b;
}

// What PathTracer::shade does at a hit, for a Lambertian surface: the shading normal (surfaceAt's)
// and frame, next-event estimation (sampleDirect, with sampleChosenLight's triangle case where the
// light is a LaneLight), and the next direction (sampleBsdf).
LUCENT_LANE_LOOP(void, shadeDiffuseLanes, (DiffuseLanes& l, uint32_t first, uint32_t last)) {
  const PathStrategy strategy = l.strategy;
  for (uint32_t k = first; k < last; ++k) {
    const Vec3 ng{l.ngx[k], l.ngy[k], l.ngz[k]};
    const Vec3 sn = select(l.hasNormals[k] != 0, orientedShadingNormal({l.normalX[k], l.normalY[k], l.normalZ[k]}, ng), ng);
    const Vec3 woWorld = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]};
    const Frame frame(shadingFrameNormal(woWorld, sn, ng, true));
    storeLane(sn, l.snX, l.snY, l.snZ, k);
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
    storeLane(shadow.origin, l.shadowOx, l.shadowOy, l.shadowOz, k);
    storeLane(shadow.direction, l.shadowDx, l.shadowDy, l.shadowDz, k);
    l.shadowTMax[k] = shadow.tMax;
    l.directR[k] = direct.contribution.r, l.directG[k] = direct.contribution.g, l.directB[k] = direct.contribution.b;

    // The next direction.
    const BsdfSample next = sampleLambertian(kd, wo.z, {l.uBsdfX[k], l.uBsdfY[k]});
    const Vec3 wiWorld = frame.toWorld(next.wi);
    l.scattered[k] = next.valid ? !leaksThroughSurface(woWorld, wiWorld, ng, false) : false;
    l.weightR[k] = next.weight.r, l.weightG[k] = next.weight.g, l.weightB[k] = next.weight.b;
    l.scatterPdf[k] = next.pdf;
    storeLane(offsetOrigin(position, ng, wiWorld), l.nextOx, l.nextOy, l.nextOz, k);
    storeLane(wiWorld, l.nextDx, l.nextDy, l.nextDz, k);
  }
}
LUCENT_LANE_VERSIONS(void, shadeDiffuseLanes, (DiffuseLanes& l, uint32_t first, uint32_t last), (l, first, last))

}  // namespace lucent
