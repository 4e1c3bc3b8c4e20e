#include "surface_lanes.h"

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

namespace {
// What every lane holds of its hit (surfaceAt's arithmetic, up to the normalization of the
// interpolated normal), whether it emits, and its base factor (baseFactorAt) as its albedo, which a
// texture may scale; the hit's material, its surface point's barycentrics, its base factor.
struct FetchedHit {
  const Material& m;
  SurfacePoint sp;
  Rgb factor;
};
FetchedHit fetchHit(const Scene& s, const Hit& hit, Vec3 direction, SurfaceLanes& l, uint32_t k) {
  const uint32_t* v = &s.indices[3 * size_t(hit.triangle)];
  storeLane(direction, l.dirX, l.dirY, l.dirZ, k);
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
  l.kdR[k] = factor.r, l.kdG[k] = factor.g, l.kdB[k] = factor.b;
  return {m, sp, factor};
}

// Texture t read at coordinates uv later (readLaneTextures), its texels requested now.
void requestTexture(const Scene& s, const Texture& t, Vec2 uv, uint32_t k, LaneTexture use, Rgb kd,
                    std::vector<TexturedLane>& textured) {
  const BilinearFootprint f = bilinearFootprint(t, s.texels.data(), uv);
  for (const uint32_t* texel : {f.row0 + f.x0, f.row0 + f.x1, f.row1 + f.x0, f.row1 + f.x1}) __builtin_prefetch(texel);
  textured.push_back({k, use, f, kd});
}
}  // namespace

void fetchLambertianSurface(const Scene& s, const Hit& hit, Vec3 direction, SurfaceLanes& l, uint32_t k,
                            std::vector<TexturedLane>& textured) {
  const FetchedHit h = fetchHit(s, hit, direction, l, k);
  if (h.m.kdTexture < 0) return;
  const Texture& t = s.textures[size_t(h.m.kdTexture)];
  requestTexture(s, t, textureUv(s, t, h.sp), k, LaneTexture::Albedo, h.factor, textured);
}

bool gltfShadedInLanes(const Material& m) {
  return m.type == MaterialType::Gltf && m.sheenColour.isBlack() && !(m.clearcoat > 0) && !(m.transmission > 0) &&
         m.boundsVolume == 0 && m.specularTexture < 0 && m.specularColorTexture < 0;
}

void fetchGltfSurface(const Scene& s, const Hit& hit, Vec3 direction, SurfaceLanes& l, uint32_t k,
                      std::vector<TexturedLane>& textured) {
  const FetchedHit h = fetchHit(s, hit, direction, l, k);
  const Material& m = h.m;
  l.metallic[k] = m.metallic, l.roughness[k] = m.roughness;
  const Rgb f0 = dielectricF0(m.ni, m.ks, m.specular);
  l.f0R[k] = f0.r, l.f0G[k] = f0.g, l.f0B[k] = f0.b;
  l.specular[k] = m.specular;
  l.heightCorrelated[k] = m.masking == GgxMasking::HeightCorrelated;
  l.normalMapped[k] = m.normalTexture >= 0;
  l.bendsNormalMap[k] = m.bendsNormalMap != 0;
  if (m.kdTexture < 0 && m.metallicRoughnessTexture < 0 && m.normalTexture < 0) return;
  const HitUv uv = hitUv(s, h.sp);
  auto request = [&](int32_t index, LaneTexture use, Rgb kd) {
    const Texture& t = s.textures[size_t(index)];
    requestTexture(s, t, textureUv(t, uv), k, use, kd, textured);
  };
  if (m.kdTexture >= 0) request(m.kdTexture, LaneTexture::Albedo, h.factor);
  if (m.metallicRoughnessTexture >= 0) request(m.metallicRoughnessTexture, LaneTexture::MetallicRoughness, {});
  if (m.normalTexture < 0) return;
  const uint32_t* v = &s.indices[3 * size_t(hit.triangle)];
  const Tangent& a = s.tangents[v[0]];
  storeLane(barycentric(a.direction, s.tangents[v[1]].direction, s.tangents[v[2]].direction, hit.b1, hit.b2), l.tangentX,
            l.tangentY, l.tangentZ, k);
  l.tangentSign[k] = a.sign;
  l.normalScale[k] = m.normalScale;
  request(m.normalTexture, LaneTexture::Normal, {});
}

