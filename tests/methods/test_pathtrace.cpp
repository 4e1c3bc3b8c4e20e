// The reference path tracer against analytic answers (furnaces) and for determinism.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "lucent/core/parallel.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/surface.h"
#include "methods/pathtrace/surface_lanes.h"
#include "methods/pathtrace/shading_steps.h"
#include "test_bsdfs.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

TEST_CASE("Closed diffuse furnace: radiance converges to Le / (1 - rho)", "[pathtrace][furnace]") {
  const Rgb rho(0.5f, 0.7f, 0.3f), le(1.0f, 2.0f, 0.5f);
  const Scene scene = test::furnaceBox(rho, le, test::testCamera({0.1f, 0.2f, 0.3f}, {0.5f, 0.1f, -1}, 32, 32, 90));
  const Visibility vis(scene);
  for (const SamplerKind sampler : {SamplerKind::Independent, SamplerKind::Sobol}) {
    PathTraceOptions opt;
    opt.common.spp = 64;
    opt.maxDepth = 100000;
    opt.common.seed = 7;
    opt.sampler = sampler;
    const RenderOutput out = renderPathTraced(scene, vis, opt);
    INFO("sampler " << int(sampler));
    test::requireImageMean(out.image, Rgb(le.r / (1 - rho.r), le.g / (1 - rho.g), le.b / (1 - rho.b)));
  }
}

TEST_CASE("Closed diffuse furnace with max depth: geometric series truncated", "[pathtrace][furnace]") {
  // With emission seen directly plus `d` bounces of lighting, L = Le (1 + rho + ... + rho^d).
  const float rho = 0.6f;
  const Scene scene = test::furnaceBox(Rgb(rho), Rgb(1.0f), test::testCamera({0, 0, 0}, {0, 0, -1}, 32, 32, 90));
  const Visibility vis(scene);
  for (const SamplerKind sampler : {SamplerKind::Independent, SamplerKind::Sobol})
    for (int depth : {1, 2, 4}) {
      PathTraceOptions opt;
      opt.common.spp = 32;
      opt.maxDepth = depth;
      opt.common.seed = 3;
      opt.sampler = sampler;
      const RenderOutput out = renderPathTraced(scene, vis, opt);
      float expected = 0, term = 1;
      for (int d = 0; d <= depth; ++d, term *= rho) expected += term;
      INFO("sampler " << int(sampler) << ", max depth " << depth);
      test::requireImageMean(out.image, Rgb(expected));
    }
}

TEST_CASE("Renders are bit-identical whatever the thread count and tile size", "[pathtrace][determinism]") {
  // The primitives under sun and sky: contribution roulette's pilot learns the light choice there.
  for (const char* file : {"/scenes/cornell-box.json", "/scenes/primitives.json"}) {
    CAPTURE(file);
    const Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + file, {true});
    Scene small = scene;
    small.camera.width = 48;
    small.camera.height = 40;
    PathTraceOptions opt;
    opt.common.spp = 12;  // contribution roulette from the ninth sample on
    opt.common.layers = true;
    opt.paths = true;
    opt.common.seed = 5;
    for (const SamplerKind sampler : {SamplerKind::Independent, SamplerKind::Sobol}) {
      opt.sampler = sampler;
      std::vector<float> reference;
      for (const auto& [threads, tile] : {std::pair{1, 16}, std::pair{2, 16}, std::pair{2, 7}, std::pair{1, 5}}) {
        ParallelScope scope(threads);
        const Visibility vis(small);
        opt.tileSize = tile;
        const RenderOutput out = renderPathTraced(small, vis, opt);
        if (reference.empty()) {
          reference = out.image.pixels();
        } else {
          INFO("sampler " << int(sampler) << ", " << threads << " threads, tile size " << tile);
          REQUIRE(out.image.pixels() == reference);
        }
      }
    }
  }
}

namespace {

// Every kind of light and material: the Cornell box with mirror and glass spheres, some glossy
// (Phong) wall triangles and some of glTF's metallic-roughness material (with a normal texture,
// bent, and a metallic-roughness texture; and of factors alone, with the height-correlated Smith
// term), plus a point light, a directional light and a constant environment; walls with
// interpolated normals made up from their positions, a textured floor, vertices with texture
// coordinates and tangents.
Scene everyMaterialAndLight() {
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-spheres.json", {true});
  Material glossy;
  glossy.type = MaterialType::Phong;
  glossy.kd = Rgb(0.3f, 0.4f, 0.2f);
  glossy.ks = Rgb(0.4f);
  glossy.ns = 30;
  Material mapped;
  mapped.type = MaterialType::Gltf;
  mapped.kd = Rgb(0.7f, 0.6f, 0.5f);
  mapped.ks = Rgb(1.0f);
  mapped.metallic = 0.8f, mapped.roughness = 0.9f;
  mapped.normalTexture = 1, mapped.normalScale = 1.5f, mapped.bendsNormalMap = 1;
  mapped.metallicRoughnessTexture = 2;
  Material factors = mapped;
  factors.kd = Rgb(0.4f, 0.6f, 0.7f);
  factors.metallic = 0.3f, factors.roughness = 0.35f;
  factors.normalTexture = factors.metallicRoughnessTexture = -1;
  factors.masking = GgxMasking::HeightCorrelated;
  const uint32_t first = uint32_t(scene.materials.size());
  scene.materials.insert(scene.materials.end(), {glossy, mapped, factors});
  // Of the Lambertian triangles that do not emit, those with t % 3 == 2 stay Lambertian; the others
  // take, by (t % 3, t % 2): (0, 0) the Phong, (0, 1) and (1, 0) the mapped glTF, (1, 1) the factors'.
  for (uint32_t t = 0; t < scene.materialIds.size(); ++t) {
    const Material& m = scene.materials[scene.materialIds[t]];
    if (!(m.type == MaterialType::Diffuse && m.ke.isBlack()) || t % 3 == 2) continue;
    const uint32_t turned[2][2] = {{first, first + 1}, {first + 1, first + 2}};
    scene.materialIds[t] = turned[t % 3][t % 2];
  }
  scene.camera.width = 40;
  scene.camera.height = 32;
  scene.lights.push_back({LightType::Point, 0, {0.3f, 1.2f, 0.5f}, Rgb(0.8f, 0.7f, 0.6f)});
  scene.lights.push_back({LightType::Directional, 0, normalize(Vec3{0.3f, -1.0f, -0.4f}), Rgb(0.5f)});
  scene.environment.present = true;
  scene.environment.radiance = Rgb(0.1f, 0.15f, 0.2f);
  for (size_t v = 0; v < scene.positions.size(); ++v) {
    const Vec3 p = scene.positions[v];
    scene.texcoords[v] = {p.x * 3.1f, p.z * 2.7f};
    if (v % 3 == 0) scene.normals[v] = normalize(Vec3{0.2f * p.x, 1.0f, 0.3f * p.z});
  }
  scene.tangents.resize(scene.positions.size());
  for (size_t v = 0; v < scene.positions.size(); ++v)
    scene.tangents[v] = {normalize(Vec3{1.0f, 0.3f * scene.positions[v].y, -0.2f}), v % 2 ? 1.0f : -1.0f};
  // Texels: albedo (sRGB), tangent-space normals ((n + 1) / 2), metallic (B) and roughness (G).
  scene.textures.push_back({0, 2, 2});
  scene.textures.push_back({4, 2, 2});
  scene.textures.push_back({8, 2, 2});
  scene.texels = {0xff2040ffu, 0xff40ff20u, 0xffff4020u, 0xffc0c0c0u, 0xffff8080u, 0xffe070c0u,
                  0xffd0a050u, 0xfff09098u, 0xff40c000u, 0xffa06000u, 0xff10ff00u, 0xfff03000u};
  for (Material& m : scene.materials)
    if ((m.type == MaterialType::Diffuse && m.ke.isBlack()) || m.normalTexture >= 0) m.kdTexture = 0;
  finalizeScene(scene);
  return scene;
}

}  // namespace

