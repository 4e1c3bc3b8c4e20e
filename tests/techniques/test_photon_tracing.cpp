// Breadth-first photon tracing: emitted power, power conservation over bounces, caustic paths and
// determinism.
#include <catch2/catch.hpp>

#include <cstring>

#include "lucent/core/parallel.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/particle_scattering.h"
#include "lucent/techniques/photons/photon_tracing.h"
#include "lucent/trace/visibility.h"
#include "test_bsdfs.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

namespace {

Rgb storedPower(const std::vector<Photon>& photons, int bounce = -1) {
  double sum[3] = {0, 0, 0};
  for (const Photon& p : photons)
    if (bounce < 0 || int(p.flags & 0xff) == bounce)
      for (int c = 0; c < 3; ++c) sum[c] += p.power[c];
  return Rgb(float(sum[0]), float(sum[1]), float(sum[2]));
}

// A closed box (side 2) of grey albedo rho whose walls all emit Ke.
Scene emissiveBox(float rho, Rgb ke) {
  return test::furnaceBox(Rgb(rho), ke, test::testCamera({0, 0, 0}, {0, 0, -1}, 8, 8));
}

// A closed, non-emitting box of albedo rho, for lights placed in code.
Scene darkBox(float rho) { return emissiveBox(rho, Rgb(0.0f)); }

}  // namespace

TEST_CASE("Photons leave area lights with the lights' total power", "[photons]") {
  const Rgb ke(1.0f, 2.0f, 0.5f);
  const Scene scene = emissiveBox(0.5f, ke);
  const Visibility vis(scene);
  PhotonTracingOptions opt;
  opt.photons = 20000;
  opt.maxBounces = 1;
  const PhotonMaps maps = tracePhotons(scene, vis, opt);
  // Every photon hits a wall of the closed box at its first bounce, carrying an equal share.
  const Rgb total = ke * (kPi * 24.0f);  // Le * pi * area of 6 faces of side 2
  const Rgb first = storedPower(maps.global, 0);
  REQUIRE(maps.global.size() == opt.photons);
  for (int c = 0; c < 3; ++c) REQUIRE(first[c] == Approx(total[c]).epsilon(1e-4));
}

TEST_CASE("A two-sided emitter sends photons from both faces, times its emissive texture", "[photons]") {
  // A 1 x 1 emitter across the middle of a closed dark box: each face emits pi A Le, the front's
  // photons landing above it, the back's below, and a two-sided emitter picks a face per photon.
  // Its emissive texture of a white and a black texel along u, read bilinearly and repeating, takes
  // values uniform in [0, 1] over the square (mean 1/2): each photon carries the value at its
  // origin. Tolerances: 4 standard errors of each sum, from the per-photon spread of the face
  // indicator I (p = 1/2) and the texture value v: relative sd of v sqrt(1/12) / (1/2), of I v
  // sqrt(1/6 - 1/16) / (1/4), of I 1; exact sums to float rounding (1e-4) where neither varies.
  const Rgb ke(1.0f, 2.0f, 0.5f);
  const double n = 20000;
  for (const bool twoSided : {true, false})
    for (const bool textured : {false, true}) {
      Scene scene = darkBox(0.5f);
      const int32_t texture = textured ? test::addTexture(scene, 2, 1, {{255, 255, 255}, {0, 0, 0}}) : -1;
      test::addCeilingEmitter(scene, 0.5f, 0, ke, twoSided, texture);
      finalizeScene(scene);
      const Visibility vis(scene);
      PhotonTracingOptions opt;
      opt.photons = uint32_t(n);
      opt.maxBounces = 1;
      const PhotonMaps maps = tracePhotons(scene, vis, opt);
      double above[3] = {0, 0, 0}, below[3] = {0, 0, 0};
      for (const Photon& p : maps.global)
        if ((p.flags & 0xff) == 0)
          for (int c = 0; c < 3; ++c) (p.position.y > 0 ? above : below)[c] += p.power[c];
      const double face = kPi * (textured ? 0.5 : 1.0);  // a face's power over Le
      const double faceSd = !twoSided ? (textured ? std::sqrt(1 / 12.0) / 0.5 : 0.0)
                                      : (textured ? std::sqrt(1 / 6.0 - 1 / 16.0) / 0.25 : 1.0);
      const double totalSd = textured ? std::sqrt(1 / 12.0) / 0.5 : 0.0;
      const double faceTolerance = std::max(1e-4, 4 * faceSd / std::sqrt(n));
      const double totalTolerance = std::max(1e-4, 4 * totalSd / std::sqrt(n));
      INFO("two-sided " << twoSided << ", textured " << textured << ": above " << above[1] << ", below " << below[1]
                        << ", a face's expected " << face * ke.g);
      for (int c = 0; c < 3; ++c) {
        CHECK(above[c] == Approx(face * ke[c]).epsilon(faceTolerance));
        if (twoSided) {
          CHECK(below[c] == Approx(face * ke[c]).epsilon(faceTolerance));
          CHECK(above[c] + below[c] == Approx(2 * face * ke[c]).epsilon(totalTolerance));
        } else {
          CHECK(below[c] == 0.0);
        }
      }
    }
}