void readLaneTextures(SurfaceLanes& l, std::span<const TexturedLane> textured) {
  for (const TexturedLane& t : textured) {
    const uint32_t k = t.lane;
    switch (t.use) {
      case LaneTexture::Albedo: {
        const Rgb kd = t.kd * bilinear(t.footprint);
        l.kdR[k] = kd.r, l.kdG[k] = kd.g, l.kdB[k] = kd.b;
        break;
      }
      case LaneTexture::MetallicRoughness: {
        // bsdfAt's: B scales the metallic factor, G the roughness.
        const Rgb c = bilinear(t.footprint, kUnorm8ToFloat);
        l.metallic[k] *= c.b;
        l.roughness[k] *= c.g;
        break;
      }
      case LaneTexture::Normal: {
        const Rgb c = bilinear(t.footprint, kUnorm8ToFloat);
        l.texelR[k] = c.r, l.texelG[k] = c.g, l.texelB[k] = c.b;
        break;
      }
    }
  }
}

LaneLight laneLight(const Scene& scene, uint32_t light) {
  const Light& l = scene.lights[light];
  if (l.type != LightType::Triangle) return {};
  const Material& m = scene.materials[scene.materialIds[l.triangle]];
  const EmittingTriangle e = emittingTriangle(scene, l.triangle);
  return {e, m.ke, !e.twoSided && m.emissiveTexture < 0 && !(m.clearcoat > 0)};
}

void fetchLaneLight(const LaneLight& light, SurfaceLanes& l, uint32_t k) {
  const EmittingTriangle& e = light.triangle;
  storeLane(e.q0, l.q0x, l.q0y, l.q0z, k);
  storeLane(e.q1, l.q1x, l.q1y, l.q1z, k);
  storeLane(e.q2, l.q2x, l.q2y, l.q2z, k);
  storeLane(e.normal, l.lightNx, l.lightNy, l.lightNz, k);
  l.lightArea[k] = e.area;
  l.leR[k] = light.le.r, l.leG[k] = light.le.g, l.leB[k] = light.le.b;
}

namespace {
// A lane's light sample: a point on its LaneLight's triangle (sampleChosenLight's triangle case), or
// the sample fetched (sampleOtherLights).
struct LaneLightSample {
  Vec3 wi, point;
  float distance, pdf;
  bool delta;
  Rgb le;
};
[[gnu::always_inline]] inline LaneLightSample laneLightSample(const SurfaceLanes& l, uint32_t k, Vec3 position) {
  const TrianglePointSample q = sampleTrianglePoint(
      {l.q0x[k], l.q0y[k], l.q0z[k]}, {l.q1x[k], l.q1y[k], l.q1z[k]}, {l.q2x[k], l.q2y[k], l.q2z[k]},
      {l.lightNx[k], l.lightNy[k], l.lightNz[k]}, l.lightArea[k], l.lightPmf[k], position, {l.uLightX[k], l.uLightY[k]});
  const bool onTriangle = l.lightIsTriangle[k] != 0;
  return {select(onTriangle, q.wi, {l.wiX[k], l.wiY[k], l.wiZ[k]}),
          select(onTriangle, q.point, {l.pointX[k], l.pointY[k], l.pointZ[k]}),
          onTriangle ? q.distance : l.lightDistance[k],
          onTriangle ? q.pdf : l.lightPdf[k],
          l.lightDelta[k] != 0,
          {l.leR[k], l.leG[k], l.leB[k]}};
}

// The light sample's shadow ray and what it brings.
[[gnu::always_inline]] inline void storeNextEvent(SurfaceLanes& l, uint32_t k, NextEventSample direct, Ray shadow) {
  l.shadowQueued[k] = direct.queued;
  storeLane(shadow.origin, l.shadowOx, l.shadowOy, l.shadowOz, k);
  storeLane(shadow.direction, l.shadowDx, l.shadowDy, l.shadowDz, k);
  l.shadowTMax[k] = shadow.tMax;
  l.directR[k] = direct.contribution.r, l.directG[k] = direct.contribution.g, l.directB[k] = direct.contribution.b;
}

// The next ray, leaving `position` along wiWorld, and the sample's weight and density; `scattered`:
// a valid sample that does not leak through the surface.
[[gnu::always_inline]] inline void storeNextRay(SurfaceLanes& l, uint32_t k, bool scattered, Rgb weight, float pdf,
                                                Vec3 position, Vec3 ng, Vec3 wiWorld) {
  l.scattered[k] = scattered;
  l.weightR[k] = weight.r, l.weightG[k] = weight.g, l.weightB[k] = weight.b;
  l.scatterPdf[k] = pdf;
  storeLane(offsetOrigin(position, ng, wiWorld), l.nextOx, l.nextOy, l.nextOz, k);
  storeLane(wiWorld, l.nextDx, l.nextDy, l.nextDz, k);
}
}  // namespace