TEST_CASE("Camera rays and Lambertian hits in lanes give the image of one path at a time, bit for bit, on every "
          "material",
          "[pathtrace][determinism]") {
  // Lambertian hits shaded all lanes at once on one side, one lane at a time on the other, where
  // each path also draws its own Sobol numbers.
  const Scene scene = everyMaterialAndLight();
  const Visibility vis(scene);
  for (const PathStrategy strategy : {PathStrategy::Mis, PathStrategy::LightSampling, PathStrategy::BsdfSampling})
    for (const int maxDepth : {1024, 2}) {
      PathTraceOptions opt;
      opt.common.spp = 10;  // contribution roulette from the ninth sample on
      opt.common.layers = true;
      opt.common.seed = 9;
      opt.maxDepth = maxDepth;
      opt.strategy = strategy;
      // The Sobol sampler's numbers are drawn in lanes on one side, one by one on the other; the
      // independent sampler's come from each path's generator on both.
      if (strategy == PathStrategy::Mis && maxDepth == 2) opt.sampler = SamplerKind::Independent;
      const RenderOutput lanes = renderPathTraced(scene, vis, opt);
      opt.laneShading = false;
      const RenderOutput scalar = renderPathTraced(scene, vis, opt);
      INFO("strategy " << int(strategy) << ", max depth " << maxDepth << ", sampler " << int(opt.sampler));
      REQUIRE(lanes.image.pixels() == scalar.image.pixels());
      // Not a vacuous comparison: light arrives, and many hits were Lambertian.
      REQUIRE(test::channelMean(lanes.image, 0).mean > 0.01);
      CHECK(lanes.stats.counter("lane_shaded_hits") > lanes.stats.counter("rays") / 4);
      CHECK(scalar.stats.counter("lane_shaded_hits") == lanes.stats.counter("lane_shaded_hits"));
    }
}

TEST_CASE("A Lambertian lane holds surfaceAt's, bsdfAt's and sampleChosenLight's values", "[pathtrace]") {
  // The lanes read a hit's surface and an emitting triangle themselves (fetchLambertianSurface,
  // fetchLaneLight), where every other hit goes through surfaceAt, bsdfAt and sampleChosenLight.
  // Hits at scattered barycentrics on the Lambertian triangles of a scene with vertex normals at
  // some vertices and a textured albedo, each lit by one of its emitting triangles.
  const Scene scene = everyMaterialAndLight();
  std::vector<uint32_t> laneLights;
  for (uint32_t li = 0; li < scene.lights.size(); ++li)
    if (laneLight(scene, li).isTriangle) laneLights.push_back(li);
  // The Cornell box's light's triangles; the point, directional and environment lights are not.
  REQUIRE(!laneLights.empty());
  REQUIRE(laneLights.size() + 3 == scene.lights.size());
  const auto lanes = std::make_unique<SurfaceLanes>();
  std::vector<TexturedLane> textured;
  std::vector<Hit> hits;
  Rng rng(5);
  for (uint32_t n = 0; n < 100 * scene.materialIds.size() && hits.size() < uint32_t(kMaxLanes); ++n) {
    const uint32_t t = n % uint32_t(scene.materialIds.size());
    const Material& m = scene.materials[scene.materialIds[t]];
    if (m.type != MaterialType::Diffuse || !m.ke.isBlack()) continue;
    const uint32_t k = lanes->count++;
    Hit& hit = hits.emplace_back();
    hit.triangle = t, hit.b1 = 0.5f * rng.uniform(), hit.b2 = 0.5f * rng.uniform(), hit.t = 1;
    fetchLambertianSurface(scene, hit, sampleUniformSphere(rng.uniform2()), *lanes, k, textured);
    lanes->light[k] = laneLights[k % laneLights.size()];
    fetchLaneLight(laneLight(scene, lanes->light[k]), *lanes, k);
    lanes->lightIsTriangle[k] = 1;
    lanes->lightPmf[k] = 0.5f;
    lanes->uLightX[k] = rng.uniform(), lanes->uLightY[k] = rng.uniform();
    lanes->uBsdfX[k] = rng.uniform(), lanes->uBsdfY[k] = rng.uniform();
  }
  REQUIRE(hits.size() == uint32_t(kMaxLanes));
  readLaneTextures(*lanes, textured);
  shadeDiffuseLanes(*lanes, 0, lanes->count);
  const SurfaceLanes& l = *lanes;
  int interpolated = 0, queued = 0;
  for (uint32_t k = 0; k < l.count; ++k) {
    INFO("lane " << k << ", triangle " << hits[k].triangle);
    const SurfacePoint sp = surfaceAt(scene, hits[k].triangle, hits[k].b1, hits[k].b2);
    const SurfaceBsdf bsdf = bsdfAt(scene, sp);
    REQUIRE(Vec3{l.posX[k], l.posY[k], l.posZ[k]} == sp.position);
    REQUIRE(Vec3{l.ngx[k], l.ngy[k], l.ngz[k]} == sp.geometricNormal);
    REQUIRE(Vec3{l.snX[k], l.snY[k], l.snZ[k]} == sp.shadingNormal);
    REQUIRE(bsdf.type == MaterialType::Diffuse);
    REQUIRE(Rgb{l.kdR[k], l.kdG[k], l.kdB[k]} == bsdf.lambertian.kd);
    interpolated += !(sp.shadingNormal == sp.geometricNormal);
    // The lane's light sample is sampleChosenLight's: its shadow ray and radiance.
    const LightSample ls = sampleChosenLight(scene, l.light[k], l.lightPmf[k], sp.position, {l.uLightX[k], l.uLightY[k]});
    if (!l.shadowQueued[k]) continue;
    ++queued;
    REQUIRE(ls.pdf > 0);
    const Ray shadow = shadowRay(sp.position, sp.geometricNormal, ls);
    REQUIRE(Vec3{l.shadowOx[k], l.shadowOy[k], l.shadowOz[k]} == shadow.origin);
    REQUIRE(Vec3{l.shadowDx[k], l.shadowDy[k], l.shadowDz[k]} == shadow.direction);
    REQUIRE(l.shadowTMax[k] == shadow.tMax);
    REQUIRE(Rgb{l.leR[k], l.leG[k], l.leB[k]} == ls.radiance);
  }
  // Not vacuous: interpolated normals, textured albedos and light samples were compared.
  CHECK(interpolated > 5);
  CHECK(textured.size() > 5);
  CHECK(queued > 5);
  // Emitters the lanes leave to sampleChosenLight: two-sided or textured ones.
  Scene twoSided = scene;
  for (Material& m : twoSided.materials) m.emitsBackFace = m.ke.isBlack() ? 0 : 1;
  Scene texturedEmitter = scene;
  for (Material& m : texturedEmitter.materials) m.emissiveTexture = m.ke.isBlack() ? -1 : 0;
  for (const uint32_t li : laneLights) {
    CHECK_FALSE(laneLight(twoSided, li).isTriangle);
    CHECK_FALSE(laneLight(texturedEmitter, li).isTriangle);
  }
}