TEST_CASE("Stored power over all bounces follows the geometric series of the albedo", "[photons]") {
  // With Russian roulette by a grey albedo rho, each photon keeps its power Phi/N and is stored
  // 1 + G times, G geometric with mean rho/(1-rho) and variance rho/(1-rho)^2.
  for (float rho : {0.3f, 0.6f, 0.85f}) {
    const Scene scene = emissiveBox(rho, Rgb(1.0f));
    const Visibility vis(scene);
    PhotonTracingOptions opt;
    opt.photons = 50000;
    opt.maxBounces = 10000;
    opt.seed = 17;
    const PhotonMaps maps = tracePhotons(scene, vis, opt);
    const double phi = kPi * 24.0, expected = phi / (1 - rho);
    const double sigma = phi * std::sqrt(rho) / (1 - rho) / std::sqrt(double(opt.photons));
    const double total = storedPower(maps.global).g;
    INFO("rho " << rho << ": stored " << total << ", expected " << expected << " +- " << sigma);
    REQUIRE(std::abs(total - expected) <= 4.5 * sigma);
    // Photons alive at bounce b: binomial with probability rho^b.
    for (size_t b = 1; b < std::min<size_t>(maps.alivePerBounce.size(), 6); ++b) {
      const double p = std::pow(rho, double(b)), n = opt.photons;
      REQUIRE(std::abs(maps.alivePerBounce[b] - n * p) <= 4.5 * std::sqrt(n * p * (1 - p)) + 1);
    }
    REQUIRE(maps.caustic.empty());
  }
}

TEST_CASE("Point, directional and environment lights emit their power", "[photons]") {
  SECTION("a point light inside a closed box: every photon lands") {
    Scene scene = darkBox(0.5f);
    scene.lights.push_back({LightType::Point, 0, {0.2f, 0.3f, -0.1f}, Rgb(3.0f, 2.0f, 1.0f) / (4 * kPi)});
    finalizeScene(scene);
    const Visibility vis(scene);
    PhotonTracingOptions opt;
    opt.photons = 10000;
    opt.maxBounces = 1;
    const Rgb first = storedPower(tracePhotons(scene, vis, opt).global, 0);
    REQUIRE(first.r == Approx(3.0f).epsilon(1e-4));
    REQUIRE(first.g == Approx(2.0f).epsilon(1e-4));
    REQUIRE(first.b == Approx(1.0f).epsilon(1e-4));
  }
  SECTION("directional and constant environment light on a small plane") {
    // A 1x1 plane in a scene whose bounding sphere is set by a far-away tiny triangle, so the
    // plane catches a small fraction of the photons: flux E cos(theta) A (directional) and
    // pi L A per side (environment); binomial tolerances.
    for (bool environment : {false, true}) {
      Scene scene;
      Material grey;
      grey.kd = Rgb(0.5f);
      const uint32_t m = test::addMaterial(scene, grey, "grey");
      test::addBox(scene, {-0.5f, -0.001f, -0.5f}, {0.5f, 0.0f, 0.5f}, m, false);
      test::addBox(scene, {3.0f, 0.0f, 0.0f}, {3.001f, 0.001f, 0.001f}, m, false);
      const Vec3 dir = normalize(Vec3{0.3f, -1.0f, 0.2f});
      if (environment) {
        scene.environment.present = true;
        scene.environment.radiance = Rgb(2.0f);
      } else {
        scene.lights.push_back({LightType::Directional, 0, dir, Rgb(5.0f)});
      }
      scene.camera = test::testCamera({0, 2, 2}, {0, 0, 0}, 8, 8);
      finalizeScene(scene);
      const Visibility vis(scene);
      PhotonTracingOptions opt;
      opt.photons = 200000;
      opt.maxBounces = 1;
      const PhotonMaps maps = tracePhotons(scene, vis, opt);
      double onPlane = 0;
      size_t hits = 0;
      for (const Photon& p : maps.global)
        if (p.position.x < 1.0f) onPlane += p.power.g, ++hits;
      // Faces of the thin slab: top and bottom 1 x 1, and four sides 1 x 0.001 (0.2% of the flux
      // under the sky; under the directional light the two it faces add 0.05%).
      const double expected = environment ? kPi * 2.0 * (2 * 1.0 + 4 * 0.001)
                                          : 5.0 * (std::abs(dir.y) * 1.0 + (std::abs(dir.x) + std::abs(dir.z)) * 0.001);
      const double perPhoton = onPlane / std::max<size_t>(hits, 1);
      const double sigma = perPhoton * std::sqrt(double(hits));  // Poisson-like count noise
      INFO((environment ? "environment" : "directional") << ": " << onPlane << " vs " << expected);
      REQUIRE(hits > 1000);
      REQUIRE(std::abs(onPlane - expected) <= 4.5 * sigma);
    }
  }
}

TEST_CASE("Caustic photons come through specular bounces only", "[photons]") {
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-spheres.json", {true});
  const Visibility vis(scene);
  PhotonTracingOptions opt;
  opt.photons = 20000;
  const PhotonMaps maps = tracePhotons(scene, vis, opt);
  REQUIRE(maps.caustic.size() > 100);
  for (const Photon& p : maps.caustic) REQUIRE((p.flags & 0xff) >= 1);
  // Every caustic photon is in the global map too.
  size_t found = 0;
  for (const Photon& c : maps.caustic)
    for (const Photon& g : maps.global)
      if (g.position == c.position && g.power == c.power) {
        ++found;
        break;
      }
  REQUIRE(found == maps.caustic.size());
  const Scene diffuse = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  const Visibility diffuseVis(diffuse);
  REQUIRE(tracePhotons(diffuse, diffuseVis, opt).caustic.empty());
}