// What PathTracer::shade does at a hit, for a Lambertian surface: the shading normal (surfaceAt's)
// and frame, next-event estimation (sampleDirect, with sampleChosenLight's triangle case where the
// light is a LaneLight), and the next direction (sampleBsdf).
LUCENT_LANE_LOOP(void, shadeDiffuseLanes, (SurfaceLanes& l, uint32_t first, uint32_t last)) {
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

    const LaneLightSample light = laneLightSample(l, k, position);
    const Vec3 wiLocal = frame.toLocal(light.wi);
    const NextEventSample direct = weighLightSample(strategy, light.pdf, light.delta, light.le, light.wi, wiLocal,
                                                    frame.n, ng, lambertianValue(kd, wo.z, wiLocal.z));
    storeNextEvent(l, k, direct, shadowRay(position, ng, light.wi, light.point, light.distance));

    const BsdfSample next = sampleLambertian(kd, wo.z, {l.uBsdfX[k], l.uBsdfY[k]});
    const Vec3 wiWorld = frame.toWorld(next.wi);
    storeNextRay(l, k, next.valid ? !leaksThroughSurface(woWorld, wiWorld, ng, false) : false, next.weight, next.pdf,
                 position, ng, wiWorld);
  }
}
LUCENT_LANE_VERSIONS(void, shadeDiffuseLanes, (SurfaceLanes& l, uint32_t first, uint32_t last), (l, first, last))

// surfaceAt's shading normal at a glTF hit (the normal texture's about the unit interpolated normal,
// or that normal) and hitFrameNormal's frame seen from the ray's origin, unbent; `bent` where
// bentForReflection has to bend it.
LUCENT_LANE_LOOP(void, gltfShadingFrames, (SurfaceLanes& l, uint32_t first, uint32_t last)) {
  for (uint32_t k = first; k < last; ++k) {
    const Vec3 ng{l.ngx[k], l.ngy[k], l.ngz[k]};
    const Vec3 interpolated{l.normalX[k], l.normalY[k], l.normalZ[k]};
    const bool hasNormals = l.hasNormals[k] != 0;
    const float len = length(interpolated);
    const Vec3 unit = select(hasNormals, select(len > 0, interpolated / len, ng), ng);
    const Vec3 mapped = tangentSpaceNormal(unit, {l.tangentX[k], l.tangentY[k], l.tangentZ[k]}, l.tangentSign[k],
                                           {l.texelR[k], l.texelG[k], l.texelB[k]}, l.normalScale[k]);
    const Vec3 sn = select(l.normalMapped[k] != 0, orientedShadingNormal(mapped, ng),
                           select(hasNormals, orientedShadingNormal(interpolated, ng), ng));
    const Vec3 wo = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]};
    const Vec3 n = shadingFrameNormal(wo, sn, ng, true);
    storeLane(sn, l.snX, l.snY, l.snZ, k);
    storeLane(n, l.frameX, l.frameY, l.frameZ, k);
    const Vec3 g = select(dot(wo, ng) > 0, ng, -ng);
    const int bends = l.bendsNormalMap[k] == 0 ? 0 : dot(wo, n) > 0 ? 1 : 0;
    l.bent[k] = bends == 0 ? 0 : reflectsTooLow(wo, n, g) ? 1 : 0;
  }
}
LUCENT_LANE_VERSIONS(void, gltfShadingFrames, (SurfaceLanes& l, uint32_t first, uint32_t last), (l, first, last))