TEST_CASE("A glTF lane holds surfaceAt's, bsdfAt's, hitFrameNormal's and the lobe's values", "[pathtrace][gltf]") {
  // The lanes read a glTF hit's surface, textures and tangents themselves (fetchGltfSurface) and
  // shade it in lane loops (shadeGltfLanes), where shade() goes through surfaceAt, bsdfAt,
  // hitFrameNormal, evalBsdfAndPdf and sampleBsdf: the same IEEE operations, so the same bits.
  // Hits at scattered barycentrics, seen from every direction, on the glTF triangles of the scene
  // with every material, lit by its lights in turn.
  const Scene scene = everyMaterialAndLight();
  const auto lanes = std::make_unique<SurfaceLanes>();
  lanes->strategy = PathStrategy::Mis;
  std::vector<TexturedLane> textured;
  std::vector<Hit> hits;
  Rng rng(7);
  for (uint32_t n = 0; n < 100 * scene.materialIds.size() && hits.size() < uint32_t(kMaxLanes); ++n) {
    const uint32_t t = n % uint32_t(scene.materialIds.size());
    if (!gltfShadedInLanes(scene.materials[scene.materialIds[t]])) continue;
    const uint32_t k = --lanes->gltfFirst;
    Hit& hit = hits.emplace_back();
    hit.triangle = t, hit.b1 = 0.5f * rng.uniform(), hit.b2 = 0.5f * rng.uniform(), hit.t = 1;
    fetchGltfSurface(scene, hit, sampleUniformSphere(rng.uniform2()), *lanes, k, textured);
    // Every light, sampled as sampleOtherLights samples the lights that are not LaneLights.
    const uint32_t light = n % uint32_t(scene.lights.size());
    const Vec2 u = rng.uniform2();
    const LightSample ls = sampleChosenLight(scene, light, 0.5f, {lanes->posX[k], lanes->posY[k], lanes->posZ[k]}, u);
    lanes->light[k] = light, lanes->lightPmf[k] = 0.5f, lanes->uLightX[k] = u.x, lanes->uLightY[k] = u.y;
    lanes->lightIsTriangle[k] = 0;
    lanes->wiX[k] = ls.wi.x, lanes->wiY[k] = ls.wi.y, lanes->wiZ[k] = ls.wi.z, lanes->lightDistance[k] = ls.distance;
    lanes->pointX[k] = ls.point.x, lanes->pointY[k] = ls.point.y, lanes->pointZ[k] = ls.point.z;
    lanes->leR[k] = ls.radiance.r, lanes->leG[k] = ls.radiance.g, lanes->leB[k] = ls.radiance.b;
    lanes->lightPdf[k] = ls.pdf, lanes->lightDelta[k] = ls.delta;
    lanes->uBsdfX[k] = rng.uniform(), lanes->uBsdfY[k] = rng.uniform(), lanes->uLobe[k] = rng.uniform();
  }
  REQUIRE(hits.size() == uint32_t(kMaxLanes));
  readLaneTextures(*lanes, textured);
  shadeGltfLanes(*lanes, lanes->gltfFirst, kMaxLanes);
  const SurfaceLanes& l = *lanes;
  int mapped = 0, bent = 0, queued = 0, glossy = 0, scattered = 0;
  for (uint32_t k = l.gltfFirst; k < uint32_t(kMaxLanes); ++k) {
    const Hit& hit = hits[kMaxLanes - 1 - k];
    INFO("lane " << k << ", triangle " << hit.triangle);
    const SurfacePoint sp = surfaceAt(scene, hit.triangle, hit.b1, hit.b2);
    const SurfaceBsdf bsdf = bsdfAt(scene, sp);
    REQUIRE(bsdf.type == MaterialType::Gltf);
    REQUIRE(Vec3{l.posX[k], l.posY[k], l.posZ[k]} == sp.position);
    REQUIRE(Vec3{l.snX[k], l.snY[k], l.snZ[k]} == sp.shadingNormal);
    const GltfMetalRoughLobe lobe = gltfLaneLobe(l, k);
    REQUIRE(std::memcmp(&lobe, &bsdf.gltf, sizeof(lobe)) == 0);
    const Vec3 wo = -Vec3{l.dirX[k], l.dirY[k], l.dirZ[k]};
    const Frame frame(hitFrameNormal(scene, sp, wo, twoSidedShading(bsdf)));
    REQUIRE(Vec3{l.frameX[k], l.frameY[k], l.frameZ[k]} == frame.n);
    mapped += scene.materials[sp.materialId].normalTexture >= 0;
    bent += l.bent[k];
    // Next-event estimation as shade() weighs it.
    const Vec3 woLocal = frame.toLocal(wo);
    const Vec3 wi{l.wiX[k], l.wiY[k], l.wiZ[k]};
    const Vec3 wiLocal = frame.toLocal(wi);
    const NextEventSample direct =
        weighLightSample(PathStrategy::Mis, l.lightPdf[k], l.lightDelta[k] != 0, {l.leR[k], l.leG[k], l.leB[k]}, wi,
                         wiLocal, frame.n, sp.geometricNormal, evalBsdfAndPdf(bsdf, woLocal, wiLocal));
    REQUIRE(l.shadowQueued[k] == int32_t(direct.queued));
    if (direct.queued) {
      ++queued;
      REQUIRE(Rgb{l.directR[k], l.directG[k], l.directB[k]} == direct.contribution);
    }
    // The next direction as sampleBsdf draws it.
    const BsdfSample next = sampleBsdf(bsdf, woLocal, l.uLobe[k], {l.uBsdfX[k], l.uBsdfY[k]});
    const bool leaks = next.valid && leaksThroughSurface(wo, frame.toWorld(next.wi), sp.geometricNormal, false);
    REQUIRE(l.scattered[k] == int32_t(next.valid && !leaks));
    if (!l.scattered[k]) continue;
    ++scattered;
    glossy += l.uLobe[k] < bsdf.gltf.specularChoice(woLocal.z);
    REQUIRE(Vec3{l.nextDx[k], l.nextDy[k], l.nextDz[k]} == frame.toWorld(next.wi));
    REQUIRE(Rgb{l.weightR[k], l.weightG[k], l.weightB[k]} == next.weight);
    REQUIRE(l.scatterPdf[k] == next.pdf);
  }
  // Not vacuous: normal textures (some bent), light samples, both lobes' directions.
  CHECK(mapped > 20);
  CHECK(bent > 0);
  CHECK(queued > 20);
  CHECK(glossy > 20);
  CHECK(scattered - glossy > 20);
}