TEST_CASE("Photon maps are identical with 1 and 2 threads", "[photons][determinism]") {
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-spheres.json", {true});
  PhotonTracingOptions opt;
  opt.photons = 30000;
  std::vector<Photon> reference;
  for (int threads : {1, 2}) {
    ParallelScope scope(threads);
    const Visibility vis(scene);
    const auto maps = tracePhotons(scene, vis, opt);
    if (threads == 1) {
      reference = maps.global;
    } else {
      REQUIRE(maps.global.size() == reference.size());
      REQUIRE(std::memcmp(maps.global.data(), reference.data(), reference.size() * sizeof(Photon)) == 0);
    }
  }
}

TEST_CASE("Caustic-only tracing stores the caustic photons of full tracing, flagged", "[photons]") {
  // Paths are keyed by (seed, photon index, bounce), so ending them at their first non-specular
  // surface changes nothing before it: the caustic map is the same, at a fraction of the work.
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-spheres.json", {true});
  const Visibility vis(scene);
  PhotonTracingOptions opt;
  opt.photons = 20000;
  opt.seed = 8;
  const PhotonMaps full = tracePhotons(scene, vis, opt);
  opt.causticOnly = true;
  const PhotonMaps only = tracePhotons(scene, vis, opt);
  REQUIRE(only.global.empty());
  REQUIRE(only.caustic.size() == full.caustic.size());
  REQUIRE(std::memcmp(only.caustic.data(), full.caustic.data(), full.caustic.size() * sizeof(Photon)) == 0);
  size_t flagged = 0;
  for (const Photon& p : full.global) {
    flagged += photonIsCaustic(p);
    if (photonIsCaustic(p)) REQUIRE(photonBounce(p) >= 1);
  }
  REQUIRE(flagged == full.caustic.size());
  for (const Photon& p : full.caustic) REQUIRE(photonIsCaustic(p));
  REQUIRE(only.alivePerBounce.size() < full.alivePerBounce.size());
}