// The rest of what PathTracer::shade does at such a hit, in the frame: next-event estimation with
// the lobe's value, and the next direction from the GGX visible normals or the cosine lobe, chosen
// by their weights at n.wo (GltfMetalRoughLobe::sample).
LUCENT_LANE_LOOP(void, shadeGltfInFrames, (SurfaceLanes& l, uint32_t first, uint32_t last)) {
  const PathStrategy strategy = l.strategy;
  for (uint32_t k = first; k < last; ++k) {
    const Vec3 ng{l.ngx[k], l.ngy[k], l.ngz[k]};
    const Vec3 woWorld = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]};
    const Frame frame({l.frameX[k], l.frameY[k], l.frameZ[k]});
    const Vec3 position{l.posX[k], l.posY[k], l.posZ[k]};
    const Vec3 wo = frame.toLocal(woWorld);
    const GltfMetalRoughLobe lobe = gltfLaneLobe(l, k);
    const GltfMetalRoughLobe::BaseChoice choice = lobe.baseChoice(wo.z);

    const LaneLightSample light = laneLightSample(l, k, position);
    storeLane(light.wi, l.wiX, l.wiY, l.wiZ, k);
    const Vec3 wiLocal = frame.toLocal(light.wi);
    const NextEventSample direct = weighLightSample(strategy, light.pdf, light.delta, light.le, light.wi, wiLocal,
                                                    frame.n, ng, lobe.reflection(wo, wiLocal, choice));
    storeNextEvent(l, k, direct, shadowRay(position, ng, light.wi, light.point, light.distance));

    const Vec2 u{l.uBsdfX[k], l.uBsdfY[k]};
    const Vec3 glossy = reflect(wo, sampleGgxVisibleNormal(lobe.alpha, wo, u));
    const Vec3 wi = select(l.uLobe[k] < choice.specular, glossy, sampleCosineHemisphere(u));
    const BsdfValue value = lobe.reflection(wo, wi, choice);
    const Vec3 wiWorld = frame.toWorld(wi);
    storeNextRay(l, k, value.pdf > 0 ? !leaksThroughSurface(woWorld, wiWorld, ng, false) : false,
                 value.f * (std::abs(wi.z) / value.pdf), value.pdf, position, ng, wiWorld);
  }
}
LUCENT_LANE_VERSIONS(void, shadeGltfInFrames, (SurfaceLanes& l, uint32_t first, uint32_t last), (l, first, last))

void shadeGltfLanes(SurfaceLanes& l, uint32_t first, uint32_t last) {
  gltfShadingFrames(l, first, last);
  for (uint32_t k = first; k < last; ++k) {
    if (!l.bent[k]) continue;
    const Vec3 wo = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]}, ng{l.ngx[k], l.ngy[k], l.ngz[k]};
    storeLane(bentForReflection(wo, {l.frameX[k], l.frameY[k], l.frameZ[k]}, dot(wo, ng) > 0 ? ng : -ng), l.frameX,
              l.frameY, l.frameZ, k);
  }
  shadeGltfInFrames(l, first, last);
}

}  // namespace lucent