TEST_CASE("Lambertian and glTF surfaces shaded in lanes agree with the same BRDFs shaded by shade()", "[pathtrace][gltf]") {
  // Independent renders of the scene with every material and kind of light, its Lambertian
  // materials turned into glTF ones: a dielectric of specular 0 reflects as Lambertian (Appendix B:
  // no Fresnel term at all, the diffuse lobe whole), shaded in glTF lanes against Lambertian lanes;
  // and a glossy metallic-roughness material shaded in lanes against shade(), which takes it where
  // a specular texture (white: the same BRDF) scales its factor.
  const Scene lambertian = everyMaterialAndLight();
  auto turned = [&](float specular, float metallic, float roughness, bool specularTexture) {
    Scene gltf = lambertian;
    gltf.textures.push_back({uint32_t(gltf.texels.size()), 1, 1});
    gltf.texels.push_back(0xffffffffu);
    for (Material& m : gltf.materials)
      if (m.type == MaterialType::Diffuse) {
        m.type = MaterialType::Gltf, m.metallic = metallic, m.roughness = roughness, m.specular = specular;
        m.ks = Rgb(1.0f);
        if (specularTexture) m.specularTexture = int32_t(gltf.textures.size() - 1);
      }
    return gltf;
  };
  PathTraceOptions opt;
  opt.common.spp = 64;
  opt.sampler = SamplerKind::Independent;
  auto render = [&](const Scene& scene, uint64_t seed) {
    opt.common.seed = seed;
    return renderPathTraced(scene, Visibility(scene), opt);
  };
  auto agree = [](const RenderOutput& a, const RenderOutput& b) {
    for (int c = 0; c < 3; ++c) {
      const double z = test::agreementZ(a.image, b.image, c);
      INFO("channel " << c << ": z = " << z);
      CHECK(std::abs(z) < 4.5);
    }
  };
  const RenderOutput lambertianLanes = render(lambertian, 3), diffuseGltfLanes = render(turned(0, 0, 0.6f, false), 4);
  agree(lambertianLanes, diffuseGltfLanes);
  const RenderOutput glossyLanes = render(turned(1, 0.3f, 0.45f, false), 5);
  const RenderOutput glossyShaded = render(turned(1, 0.3f, 0.45f, true), 6);
  agree(glossyLanes, glossyShaded);
  // Every hit but the mirror's, the glass's and the Phong triangles' in lanes; the turned triangles'
  // (some 40% of them) not in the last render.
  CHECK(glossyLanes.stats.counter("lane_shaded_hits") > glossyLanes.stats.counter("rays") / 4);
  CHECK(glossyShaded.stats.counter("lane_shaded_hits") < 0.8 * glossyLanes.stats.counter("lane_shaded_hits"));
}

TEST_CASE("Pixel centres: every sample of a pixel takes the centre's camera ray, in lanes and one by one",
          "[pathtrace]") {
  // With the path cut at the camera's hit (max depth 0: emission seen directly) a sample's value is
  // fixed by its camera ray alone. Through the pixel centres, 8 samples then give the image of 1;
  // spread over the pixels (the default) they differ from it where the light's edge crosses a pixel.
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  scene.camera.width = scene.camera.height = 24;
  const Visibility vis(scene);
  auto render = [&](int spp, bool centres, bool lanes) {
    PathTraceOptions opt;
    opt.common.spp = spp;
    opt.maxDepth = 0;
    opt.pixelCentres = centres;
    opt.laneShading = lanes;
    return renderPathTraced(scene, vis, opt).image;
  };
  for (const bool lanes : {true, false}) {
    INFO("lanes " << lanes);
    const Image one = render(1, true, lanes), eight = render(8, true, lanes), spread = render(8, false, lanes);
    int lit = 0, differing = 0;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x) {
        const float v = one.at(x, y, 0);
        lit += v > 0;
        REQUIRE(std::abs(eight.at(x, y, 0) - v) <= 1e-6f * v);
        differing += std::abs(spread.at(x, y, 0) - v) > 1e-3f * v + 1e-6f;
      }
    CHECK(lit > 0);
    CHECK(differing > 0);
  }
}

namespace {

// Renders a scene built in code at 2 spp with Lambertian hits shaded in lanes, then one by one,
// and hands each output to check.
template <class Check>
void renderInLanesAndOneByOne(const Scene& scene, Check&& check) {
  const Visibility vis(scene);
  for (const bool lanes : {true, false}) {
    PathTraceOptions opt;
    opt.common.spp = 2;
    opt.laneShading = lanes;
    INFO("lanes " << lanes);
    check(renderPathTraced(scene, vis, opt));
  }
}

}  // namespace