TEST_CASE("Caustic emission aimed at the specular objects stores the same caustic power", "[photons][caustic]") {
  // Aiming changes the density of the sampled paths, not their expectation: the caustic map's
  // total power with and without aiming agrees within the two estimates' standard errors, for an
  // area light, a point light, a directional light, an environment and two point lights apart (each
  // aimed through its own projection map), while aiming stores many more photons per path.
  auto caustic = [](const Scene& scene, uint32_t photons, bool aimed) {
    const Visibility vis(scene);
    PhotonTracingOptions opt;
    opt.photons = photons;
    opt.causticOnly = true;
    opt.seed = aimed ? 3 : 4;
    if (aimed) opt.target = specularTarget(scene);
    REQUIRE(opt.target.has_value() == aimed);
    const std::vector<Photon> stored = tracePhotons(scene, vis, opt).caustic;
    // Each path stores at most one caustic photon: the total is a mean over paths.
    double sum = 0, sum2 = 0;
    for (const Photon& p : stored) {
      const double v = double(p.power.r) + p.power.g + p.power.b;
      sum += v, sum2 += v * v;
    }
    const double variance = std::max(0.0, sum2 - sum * sum / photons);
    return std::tuple{sum, std::sqrt(variance), stored.size()};
  };
  enum class Sky { Directional, Environment, TwoPointLights };
  auto mirrorOnPlane = [](Sky sky) {
    Scene scene;
    Material grey, mirror;
    grey.kd = Rgb(0.5f);
    mirror.type = MaterialType::Mirror;
    mirror.kd = Rgb(0.0f);
    mirror.ks = Rgb(0.9f);
    test::addBox(scene, {-2, -0.01f, -2}, {2, 0, 2}, test::addMaterial(scene, grey, "grey"), false);
    test::addBox(scene, {-0.3f, 0.2f, -0.3f}, {0.3f, 0.5f, 0.3f}, test::addMaterial(scene, mirror, "mirror"), false);
    if (sky == Sky::Environment) {
      scene.environment.present = true;
      scene.environment.radiance = Rgb(1.0f);
    } else if (sky == Sky::Directional) {
      scene.lights.push_back({LightType::Directional, 0, normalize(Vec3{0.4f, -1.0f, 0.1f}), Rgb(2.0f)});
    } else {
      scene.lights.push_back({LightType::Point, 0, {-1.5f, 1.5f, 0.3f}, Rgb(2.0f)});
      scene.lights.push_back({LightType::Point, 0, {1.2f, 1.0f, -0.8f}, Rgb(3.0f)});
    }
    scene.camera = test::testCamera({0, 3, 3}, {0, 0, 0}, 8, 8);
    finalizeScene(scene);
    return scene;
  };
  struct Case {
    const char* name;
    Scene scene;
    uint32_t photons;
  };
  std::vector<Case> cases;
  cases.push_back({"area light", loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-spheres.json", {true}), 100000});
  cases.push_back({"point light", loadScene(LUCENT_SOURCE_DIR "/scenes/ring.json", {true}), 400000});
  cases.push_back({"directional", mirrorOnPlane(Sky::Directional), 100000});
  cases.push_back({"environment", mirrorOnPlane(Sky::Environment), 200000});
  cases.push_back({"two point lights", mirrorOnPlane(Sky::TwoPointLights), 200000});
  for (const Case& c : cases) {
    const auto [plain, plainError, plainStored] = caustic(c.scene, c.photons, false);
    const auto [aimed, aimedError, aimedStored] = caustic(c.scene, c.photons / 4, true);
    INFO(c.name << ": caustic power " << aimed << " +- " << aimedError << " aimed (" << aimedStored << " photons), "
                << plain << " +- " << plainError << " in every direction (" << plainStored << " photons)");
    REQUIRE(plainStored > 100);
    REQUIRE(std::abs(aimed - plain) <= 4 * std::hypot(aimedError, plainError));
    // Per path (a quarter as many aimed): a smaller variance, and more photons stored, by more than
    // 4.5 standard deviations of the difference of the two counts (Poisson: 16 A + P).
    REQUIRE(aimedError * std::sqrt(c.photons / 4.0) < plainError * std::sqrt(double(c.photons)));
    REQUIRE(aimedStored * 4.0 - plainStored > 4.5 * std::sqrt(16.0 * aimedStored + plainStored));
  }
}

TEST_CASE("Photons under shading normals carry what the path tracer's radiance does", "[photons]") {
  // A floor A (y = 0, x in [0, 4], Kd 0.8) lit from straight above by a directional light, and a
  // wall B (x = 0, Kd 0.5) that sees only the floor's reflection; both with shading normals tilted
  // away from the geometric ones (27 and 30 degrees). The path tracer reflects radiance with the
  // shading normal's cosine, and takes the geometric normal where its viewer is below the shading
  // normal: A sends L_A = (0.8 / pi) E (l . ns_A) towards directions above ns_A and (0.8 / pi) E
  // into the wedge below it, and B's irradiance, with B's shading cosine, is the integral over A
  // of L_A max(0, w . ns_B) cos_A / r^2 (midpoint rule over 64 x 64 floor cells). Checked first
  // against the path tracer itself (4.5 standard errors of its pixels' differences to it, 0.25%:
  // the shading cosine in the wedge too would be 1.6% off), then the flux that
  // B's photons store on a 1 x 1 patch against it (4.5 standard deviations of the photons' powers
  // as a Poisson process). Photons that kept their flux per unit of true area would store 1.36
  // times as much; scattered about the shading normal alone, 0.85 times (particle_scattering.h).
  Scene scene;
  Material floor, wall;
  floor.kd = Rgb(0.8f);
  wall.kd = Rgb(0.5f);
  const Vec3 nsA = normalize(Vec3{0.3f, 1, 0.4f}), nsB = normalize(Vec3{1, 0.5f, -0.3f});
  test::addQuad(scene, {0, 0, -2}, {0, 0, 2}, {4, 0, 2}, {4, 0, -2}, test::addMaterial(scene, floor, "floor"), nsA);
  test::addQuad(scene, {0, 0, -2}, {0, 2, -2}, {0, 2, 2}, {0, 0, 2}, test::addMaterial(scene, wall, "wall"), nsB);
  const float irradiance = 2;
  scene.lights.push_back({LightType::Directional, 0, Vec3{0, -1, 0}, Rgb(irradiance)});
  scene.camera = test::testCamera({2, 1, 3}, {0, 0.5f, 0}, 8, 8);
  finalizeScene(scene);
  REQUIRE(scene.geometricNormal(0).y > 0.99f);
  REQUIRE(scene.geometricNormal(2).x > 0.99f);
  const Visibility vis(scene);

  // B's irradiance at x as the path tracer sees it (midpoint rule over 64 x 64 floor cells).
  const double radianceA = 0.8 * kInvPi * irradiance * nsA.y, radianceWedge = 0.8 * kInvPi * irradiance;
  auto irradianceAt = [&](Vec3 x) {
    constexpr int cells = 64;
    double e = 0;
    for (int l = 0; l < cells; ++l)
      for (int k = 0; k < cells; ++k) {
        const Vec3 a{4.0f * (k + 0.5f) / cells, 0, -2 + 4.0f * (l + 0.5f) / cells};
        const Vec3 d = a - x;
        const float r2 = dot(d, d);
        const Vec3 w = d / std::sqrt(r2);  // from B towards the floor
        if (dot(w, nsB) <= 0) continue;
        // Seen from the wedge below its shading normal, the path tracer takes A's geometric one.
        const double radiance = dot(-w, nsA) > 0 ? radianceA : radianceWedge;
        e += radiance * double(dot(w, nsB)) * -w.y / r2 * (16.0 / (cells * cells));
      }
    return e;
  };

  // The path tracer itself (two bounces: floor, wall), through the pixel centres of a view of B,
  // against the quadrature at the points they see: this is the answer photons must reach.
  {
    PathTraceOptions pt;
    pt.common.spp = 4096;
    pt.maxDepth = 2;
    pt.pixelCentres = true;
    Scene view = scene;
    view.camera = test::testCamera({2, 1, 0}, {0, 1, 0}, 16, 16, 20);
    const Image image = renderPathTraced(view, Visibility(view), pt).image;
    const PinholeCamera camera(view.camera);
    // The standard error from the spread of the pixels' differences to the quadrature: their
    // noise, not the radiance's variation across the wall.
    std::vector<double> differences;
    double quadrature = 0;
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        const Ray ray = camera.generate(float(x) + 0.5f, float(y) + 0.5f);
        const double q = 0.5 * kInvPi * irradianceAt(ray.origin + ray.direction * (-ray.origin.x / ray.direction.x));
        differences.push_back(image.at(x, y, 1) - q);
        quadrature += q;
      }
    const test::MeanAndError difference = test::meanOf(differences);
    INFO("path tracer minus quadrature " << difference.mean << " +- " << difference.standardError << ", quadrature "
                                         << quadrature / double(differences.size()));
    CHECK(std::abs(difference.mean) <= 4.5 * difference.standardError);
  }

  // The flux onto the patch y in [0.5, 1.5], z in [-0.5, 0.5] of B (8 x 8 points).
  double expected = 0;
  constexpr int patchCells = 8;
  for (int j = 0; j < patchCells; ++j)
    for (int i = 0; i < patchCells; ++i)
      expected += irradianceAt({0, 0.5f + (i + 0.5f) / patchCells, -0.5f + (j + 0.5f) / patchCells}) /
                  (patchCells * patchCells);

  PhotonTracingOptions opt;
  opt.photons = 4000000;
  opt.maxBounces = 2;  // the light's photon stored on the floor, then on the wall
  opt.seed = 5;
  const PhotonMaps maps = tracePhotons(scene, vis, opt);
  double flux = 0, flux2 = 0;
  size_t count = 0;
  for (const Photon& p : maps.global)
    if (p.position.x < 1e-3f && p.position.y > 0.5f && p.position.y < 1.5f && std::abs(p.position.z) < 0.5f) {
      REQUIRE((p.flags & 0xff) == 1);
      flux += p.power.g, flux2 += double(p.power.g) * p.power.g, ++count;
    }
  INFO("patch: " << count << " photons, flux " << flux << " +- " << std::sqrt(flux2) << ", path tracer's " << expected);
  REQUIRE(count > 10000);
  CHECK(std::abs(flux - expected) <= 4.5 * std::sqrt(flux2));
}

TEST_CASE("Particle scattering: without shading normals the BSDF sample itself, with them the adjoint's two regions",
          "[photons]") {
  SurfacePoint flat;
  flat.geometricNormal = flat.shadingNormal = normalize(Vec3{0.2f, 1, -0.1f});
  // A face whose geometric normal is +z and whose shading normal leans towards +x by `degrees`.
  auto tiltedBy = [](float degrees) {
    SurfacePoint tilted;
    tilted.geometricNormal = {0, 0, 1};
    tilted.shadingNormal = normalize(Vec3{std::sin(degrees * kPi / 180), 0, std::cos(degrees * kPi / 180)});
    return tilted;
  };
  const SurfaceBsdf glass = GlassLobe{1.5f};
  const SurfaceBsdf mirror = MirrorLobe{Rgb(0.9f)};
  SECTION("a face without vertex normals: sampleBsdf's weight bit for bit, and no number drawn") {
    Rng numbers(3);
    for (const SurfaceBsdf& b : {test::diffuseBsdf(Rgb(0.6f)), test::phongBsdf(Rgb(0.2f), Rgb(0.5f), 20), glass, mirror})
      for (int k = 0; k < 2000; ++k) {
        const Vec3 wo = sampleUniformSphere(numbers.uniform2());
        const float uLobe = numbers.uniform();
        const Vec2 u2 = numbers.uniform2();
        Rng rng(11, uint64_t(k)), untouched(11, uint64_t(k));
        const ParticleScatter s = scatterParticle(b, flat, wo, uLobe, u2, rng);
        REQUIRE(rng.next() == untouched.next());
        const Vec3 n = particleShadingNormal(b, flat, wo);
        const Frame frame(n);
        const BsdfSample bs = sampleBsdf(b, frame.toLocal(wo), uLobe, u2, Transport::Importance);
        REQUIRE(s.valid == bs.valid);
        if (!s.valid) continue;
        REQUIRE(s.weight == bs.weight);
        REQUIRE(s.wi == frame.toWorld(bs.wi));
        REQUIRE(particleArrivalRatio(flat, n, wo) == 1.0f);
      }
  }
  SECTION("a mirror with a tilted normal sends the particle to each viewer the path tracer reflects into it") {
    // Shading normal 35 degrees from the geometric one (+z). Arriving near the normal, only the
    // reflection about the shading normal is a viewer the path tracer reflects into wo (weight
    // Ks cos(wi, ng) / cos(wo, ng)); arriving at 77 degrees on the tilt's side, the reflection about
    // the geometric normal lies in the wedge too (weight Ks): one of the two at random, twice
    // the weight, each half the time (4.5 binomial standard deviations of 20,000).
    const SurfacePoint tilted = tiltedBy(35);
    Rng rng(8);
    const Vec3 near = normalize(Vec3{0.1f, 0, 1});
    const ParticleScatter one = scatterParticle(mirror, tilted, near, 0.5f, {0.5f, 0.5f}, rng);
    const Vec3 aboutShading = reflect(near, tilted.shadingNormal);
    REQUIRE(one.valid);
    REQUIRE(one.delta);
    CHECK(length(one.wi - aboutShading) < 1e-6f);
    CHECK(one.weight.r == Approx(0.9 * aboutShading.z / near.z).epsilon(1e-6));
    const Vec3 grazing = normalize(Vec3{0.9f, 0, 0.2f});
    const Vec3 viaShading = reflect(grazing, tilted.shadingNormal), viaGeometric = reflect(grazing, {0, 0, 1});
    REQUIRE(viaShading.z > 0);
    REQUIRE(dot(viaGeometric, tilted.shadingNormal) < 0);
    int shading = 0;
    constexpr int n = 20000;
    for (int k = 0; k < n; ++k) {
      const ParticleScatter s = scatterParticle(mirror, tilted, grazing, 0.5f, {0.5f, 0.5f}, rng);
      REQUIRE(s.valid);
      if (length(s.wi - viaShading) < 1e-6f) {
        ++shading;
        REQUIRE(s.weight.r == Approx(2 * 0.9 * viaShading.z / grazing.z).epsilon(1e-6));
      } else {
        REQUIRE(length(s.wi - viaGeometric) < 1e-6f);
        REQUIRE(s.weight.r == Approx(2 * 0.9).epsilon(1e-6));
      }
    }
    CHECK(std::abs(shading - n / 2) <= 4.5 * std::sqrt(n / 4.0));
  }
  SECTION("a mirror's particles carry what the path tracer's mirror reflects, for any light and viewers") {
    // The path tracer's mirror (pathtracer.cpp): a viewer in direction v sees Ks L(l), l = v
    // reflected about the shading normal where v is above it, about the geometric normal in the
    // wedge, and nothing where l ends up on the other side of the true surface. Particles must
    // carry the same light: for incident radiance L and viewers' importance W, both sides of the
    // mirror, integral of W(v) Ks L(l(v)) |cos(v, ng)| over v equals integral of L(l) |cos(l, ng)|
    // times the mean of W(wi) * weight over l's scattered particles. Each side by Monte Carlo
    // (directions uniform over the sphere, 10^6), required within 4.5 standard errors. L: a 0.13 sr
    // cone (a small light) near grazing on the tilt's side, whose reflections about the geometric
    // normal fall in the wedge, or behind the mirror, over a dim linear background; W jumps by 3
    // across the plane of the tilt so that the two reflections of a particle are told apart.
    for (const float degrees : {15.0f, 40.0f})
      for (const Vec3 light : {normalize(Vec3{0.97f, 0.1f, 0.15f}), normalize(Vec3{-0.6f, 0.3f, -0.7f})}) {
        const SurfacePoint tilted = tiltedBy(degrees);
        const Vec3 ng = tilted.geometricNormal, ns = tilted.shadingNormal;
        auto incident = [&](Vec3 l) { return (dot(l, light) > 0.98f ? 1.0 : 0.0) + 0.05 * (1 + l.x); };
        auto importance = [](Vec3 v) { return 1.0 + v.x + 2 * v.y * v.y + (v.x < 0 ? 3.0 : 0.0); };
        Rng rng(17, uint64_t(degrees), uint64_t(light.z < 0));
        constexpr int n = 1000000;
        std::vector<double> viewers(n), particles(n);
        for (int k = 0; k < n; ++k) {
          const Vec3 v = sampleUniformSphere(rng.uniform2());
          Vec3 normal = dot(v, ns) * dot(v, ng) > 0 ? ns : ng;
          if (dot(v, ng) < 0) normal = -normal;
          const Vec3 l = reflect(v, normal);
          viewers[k] = dot(l, ng) * dot(v, ng) > 0 ? importance(v) * 0.9 * incident(l) * std::abs(dot(v, ng)) * 4 * kPi : 0;
          const Vec3 wo = sampleUniformSphere(rng.uniform2());
          const float uLobe = rng.uniform();
          const Vec2 u2 = rng.uniform2();
          const ParticleScatter s = scatterParticle(mirror, tilted, wo, uLobe, u2, rng);
          particles[k] = s.valid ? incident(wo) * std::abs(dot(wo, ng)) * 4 * kPi * importance(s.wi) * s.weight.r : 0;
        }
        const test::MeanAndError radiance = test::meanOf(viewers), adjoint = test::meanOf(particles);
        INFO(degrees << " degrees, light from " << light.x << ", " << light.y << ", " << light.z << ": radiance "
                     << radiance.mean << " +- " << radiance.standardError << ", particles " << adjoint.mean << " +- "
                     << adjoint.standardError);
        CHECK(std::abs(adjoint.mean - radiance.mean) <= 4.5 * std::hypot(radiance.standardError, adjoint.standardError));
      }
  }
  SECTION("glass takes a particle only from the side of the shading normal its surface is on") {
    // Shading normals 35 and 60 degrees from the geometric one (+z). A particle arriving above the
    // true surface but below the shading normal, or the other way round, carries nothing further
    // (the path tracer's glass would see no light from there); one above both reflects about the
    // shading normal with the geometric cosines' ratio, or refracts into the other side.
    Rng rng(12);
    for (const float degrees : {35.0f, 60.0f}) {
      const SurfacePoint steep = tiltedBy(degrees);
      int wrongSide = 0;
      for (int k = 0; k < 20000; ++k) {
        const Vec3 wo = sampleUniformSphere(rng.uniform2());
        if (dot(wo, steep.geometricNormal) * dot(wo, steep.shadingNormal) >= 0) continue;
        ++wrongSide;
        const float uLobe = rng.uniform();
        const ParticleScatter s = scatterParticle(glass, steep, wo, uLobe, rng.uniform2(), rng);
        REQUIRE_FALSE((s.valid && !s.weight.isBlack()));
      }
      REQUIRE(wrongSide > 1000);
    }
    const SurfacePoint tilted = tiltedBy(35);
    const Vec3 wo = normalize(Vec3{0.1f, 0.3f, 1});
    int reflected = 0;
    for (int k = 0; k < 1000; ++k) {
      const float uLobe = rng.uniform();
      const ParticleScatter s = scatterParticle(glass, tilted, wo, uLobe, rng.uniform2(), rng);
      REQUIRE(s.valid);
      REQUIRE(s.delta);
      if (s.wi.z > 0) {
        ++reflected;
        REQUIRE(length(s.wi - reflect(wo, tilted.shadingNormal)) < 1e-6f);
        REQUIRE(s.weight.r == Approx(s.wi.z / wo.z).epsilon(1e-5));
      } else {
        REQUIRE(dot(s.wi, tilted.shadingNormal) < 0);
      }
    }
    CHECK(reflected > 0);
  }
  SECTION("tilted normals: each region's mean weight is the adjoint kernel's integral over it") {
    // A Lambertian surface, shading normal 35 degrees from the geometric one, a particle arriving
    // from wo. The adjoint kernel for a viewer wi above the true surface is
    // kd / pi * cos(wo, N(wi)) / cos(wo, ng) * cos(wi, ng), N(wi) the shading normal where wi is
    // above it, the geometric one in the wedge. Its integral: kd r (1 - w) over the shading
    // region and kd w over the wedge, r = cos(wo, ns) / cos(wo, ng), w = (1 - cos 35) / 2.
    // Required: each region's sample mean within 4.5 standard errors (200,000 samples).
    const SurfacePoint tilted = tiltedBy(35);
    const SurfaceBsdf b = test::diffuseBsdf(Rgb(0.6f));
    const float w = 0.5f * (1 - std::cos(35 * kPi / 180));
    for (const Vec3 wo : {normalize(Vec3{0.3f, 0.2f, 1}), normalize(Vec3{-0.8f, 0.1f, 0.4f})}) {
      const double r = std::max(0.0f, dot(wo, tilted.shadingNormal)) / dot(wo, tilted.geometricNormal);
      constexpr int n = 200000;
      std::vector<double> weights[2] = {std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};  // per region
      Rng rng(5);
      for (int k = 0; k < n; ++k) {
        const float uLobe = rng.uniform();
        const Vec2 u2 = rng.uniform2();
        const ParticleScatter s = scatterParticle(b, tilted, wo, uLobe, u2, rng);
        if (!s.valid) continue;
        REQUIRE(dot(s.wi, tilted.geometricNormal) > 0);
        weights[dot(s.wi, tilted.shadingNormal) > 0 ? 0 : 1][k] = s.weight.r;
      }
      const double expected[2] = {0.6 * r * (1 - w), 0.6 * w};
      for (int region = 0; region < 2; ++region) {
        const test::MeanAndError mean = test::meanOf(weights[region]);
        INFO("wo " << wo.x << " " << wo.y << " " << wo.z << ", region " << region << ": " << mean.mean << " +- "
                   << mean.standardError << ", expected " << expected[region]);
        CHECK(std::abs(mean.mean - expected[region]) <= 4.5 * mean.standardError);
      }
    }
  }
  SECTION("tilted normals on a volume's boundary: each region's mean weight is the adjoint kernel's integral") {
    // A rough glTF boundary (index 1.5, roughness 0.5) with the shading normal 35 degrees from the
    // geometric one, a particle arriving from outside or inside. The path tracer's viewer wi sees
    // the lobe in the shading frame where wi lies on the same side of both normals (region A),
    // else in the winding's geometric frame (the wedges W, one on each side). The adjoint kernel:
    // f_N(wi)(wi, wo) cos(wo, N(wi)) / cos(wo, ng) |cos(wi, ng)|, its integral over each region by
    // the midpoint rule (1,200 x 2,400 directions). Required: each region's sample mean within 4.5
    // standard errors (200,000 samples). W's integral measured 0.0023 from outside and 0.11 (of
    // 1.06) from inside; without the wedges their means were 0.
    const SurfacePoint tilted = tiltedBy(35);
    Material m;
    m.type = MaterialType::Gltf;
    m.kd = Rgb(1.0f), m.ks = Rgb(1.0f), m.ni = 1.5f, m.metallic = 0, m.roughness = 0.5f, m.transmission = 1;
    m.boundsVolume = 1;
    const SurfaceBsdf b = materialBsdf(m);
    const Frame shading(tilted.shadingNormal), winding(tilted.geometricNormal);
    const SurfaceBsdf inShading = b.inFrame(shading), inWinding = b.inFrame(winding);
    auto inRegionA = [&](Vec3 d) { return dot(d, tilted.shadingNormal) * dot(d, tilted.geometricNormal) > 0; };
    for (const Vec3 wo : {normalize(Vec3{0.3f, 0.2f, 1}), normalize(Vec3{-0.5f, 0.1f, -0.8f})}) {
      const double r = inRegionA(wo) ? std::abs(dot(wo, tilted.shadingNormal) / dot(wo, tilted.geometricNormal)) : 0;
      double expected[2] = {0, 0};
      constexpr int nTheta = 1200, nPhi = 2400;
      for (int i = 0; i < nTheta; ++i) {
        const double theta = (i + 0.5) * kPi / nTheta;
        for (int j = 0; j < nPhi; ++j) {
          const Vec3 wi = test::directionAt(theta, (j + 0.5) * 2 * kPi / nPhi);
          const double dw = std::sin(theta) * (kPi / nTheta) * (2 * kPi / nPhi), cosine = std::abs(wi.z);
          if (inRegionA(wi))
            expected[0] += evalBsdf(inShading, shading.toLocal(wi), shading.toLocal(wo)).r * r * cosine * dw;
          else
            expected[1] += evalBsdf(inWinding, winding.toLocal(wi), winding.toLocal(wo)).r * cosine * dw;
        }
      }
      constexpr int n = 200000;
      std::vector<double> weights[2] = {std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
      Rng rng(6);
      for (int k = 0; k < n; ++k) {
        const float uLobe = rng.uniform();
        const Vec2 u2 = rng.uniform2();
        const ParticleScatter s = scatterParticle(b, tilted, wo, uLobe, u2, rng);
        if (s.valid) weights[inRegionA(s.wi) ? 0 : 1][k] = s.weight.r;
      }
      for (int region = 0; region < 2; ++region) {
        const test::MeanAndError mean = test::meanOf(weights[region]);
        INFO("wo " << wo.x << " " << wo.y << " " << wo.z << ", region " << region << ": " << mean.mean << " +- "
                   << mean.standardError << ", expected " << expected[region]);
        CHECK(std::abs(mean.mean - expected[region]) <= 4.5 * mean.standardError);
      }
    }
  }
}

TEST_CASE("A point light's projection map marks every direction towards a specular triangle", "[photons][caustic]") {
  // Aiming through the marked cells only is unbiased if no caustic path starts through an unmarked
  // one: directions from RING's light to random points of every mirror triangle (and to their
  // corners) must all lie in marked cells. The map must also be tighter than the sphere's cone.
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/ring.json", {true});
  const std::optional<EmissionTarget> target = specularTarget(scene);
  REQUIRE(target.has_value());
  REQUIRE(target->pointLightMaps.size() == scene.lights.size());
  const ProjectionMap& map = target->pointLightMaps[0];
  REQUIRE(!map.cells.empty());
  std::vector<uint8_t> marked(size_t(map.resolution) * map.resolution, 0);
  for (uint32_t c : map.cells) marked[c] = 1;
  const Vec3 light = scene.lights[0].vector;
  Rng rng(12);
  size_t checked = 0, unmarked = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    if (scene.materials[scene.materialIds[t]].type != MaterialType::Mirror) continue;
    for (int sample = 0; sample < 8; ++sample) {
      const Vec2 b = sample < 3 ? Vec2(sample == 1 ? 1.0f : 0.0f, sample == 2 ? 1.0f : 0.0f) : sampleUniformTriangle(rng.uniform2());
      const Vec3 p = barycentric(scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2), b.x, b.y);
      const Vec3 d = map.frame.toLocal(p - light);
      REQUIRE(d.z > 0);
      const int32_t cx = int32_t(std::floor((d.x / d.z + map.extent) / map.cellSide()));
      const int32_t cy = int32_t(std::floor((d.y / d.z + map.extent) / map.cellSide()));
      REQUIRE((cx >= 0 && cy >= 0 && cx < int32_t(map.resolution) && cy < int32_t(map.resolution)));
      unmarked += !marked[size_t(cy) * map.resolution + size_t(cx)];
      ++checked;
    }
  }
  CHECK(checked > 40000);
  CHECK(unmarked == 0);
  // The marked cells' solid angle against the cone's (2 pi (1 - cos)).
  double marked_solid_angle = 0;
  const float side = map.cellSide();
  for (uint32_t c : map.cells) {
    const float x = -map.extent + (float(c % map.resolution) + 0.5f) * side, y = -map.extent + (float(c / map.resolution) + 0.5f) * side;
    marked_solid_angle += side * side / std::pow(1 + x * x + y * y, 1.5);
  }
  TargetCone cone;
  REQUIRE(coneTowards(*target, light, cone));
  INFO("marked " << map.cells.size() << " cells, " << marked_solid_angle << " sr against the cone's " << cone.solidAngle);
  CHECK(marked_solid_angle < 0.6 * cone.solidAngle);

  // The sampler: every direction through a marked cell, and the weights' mean (power over
  // intensity, 1 / density) the marked cells' solid angle, by quadrature (8 x 8 points a cell).
  double exact = 0;
  for (uint32_t c : map.cells)
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) {
        const double x = -map.extent + (double(c % map.resolution) + (i + 0.5) / 8) * side;
        const double y = -map.extent + (double(c / map.resolution) + (j + 0.5) / 8) * side;
        exact += double(side) * side / 64 / std::pow(1 + x * x + y * y, 1.5);
      }
  const uint32_t samples = 400000;
  double sum = 0, sum2 = 0;
  size_t outside = 0;
  for (uint32_t i = 0; i < samples; ++i) {
    Rng r(21, i, 0);
    const float uLight = r.uniform();
    const Vec2 uPosition = r.uniform2(), uDirection = r.uniform2();
    const EmissionSample e = sampleEmission(scene, uLight, uPosition, uDirection, &*target, r.next());
    REQUIRE(e.valid);
    const Vec3 d = map.frame.toLocal(e.ray.direction);
    const int32_t cx = int32_t(std::floor((d.x / d.z + map.extent) / side));
    const int32_t cy = int32_t(std::floor((d.y / d.z + map.extent) / side));
    outside += !(cx >= 0 && cy >= 0 && cx < int32_t(map.resolution) && cy < int32_t(map.resolution) &&
                 marked[size_t(cy) * map.resolution + size_t(cx)]);
    const double w = double(e.power.r) / double(scene.lights[0].value.r);
    sum += w, sum2 += w * w;
  }
  const double mean = sum / samples, se = std::sqrt(std::max(0.0, sum2 / samples - mean * mean) / samples);
  INFO("mean weight " << mean << " +- " << se << " against " << exact << " sr");
  CHECK(outside < samples / 10000);  // rounding at a cell's edge only
  CHECK(std::abs(mean - exact) <= 4 * se);
}