TEST_CASE("A scene without lights built in code renders black, in lanes and one by one", "[pathtrace]") {
  const Scene scene = test::furnaceBox(Rgb(0.5f), Rgb(0.0f), test::testCamera({0, 0, 0}, {0, 0, -1}, 8, 8));
  REQUIRE(scene.lights.empty());
  renderInLanesAndOneByOne(scene, [](const RenderOutput& out) {
    for (const float v : out.image.pixels()) REQUIRE(v == 0.0f);
  });
}

TEST_CASE("Samples whose ray is not finite are dropped and counted, in lanes and one by one", "[pathtrace]") {
  // The loader refuses such cameras; one built in code with a NaN eye makes every camera ray
  // untraceable. Embree is not asked (Visibility answers a miss), and the path tracer must not take
  // that miss for an escaped path: the samples are counted invalid and the pixels stay 0, although
  // the furnace's walls emit.
  Camera camera = test::testCamera({0, 0, 0}, {0, 0, -1}, 4, 3);
  camera.eye.x = std::numeric_limits<float>::quiet_NaN();
  const Scene scene = test::furnaceBox(Rgb(0.5f), Rgb(1.0f), camera);
  renderInLanesAndOneByOne(scene, [](const RenderOutput& out) {
    CHECK(out.stats.counter("invalid_samples") == 4 * 3 * 2);
    for (const float v : out.image.pixels()) REQUIRE(v == 0.0f);
  });
}


TEST_CASE("MIS, light sampling alone and BSDF sampling alone converge to the same image", "[pathtrace]") {
  // Light sampling alone finds what BSDF sampling misses and vice versa: any error in a pdf, a
  // MIS weight or a shadow ray (a light blocking its own samples) breaks the agreement.
  for (const char* file : {"/scenes/cornell-box.json", "/scenes/cornell-box-glossy.json"}) {
    Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + file, {true});
    scene.camera.width = 64;
    scene.camera.height = 64;
    const Visibility vis(scene);
    PathTraceOptions opt;
    opt.common.spp = 256;
    opt.maxDepth = 3;
    std::vector<Image> images;
    for (PathStrategy s : {PathStrategy::Mis, PathStrategy::LightSampling, PathStrategy::BsdfSampling}) {
      opt.strategy = s;
      opt.common.seed = images.size() + 1;  // independent images
      images.push_back(renderPathTraced(scene, vis, opt).image);
    }
    // And MIS by the Sobol sampler, whose pixels are independent of one another as well.
    opt.strategy = PathStrategy::Mis;
    opt.sampler = SamplerKind::Sobol;
    opt.common.seed = 4;
    images.push_back(renderPathTraced(scene, vis, opt).image);
    for (const auto& [a, b] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}, std::pair{0, 3}, std::pair{1, 3}})
      for (int c = 0; c < 3; ++c) {
        const double z = test::agreementZ(images[a], images[b], c);
        INFO(file << ": strategy " << a << " against " << b << ", channel " << c << ": z = " << std::to_string(z));
        CHECK(std::abs(z) < 4.5);
      }
  }
}

TEST_CASE("White furnace: convex white, mirror, glass and glTF volume objects under a constant environment vanish",
          "[pathtrace][furnace]") {
  // The glTF volumes' boundaries (KHR_materials_volume, refracting at 1.5 and index-matched) are
  // white: each microfacet reflects F and passes 1 - F from either side (the Schlick term read
  // outside), so whatever enters leaves; radiance is scaled by eta^2 going in and back by 1 / eta^2
  // going out. Masking at roughness 0.1 loses below 1e-4 per interaction.
  std::vector<Material> objects;
  for (MaterialType type : {MaterialType::Diffuse, MaterialType::Mirror, MaterialType::Glass}) {
    Material m;
    m.type = type;
    m.kd = Rgb(type == MaterialType::Diffuse ? 1.0f : 0.0f);
    m.ks = Rgb(type == MaterialType::Mirror ? 1.0f : 0.0f);
    m.ni = 1.5f;
    objects.push_back(m);
  }
  for (const float ior : {1.5f, 1.0f}) {
    Material m;
    m.type = MaterialType::Gltf;
    m.kd = Rgb(1.0f);
    m.ks = Rgb(1.0f);
    m.ni = ior;
    m.metallic = 0;
    m.roughness = 0.1f;
    m.transmission = 1;
    m.boundsVolume = 1;
    objects.push_back(m);
  }
  for (const Material& m : objects) {
    Scene scene;
    test::addBox(scene, {-1, -1, -1}, {1, 1, 1}, test::addMaterial(scene, m, "object"), false);
    scene.camera = test::testCamera({2.5f, 1.5f, 3.5f}, {0, 0, 0}, 32, 32, 50);
    scene.environment.present = true;
    scene.environment.radiance = Rgb(0.8f, 1.0f, 1.2f);
    finalizeScene(scene);
    const Visibility vis(scene);
    PathTraceOptions opt;
    opt.common.spp = 64;
    opt.common.seed = 2;
    INFO("material type " << int(m.type) << ", index " << m.ni);
    test::requireImageMean(renderPathTraced(scene, vis, opt).image, scene.environment.radiance);
  }
}

TEST_CASE("Beer-Lambert: a KHR_materials_volume medium keeps attenuationColour^(x / attenuationDistance) of the "
          "light crossing x of it, on camera and shadow rays",
          "[pathtrace][gltf]") {
  // An index-matched box [-1, 1]^3 (nothing bends; its boundary passes 1 - (1 - cos)^5 of the
  // light, within 1e-8 of all in this view) holds a diffuse plane at z = -0.5, lit by a point light
  // inside; the camera looks down -z through the face z = 1. Direct light only: each pixel's centre
  // sees rho I cos / (pi d^2) times the medium's transmittance over the camera ray's 1.5 / |dir.z|
  // inside and the light's d; within 5e-4, what float rounding and the rays' offsets off their ends
  // leave (measured below 1.5e-4; missing either segment's attenuation costs a factor 0.3 or less).
  Scene scene;
  Material medium;
  medium.type = MaterialType::Gltf;
  medium.kd = Rgb(1.0f);
  medium.ks = Rgb(1.0f);
  medium.ni = 1.0f;
  medium.metallic = 0;
  medium.roughness = 0.5f;
  medium.transmission = 1;
  medium.boundsVolume = 1;
  medium.attenuationColour = Rgb(0.5f, 0.25f, 0.8f);
  medium.attenuationDistance = 1.2f;
  test::addBox(scene, {-1, -1, -1}, {1, 1, 1}, test::addMaterial(scene, medium, "medium"), false);
  Material floor;
  floor.kd = Rgb(0.8f);
  test::addQuad(scene, {-0.9f, -0.9f, -0.5f}, {0.9f, -0.9f, -0.5f}, {0.9f, 0.9f, -0.5f}, {-0.9f, 0.9f, -0.5f},
                test::addMaterial(scene, floor, "floor"));
  Light point;
  point.type = LightType::Point;
  point.vector = {0.2f, -0.1f, 0.5f};
  point.value = Rgb(3.0f);
  scene.lights.push_back(point);
  scene.camera = test::testCamera({0, 0, 6}, {0, 0, 0}, 16, 16, 16);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 1;
  opt.maxDepth = 2;
  opt.pixelCentres = true;
  const Image image = renderPathTraced(scene, vis, opt).image;
  const PinholeCamera camera(scene.camera);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const Ray ray = camera.generate(x + 0.5f, y + 0.5f);
      const Vec3 p = ray.origin + ray.direction * ((-0.5f - ray.origin.z) / ray.direction.z);
      const double inside = 1.5 * length(ray.direction) / std::abs(ray.direction.z);
      const Vec3 toLight = point.vector - p;
      const double d = length(toLight);
      const double direct = 0.8 * kInvPi * 3.0 * (toLight.z / d) / (d * d);
      for (int c = 0; c < 3; ++c) {
        const double expected = direct * std::pow(double(medium.attenuationColour[c]), (inside + d) / 1.2);
        INFO("pixel " << x << ", " << y << ", channel " << c);
        REQUIRE(image.at(x, y, c) == Approx(expected).epsilon(5e-4));
      }
    }
}

TEST_CASE("A directional light on a diffuse plane gives rho E cos(theta) / pi", "[pathtrace]") {
  Scene scene;
  Material grey;
  grey.kd = Rgb(0.6f);
  test::addBox(scene, {-50, -1, -50}, {50, 0, 50}, test::addMaterial(scene, grey, "grey"), false);
  const Vec3 direction = normalize(Vec3{0.4f, -1.0f, 0.3f});
  scene.lights.push_back({LightType::Directional, 0, direction, Rgb(2.0f, 3.0f, 4.0f)});
  scene.camera = test::testCamera({0, 5, 0}, {0, 0, 0.001f}, 16, 16, 30);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 4;
  opt.maxDepth = 1;
  const Image image = renderPathTraced(scene, vis, opt).image;
  const float scale = 0.6f * std::abs(direction.y) * kInvPi;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) REQUIRE(image.at(x, y, c) == Approx(scale * (c + 2.0f)).epsilon(1e-4));
}

TEST_CASE("Layers: light seen through mirrors and glass is direct", "[pathtrace]") {
  // An emitting enclosure with a mirror box and a glass box inside: every path reaches the emitter
  // through specular bounces only, so all light is direct and the indirect layer is exactly zero.
  Scene scene;
  Material emitter, mirror, glass;
  emitter.kd = Rgb(0.0f);
  emitter.ke = Rgb(1.0f, 2.0f, 3.0f);
  mirror.type = MaterialType::Mirror;
  mirror.ks = Rgb(0.9f);
  glass.type = MaterialType::Glass;
  glass.ni = 1.5f;
  test::addBox(scene, {-5, -5, -5}, {5, 5, 5}, test::addMaterial(scene, emitter, "emitter"), true);
  test::addBox(scene, {-2, -1, -1}, {-0.2f, 1, 1}, test::addMaterial(scene, mirror, "mirror"), false);
  test::addBox(scene, {0.2f, -1, -1}, {2, 1, 1}, test::addMaterial(scene, glass, "glass"), false);
  scene.camera = test::testCamera({0, 0.5f, 4}, {0, 0, 0}, 24, 24, 60);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 8;
  opt.common.layers = true;
  const Image image = renderPathTraced(scene, vis, opt).image;
  const int beauty = image.channelIndex("G"), direct = image.channelIndex("direct.G"),
            indirect = image.channelIndex("indirect.G");
  double total = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) {
      REQUIRE(image.at(x, y, indirect) == 0.0f);
      REQUIRE(image.at(x, y, direct) == image.at(x, y, beauty));
      total += image.at(x, y, direct);
    }
  REQUIRE(total > 0);
}

TEST_CASE("glTF furnace: a plane of glTF material under a constant environment shows the radiance times its "
          "directional albedo",
          "[pathtrace][furnace][gltf]") {
  // One bounce to the environment, which is sampled as a light and found by BSDF samples: MIS and
  // each strategy alone give L a(wo), a(wo) integrated numerically (test_bsdfs.h). The camera sees
  // the plane within 1 degree of theta; the expectation spans a(wo) over that range. The last cases
  // have a KHR_materials_sheen layer, a KHR_materials_clearcoat coat (its normal the plane's, which
  // the render takes from world space into its shading frame), and a thin-walled
  // KHR_materials_transmission, through which the environment below is seen and lit from.
  struct Case {
    float metallic, roughness;
    Rgb base;
    GgxMasking masking;
    double theta;
    Rgb sheenColour{0.0f};
    float sheenRoughness = 0;
    float clearcoat = 0, clearcoatRoughness = 0;
    float transmission = 0;
  };
  for (const Case& k : {Case{1, 0.3f, Rgb(0.9f, 0.6f, 0.3f), GgxMasking::Separable, 1.0},
                        Case{0, 0.5f, Rgb(1.0f), GgxMasking::Separable, 1.4},
                        Case{0.5f, 0.7f, Rgb(0.2f, 0.5f, 0.8f), GgxMasking::HeightCorrelated, 0.5},
                        Case{0, 0.6f, Rgb(0.3f, 0.2f, 0.6f), GgxMasking::Separable, 1.2, Rgb(1.0f, 0.8f, 0.6f), 0.4f},
                        Case{0.3f, 0.5f, Rgb(0.8f, 0.3f, 0.2f), GgxMasking::HeightCorrelated, 1.3, Rgb(0.0f), 0, 0.9f, 0.2f},
                        Case{0, 0.3f, Rgb(0.9f, 0.7f, 0.4f), GgxMasking::Separable, 0.9, Rgb(0.0f), 0, 0.5f, 0.2f, 0.8f}})
    for (const PathStrategy strategy : {PathStrategy::Mis, PathStrategy::LightSampling, PathStrategy::BsdfSampling}) {
      Scene scene;
      Material m;
      m.type = MaterialType::Gltf;
      m.masking = k.masking;
      m.kd = k.base;
      m.ks = Rgb(1.0f);
      m.ni = 1.5f;
      m.metallic = k.metallic;
      m.roughness = k.roughness;
      m.sheenColour = k.sheenColour;
      m.sheenRoughness = k.sheenRoughness;
      m.clearcoat = k.clearcoat;
      m.clearcoatRoughness = k.clearcoatRoughness;
      m.transmission = k.transmission;
      test::addQuad(scene, {-100, 0, -100}, {-100, 0, 100}, {100, 0, 100}, {100, 0, -100},
                    test::addMaterial(scene, m, "plane"));
      const Vec3 eye{0, float(20 * std::cos(k.theta)), float(20 * std::sin(k.theta))};
      scene.camera = test::testCamera(eye, {0, 0, 0}, 16, 16, 2);
      scene.environment.present = true;
      scene.environment.radiance = Rgb(1.0f, 2.0f, 0.5f);
      finalizeScene(scene);
      const Visibility vis(scene);
      PathTraceOptions opt;
      opt.common.spp = 256;
      opt.common.seed = 9;
      opt.strategy = strategy;
      const Image image = renderPathTraced(scene, vis, opt).image;
      Material plane = scene.materials[0];
      const SurfaceBsdf b = materialBsdf(plane);
      Rgb low(1e9f), high(0.0f);
      for (const double theta : {k.theta - 0.0175, k.theta, k.theta + 0.0175}) {
        const Rgb a = test::directionalAlbedo(b, test::directionAt(theta, 0)) * scene.environment.radiance;
        for (int c = 0; c < 3; ++c) low[c] = std::min(low[c], a[c]), high[c] = std::max(high[c], a[c]);
      }
      for (int c = 0; c < 3; ++c) {
        const test::MeanAndError s = test::channelMean(image, c);
        INFO("metallic " << k.metallic << ", theta " << k.theta << ", strategy " << int(strategy) << ", channel " << c
                         << ": mean " << s.mean << " +- " << s.standardError << ", expected [" << low[c] << ", "
                         << high[c] << "]");
        CHECK(s.mean >= low[c] - 4.5 * s.standardError);
        CHECK(s.mean <= high[c] + 4.5 * s.standardError);
      }
    }
}

TEST_CASE("glTF metals and dielectrics: MIS, light sampling alone and BSDF sampling alone agree", "[pathtrace][gltf]") {
  // The exported Cornell box with its walls turned into rough metals and its blocks into a shiny
  // dielectric under a clear coat: every strategy's pdf and weight of the GGX lobes against the
  // others'.
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/gltf/cornell-box.glb", {true});
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    Material& m = scene.materials[i];
    if (scene.materialNames[i] == "white") m.roughness = 0.25f, m.ks = Rgb(1.0f), m.ni = 1.5f, m.clearcoat = 0.7f, m.clearcoatRoughness = 0.15f;
    if (scene.materialNames[i] == "red" || scene.materialNames[i] == "green") m.metallic = 1, m.roughness = 0.4f;
  }
  scene.camera.width = 48;
  scene.camera.height = 48;
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 256;
  opt.maxDepth = 3;
  opt.sampler = SamplerKind::Independent;
  std::vector<Image> images;
  for (PathStrategy s : {PathStrategy::Mis, PathStrategy::LightSampling, PathStrategy::BsdfSampling}) {
    opt.strategy = s;
    opt.common.seed = images.size() + 11;
    images.push_back(renderPathTraced(scene, vis, opt).image);
  }
  for (const auto& [a, b] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}})
    for (int c = 0; c < 3; ++c) {
      const double z = test::agreementZ(images[a], images[b], c);
      INFO("strategy " << a << " against " << b << ", channel " << c << ": z = " << std::to_string(z));
      CHECK(std::abs(z) < 4.5);
    }
}

TEST_CASE("A spot light on a diffuse plane gives rho I falloff cos(theta) / (pi d^2)", "[pathtrace]") {
  Scene scene;
  Material grey;
  grey.kd = Rgb(0.6f);
  test::addBox(scene, {-50, -1, -50}, {50, 0, 50}, test::addMaterial(scene, grey, "grey"), false);
  Light spot;
  spot.type = LightType::Spot;
  spot.vector = {0.3f, 2, -0.2f};
  spot.axis = normalize(Vec3{0.2f, -1, 0.1f});
  spot.value = Rgb(2.0f, 3.0f, 4.0f);
  spot.angleScale = float(1 / (std::cos(0.15) - std::cos(0.45)));
  spot.angleOffset = float(-std::cos(0.45) * spot.angleScale);
  scene.lights.push_back(spot);
  scene.camera = test::testCamera({0, 5, 0}, {0, 0, 0.001f}, 24, 24, 40);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 1;
  opt.maxDepth = 1;
  opt.pixelCentres = true;  // every pixel's value at its centre's hit, computed below
  const Image image = renderPathTraced(scene, vis, opt).image;
  const PinholeCamera camera(scene.camera);
  int lit = 0, dark = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) {
      const Ray ray = camera.generate(x + 0.5f, y + 0.5f);
      const Vec3 p = ray.origin + ray.direction * (-ray.origin.y / ray.direction.y);
      const Vec3 toLight = spot.vector - p;
      const float d2 = dot(toLight, toLight);
      const Vec3 wi = toLight / std::sqrt(d2);
      const float expected = 0.6f * kInvPi * spotFalloff(spot, -wi) * wi.y / d2;
      (expected > 0 ? lit : dark)++;
      for (int c = 0; c < 3; ++c) REQUIRE(image.at(x, y, c) == Approx(expected * (c + 2.0f)).epsilon(1e-3).margin(1e-7));
    }
  CHECK(lit > 50);
  CHECK(dark > 50);
}

TEST_CASE("Two point lights chosen by distance light a diffuse plane as rho sum I cos(theta) / (pi d^2), in lanes "
          "and one by one", "[pathtrace]") {
  // Each light sample picks one of the lights, the nearer more often (chooseLight): the pixel's
  // mean must still be both lights' light. Independent samples, each pixel's centre, against the
  // analytic value: all pixels together within 4 standard deviations. (A pixel alone is not
  // tested by its variance alone: near a light, where the other is picked for 3% of the samples,
  // all of a pixel's samples may pick the near one, and its variance is then zero; each pixel is
  // within 5 standard deviations or 5% of its value, the other light's share.)
  Scene scene;
  Material grey;
  grey.kd = Rgb(0.6f);
  test::addBox(scene, {-50, -1, -50}, {50, 0, 50}, test::addMaterial(scene, grey, "grey"), false);
  const Light a{LightType::Point, 0, {-1.5f, 0.5f, 0.3f}, Rgb(1.0f, 2.0f, 3.0f)};
  const Light b{LightType::Point, 0, {1.0f, 1.5f, -0.5f}, Rgb(3.0f, 2.0f, 1.0f)};
  scene.lights = {a, b};
  scene.camera = test::testCamera({0, 5, 0}, {0, 0, 0.001f}, 24, 24, 60);
  finalizeScene(scene);
  REQUIRE(scene.nearbyLights.size() == 2);
  const Visibility vis(scene);
  const PinholeCamera camera(scene.camera);
  for (const bool lanes : {true, false}) {
    PathTraceOptions opt;
    opt.common.spp = 256;
    opt.maxDepth = 1;
    opt.pixelCentres = true;
    opt.sampler = SamplerKind::Independent;
    opt.variance = true;
    opt.laneShading = lanes;
    const Image image = renderPathTraced(scene, vis, opt).image;
    double difference = 0, variance = 0;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x) {
        const Ray ray = camera.generate(x + 0.5f, y + 0.5f);
        const Vec3 p = ray.origin + ray.direction * (-ray.origin.y / ray.direction.y);
        Rgb expected(0.0f);
        for (const Light& light : {a, b}) {
          const Vec3 toLight = light.vector - p;
          const float d2 = dot(toLight, toLight);
          expected += light.value * (0.6f * kInvPi * (toLight.y / std::sqrt(d2)) / d2);
        }
        for (int c = 0; c < 3; ++c) {
          const double v = image.at(x, y, c), var = image.at(x, y, image.channelIndex(std::string("variance.") + "RGB"[c]));
          INFO("pixel " << x << "," << y << " channel " << c << " lanes " << lanes);
          CHECK(std::abs(v - expected[c]) <= std::max(5 * std::sqrt(var), 0.05 * double(expected[c])));
          difference += v - expected[c], variance += var;
        }
      }
    CHECK(std::abs(difference) <= 4 * std::sqrt(variance));
  }
}

namespace {

// The form factor from a point to a rectangle parallel to its surface, one of whose corners lies
// straight above the point: sides a and b in units of the height (the unit-sphere method).
double cornerFormFactor(double a, double b) {
  const double ra = std::sqrt(1 + a * a), rb = std::sqrt(1 + b * b);
  return (a / ra * std::atan(b / ra) + b / rb * std::atan(a / rb)) / (2 * kPi);
}

}  // namespace

TEST_CASE("A two-sided emitter lights what lies behind it, times its emissive texture, with every strategy",
          "[pathtrace]") {
  // A floor of albedo 0.5 under a 4 x 4 emitter 1 above it whose front faces up: only its back face
  // can light the floor, whose radiance at the centre is rho Le F (F the form factor of the square,
  // 0.8310) for a two-sided emitter, and nothing for a one-sided one. An emissive texture of
  // two texels, white and black along u, halves it: read bilinearly and repeating, its value is a
  // triangle wave about 1/2 whose two halves about the centre sum to 1. The camera between the two
  // sees the floor within 0.022 of the centre, where the form factor differs from the centre's by
  // less than 3e-5 and the texture's slope cancels between the image's halves. Each strategy's image
  // mean within 4 standard errors (the pixels' spread) of the answer; its emission seen from below
  // too (a camera looking up at the back face: Le times the texture at the centre, 1/2).
  const float le = 2.0f, rho = 0.5f;
  const double f = 4 * cornerFormFactor(2, 2);
  for (const bool twoSided : {true, false})
    for (const bool textured : {false, true}) {
      Scene scene;
      Material floor;
      floor.kd = Rgb(rho);
      test::addQuad(scene, {-100, 0, -100}, {-100, 0, 100}, {100, 0, 100}, {100, 0, -100}, test::addMaterial(scene, floor, "floor"));
      const int32_t texture = textured ? test::addTexture(scene, 2, 1, {{255, 255, 255}, {0, 0, 0}}) : -1;
      test::addCeilingEmitter(scene, 2, 1, Rgb(le), twoSided, texture);
      scene.camera = test::testCamera({0, 0.5f, 0}, {0, 0, 0.001f}, 8, 8, 5);
      finalizeScene(scene);
      const Visibility vis(scene);
      const double expected = twoSided ? rho * le * f * (textured ? 0.5 : 1.0) : 0.0;
      for (const PathStrategy strategy : {PathStrategy::Mis, PathStrategy::LightSampling, PathStrategy::BsdfSampling}) {
        PathTraceOptions opt;
        opt.common.spp = 64;
        opt.maxDepth = 2;
        opt.strategy = strategy;
        const Image image = renderPathTraced(scene, vis, opt).image;
        double sum = 0, sum2 = 0;
        for (int y = 0; y < 8; ++y)
          for (int x = 0; x < 8; ++x) sum += image.at(x, y, 0), sum2 += double(image.at(x, y, 0)) * image.at(x, y, 0);
        const double mean = sum / 64, se = std::sqrt(std::max(0.0, sum2 / 64 - mean * mean) / 64);
        INFO("two-sided " << twoSided << ", textured " << textured << ", strategy " << int(strategy) << ": " << mean
                          << " +- " << se << ", expected " << expected);
        // BSDF sampling alone meets the emitter with probability F: its pixels may all agree
        // (se 0) though a sample misses with probability 1 - F, whose spread over the 4,096
        // samples bounds the standard error from below.
        const double missSpread = expected * std::sqrt(f * (1 - f) / 4096);
        if (twoSided)
          CHECK(std::abs(mean - expected) <= 4 * std::max(se, missSpread));
        else
          CHECK(mean == 0.0);
      }
      Scene below = scene;
      below.camera = test::testCamera({0, 0.5f, 0}, {0, 1, 0.001f}, 1, 1, 0.01f);
      PathTraceOptions opt;
      opt.common.spp = 4;
      opt.maxDepth = 1;
      const double seen = renderPathTraced(below, Visibility(below), opt).image.at(0, 0, 0);
      INFO("two-sided " << twoSided << ", textured " << textured << ": the back face seen as " << seen);
      CHECK(seen == Approx(twoSided ? le * (textured ? 0.5 : 1.0) : 0.0).margin(1e-3));
    }
}
