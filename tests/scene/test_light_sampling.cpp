// Chi-square tests of next-event estimation (light_sampling.h): directions sampled towards emissive
// triangles and the environment against densities computed independently here (ray-triangle
// intersection, lat-long texel lookup), the light choice against the power estimates, and the delta
// lights' directions and radiance; with negative controls that wrong samplers are rejected.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "chi2.h"
#include "lucent/core/rng.h"
#include "lucent/image/image.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/loader.h"
#include "test_bsdfs.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;
using chi2::DirectionSample;
using chi2::IndexSample;
namespace fs = std::filesystem;

namespace {

// The number of passing chi-square tests below (negative controls excluded): two triangle-light
// scenes, the environment map and the constant environment, and the light choice.
constexpr int kChi2Tests = 5;
const double kAlpha = chi2::sidak(0.01, kChi2Tests);

// Double-precision vectors for the reference densities.
struct D3 {
  double x = 0, y = 0, z = 0;
  D3() = default;
  D3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  explicit D3(Vec3 v) : x(v.x), y(v.y), z(v.z) {}
};
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double length(D3 a) { return std::sqrt(dot(a, a)); }

// Moller-Trumbore: distance along the unit direction d from o to triangle (p0, p1, p2), if it is hit;
// `slack` widens the triangle by that much in barycentric terms (for points sampled on an edge).
std::optional<double> intersect(D3 o, D3 d, D3 p0, D3 p1, D3 p2, double slack = 0) {
  const D3 e1 = p1 - p0, e2 = p2 - p0, pv = cross(d, e2);
  const double det = dot(e1, pv);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const D3 tv = o - p0;
  const double b1 = dot(tv, pv) / det;
  const D3 qv = cross(tv, e1);
  const double b2 = dot(d, qv) / det, t = dot(e2, qv) / det;
  if (b1 < -slack || b2 < -slack || b1 + b2 > 1 + slack || !(t > 0)) return std::nullopt;
  return t;
}

double luminance(Rgb c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

uint32_t addTriangle(Scene& scene, Vec3 a, Vec3 b, Vec3 c, uint32_t material) {
  const auto base = uint32_t(scene.positions.size());
  for (Vec3 p : {a, b, c}) {
    scene.positions.push_back(p);
    scene.normals.push_back({0, 0, 0});
    scene.texcoords.push_back({0, 0});
  }
  scene.indices.insert(scene.indices.end(), {base, base + 1, base + 2});
  scene.materialIds.push_back(material);
  return scene.triangleCount() - 1;
}
// A triangle wound so that its emitting (counter-clockwise) side faces `viewer`, or turns its back on it.
uint32_t addTriangleFacing(Scene& scene, Vec3 a, Vec3 b, Vec3 c, uint32_t material, Vec3 viewer, bool front) {
  const bool faces = dot(cross(b - a, c - a), viewer - a) > 0;
  return faces == front ? addTriangle(scene, a, b, c, material) : addTriangle(scene, a, c, b, material);
}
uint32_t emitter(Scene& scene, Rgb ke, const std::string& name) {
  Material m;
  m.kd = Rgb(0.0f);
  m.ke = ke;
  return test::addMaterial(scene, m, name);
}

// Receiver at the origin; three emitters of different sizes, emission and tilts facing it, in
// separate directions within 65 degrees of +y, one that turns its back on it, and a diffuse floor.
// With `overlap`, a fourth emitter behind the first covers part of it, seen from the receiver.
const Vec3 kReceiver{0, 0, 0};
Scene triangleLightScene(bool overlap) {
  Scene scene;
  const uint32_t white = test::addMaterial(scene, Material{}, "white");
  addTriangle(scene, {-3, -1, -3}, {3, -1, -3}, {0, -1, 3}, white);
  addTriangleFacing(scene, {-1.5f, 3, -1}, {1.5f, 3, -1}, {0, 3, 1.8f}, emitter(scene, Rgb(4.0f), "big"), kReceiver,
                    true);
  const Vec3 c1{1.8f, 2.0f, 0.8f};
  addTriangleFacing(scene, c1 + Vec3(0.3f, 0, 0), c1 + Vec3(0, 0.25f, 0.1f), c1 + Vec3(-0.1f, -0.1f, 0.3f),
                    emitter(scene, {30, 20, 10}, "small"), kReceiver, true);
  addTriangleFacing(scene, {-2.2f, 1, 0.3f}, {-1.8f, 2.2f, 1.2f}, {-2.3f, 1.2f, 1.8f},
                    emitter(scene, {1, 2, 3}, "blue"), kReceiver, true);
  addTriangleFacing(scene, {0, 1.7f, -2}, {1, 1.8f, -2.2f}, {0.5f, 2.5f, -1.9f}, emitter(scene, Rgb(5.0f), "away"),
                    kReceiver, false);
  if (overlap)
    addTriangleFacing(scene, {0.5f, 4.5f, -2}, {3, 4.5f, -1}, {1, 4.5f, 2}, emitter(scene, {2, 1, 1}, "behind"),
                      kReceiver, true);
  finalizeScene(scene);
  return scene;
}

// Selection probabilities of the emissive triangles when they are the only lights: proportional to
// luminance(Ke) times area (the pi of the power estimate cancels).
std::vector<double> trianglePmf(const Scene& scene) {
  std::vector<double> pmf(scene.triangleCount(), 0.0);
  double sum = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    const D3 p0(scene.vertex(t, 0)), p1(scene.vertex(t, 1)), p2(scene.vertex(t, 2));
    pmf[t] = luminance(scene.materials[scene.materialIds[t]].ke) * 0.5 * length(cross(p1 - p0, p2 - p0));
    sum += pmf[t];
  }
  for (double& p : pmf) p /= sum;
  return pmf;
}

// The solid-angle density of sampleLight's directions from `receiver`, summed over every emitter the
// ray meets: pmf * distance^2 / (cos_light * area) where the ray reaches the emitting side.
double referenceTrianglePdf(const Scene& scene, const std::vector<double>& pmf, Vec3 receiver, Vec3 direction) {
  const D3 o(receiver), d = D3(direction) * (1 / length(D3(direction)));
  double pdf = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    if (pmf[t] == 0) continue;
    const D3 p0(scene.vertex(t, 0)), p1(scene.vertex(t, 1)), p2(scene.vertex(t, 2));
    const auto dist = intersect(o, d, p0, p1, p2);
    if (!dist) continue;
    const D3 n = cross(p1 - p0, p2 - p0);
    const double area = 0.5 * length(n), cosLight = -dot(d, n) / length(n);
    if (cosLight > 0) pdf += pmf[t] * *dist * *dist / (cosLight * area);
  }
  return pdf;
}

// The emissive triangle that a light sample's point (receiver + wi * distance) lies on, or -1.
int64_t sampledTriangle(const Scene& scene, Vec3 receiver, const LightSample& s) {
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    if (scene.triangleLight[t] < 0) continue;
    const auto dist =
        intersect(D3(receiver), D3(s.wi), D3(scene.vertex(t, 0)), D3(scene.vertex(t, 1)), D3(scene.vertex(t, 2)), 1e-5);
    if (dist && std::abs(*dist - s.distance) <= 1e-4 * s.distance) return t;
  }
  return -1;
}

// Checks of each sample beyond its direction and pdf, counted with the first failure described.
struct SampleChecks {
  uint64_t wrong = 0;
  std::string first;
  void fail(const std::string& what) {
    if (wrong++ == 0) first = what;
  }
};

bool relClose(double a, double b, double tol) { return std::abs(a - b) <= tol * std::max(std::abs(a), std::abs(b)); }

using test::TempDir;

}  // namespace

TEST_CASE("Triangle lights: sampled directions against an independent solid-angle density", "[lights][chi2]") {
  const chi2::Options binning{.thetaBins = 20, .phiBins = 40, .zMin = 0.2, .axis = {0, 1, 0}};
  for (bool overlap : {false, true}) {
    INFO((overlap ? "with" : "without") << " an emitter behind another");
    const Scene scene = triangleLightScene(overlap);
    const std::vector<double> pmf = trianglePmf(scene);
    for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
      if (pmf[t] == 0) {
        CHECK(scene.triangleLight[t] == -1);
      } else {
        REQUIRE(scene.triangleLight[t] >= 0);
        CHECK(scene.lightDistribution.pmf(uint32_t(scene.triangleLight[t])) == Approx(pmf[t]).epsilon(1e-5));
      }
    }
    // Only the emitter that turns its back on the receiver gives failures (pdf 0).
    const double backPmf = pmf[4];
    auto reference = [&](Vec3 d) { return float(referenceTrianglePdf(scene, pmf, kReceiver, d)); };

    SampleChecks checks;
    uint64_t seen[8] = {};
    auto sampler = [&](Rng& rng) {
      const float uLight = rng.uniform();
      const LightSample s = sampleLight(scene, kReceiver, uLight, rng.uniform2());
      if (!(s.pdf > 0)) return DirectionSample{{}, 0.0f};
      const int64_t t = sampledTriangle(scene, kReceiver, s);
      if (t < 0) {
        checks.fail("no emitter at the sample's distance along " + chi2::detail::str(s.wi));
        return DirectionSample{s.wi, s.pdf};
      }
      ++seen[t];
      const float pdfBack = triangleLightPdf(scene, uint32_t(t), s.wi, s.distance);
      if (s.delta || !relClose(s.pdf, pdfBack, 1e-4))
        checks.fail("pdf " + std::to_string(s.pdf) + " but triangleLightPdf " + std::to_string(pdfBack));
      if (!(s.radiance == scene.materials[scene.materialIds[t]].ke)) checks.fail("radiance is not Ke");
      if (!overlap) return DirectionSample{s.wi, s.pdf};
      // Where emitters overlap, the density of a direction is the sum over the emitters along it: the
      // claim is that sum, from triangleLightPdf at each emitter's own distance.
      float sum = 0;
      for (uint32_t u = 0; u < scene.triangleCount(); ++u)
        if (const auto dist = intersect(D3(kReceiver), D3(s.wi), D3(scene.vertex(u, 0)), D3(scene.vertex(u, 1)),
                                        D3(scene.vertex(u, 2)), u == t ? 1e-5 : 0.0))
          sum += triangleLightPdf(scene, u, s.wi, float(*dist));
      return DirectionSample{s.wi, sum};
    };
    chi2::Options opt = binning;
    opt.seed = overlap ? 2 : 1;
    opt.mass = 1 - backPmf;
    CHECK_CHI2_PASS(chi2::testSphere(sampler, reference, opt));
    INFO(checks.first);
    CHECK(checks.wrong == 0);
    CHECK(seen[4] == 0);
    if (overlap) CHECK(seen[5] > 0);
  }
}

TEST_CASE("Triangle lights: negative controls", "[lights][chi2]") {
  const chi2::Options opt{.thetaBins = 20, .phiBins = 40, .zMin = 0.2, .axis = {0, 1, 0}, .mass = std::nullopt};
  const Scene scene = triangleLightScene(false);
  const std::vector<double> pmf = trianglePmf(scene);
  auto reference = [&](Vec3 d) { return float(referenceTrianglePdf(scene, pmf, kReceiver, d)); };
  auto claimingReference = [&](const Scene& sampled) {
    return [&, sampledScene = &sampled](Rng& rng) {
      const float uLight = rng.uniform();
      const LightSample s = sampleLight(*sampledScene, kReceiver, uLight, rng.uniform2());
      return DirectionSample{s.wi, s.pdf > 0 ? reference(s.wi) : 0.0f};
    };
  };
  SECTION("lights chosen uniformly instead of by power") {
    Scene wrong = scene;
    wrong.lightDistribution = Distribution1D(std::vector<float>(wrong.lights.size(), 1.0f));
    CHECK_CHI2_REJECT(chi2::testSphere(claimingReference(wrong), reference, opt));
  }
  SECTION("the small emitter's Ke 10% brighter in the selection than in the reference") {
    Scene wrong = scene;
    for (Material& m : wrong.materials)
      if (m.ke == Rgb(30, 20, 10)) m.ke = Rgb(33, 22, 11);
    finalizeScene(wrong);
    CHECK_CHI2_REJECT(chi2::testSphere(claimingReference(wrong), reference, opt));
  }
  SECTION("points not uniform on the triangle: b1 = u1, b2 = (1 - u1) u2") {
    auto sampler = [&](Rng& rng) {
      const uint32_t li = scene.lightDistribution.sampleDiscrete(rng.uniform());
      const uint32_t t = scene.lights[li].triangle;
      const Vec2 u = rng.uniform2();
      const float b1 = u.x, b2 = (1 - u.x) * u.y;
      const Vec3 q = scene.vertex(t, 0) * (1 - b1 - b2) + scene.vertex(t, 1) * b1 + scene.vertex(t, 2) * b2;
      const Vec3 wi = normalize(q - kReceiver);
      return DirectionSample{wi, reference(wi)};
    };
    CHECK_CHI2_REJECT(chi2::testSphere(sampler, reference, opt));
  }
}

namespace {

// A strongly non-uniform lat-long map: a sky gradient varying with azimuth, a bright row at the +y pole
// (where the density has its 1/sin(theta) pole), a black row (no directions there) and a two-texel sun.
Image makeSkyMap(int w, int h) {
  return test::rgbImage(w, h, [&](int x, int y) {
    const float v = (y + 0.5f) / h, u = (x + 0.5f) / w;
    const float sky = (0.05f + 2 * std::pow(1 - v, 3.0f)) * (1 + 0.8f * std::sin(2 * kPi * u));
    if (y == 0) return Rgb(6, 3, 1);
    if (y == 10) return Rgb(0.0f);
    if (y == 3 && (x == 20 || x == 21)) return Rgb(500, 400, 300);
    return Rgb(sky, 0.8f * sky, 0.6f * sky);
  });
}

// Writes the map and a scene with it as environment (scale 0.5), a point light and one diffuse
// triangle, and loads it: the environment's sampling distribution is the loader's.
Scene loadSkyScene(const TempDir& dir, const Image& map) {
  writeExr(map, (dir.path / "sky.exr").string());
  std::ofstream(dir.path / "tri.obj") << "mtllib tri.mtl\nusemtl white\nv -1 0 -1\nv 1 0 -1\nv 0 0 1\nf 1 2 3\n";
  std::ofstream(dir.path / "tri.mtl") << "newmtl white\nKd 0.5 0.5 0.5\n";
  std::ofstream(dir.path / "scene.json") << R"({
    "camera": { "eye": [0, 5, 0], "look_at": [0, 0, 0.001], "up": [0, 0, 1], "fov_y": 40, "resolution": [8, 8] },
    "meshes": [ { "obj": "tri.obj" } ],
    "lights": [ { "type": "point", "position": [0, 3, 0], "power": [10, 10, 10] },
                { "type": "environment", "map": "sky.exr", "scale": 0.5 } ] })";
  return loadScene((dir.path / "scene.json").string(), {true});
}

// The environment's solid-angle density computed from its texels alone: texel weight
// luminance x sin(theta at the row's centre), spread uniformly over the texel in (u, v), whose
// Jacobian to solid angle is 2 pi^2 sin(theta); u = 0 at -z, 1/4 at +x; v = 0 at +y, row 0.
struct EnvironmentReference {
  const Environment& env;
  double pmf;  // the environment's selection probability
  std::vector<double> weights;
  double total = 0;

  EnvironmentReference(const Environment& e, double selection) : env(e), pmf(selection) {
    for (uint32_t y = 0; y < env.height; ++y)
      for (uint32_t x = 0; x < env.width; ++x) {
        weights.push_back(luminance(env.texels[y * env.width + x]) * std::sin(kPi * (y + 0.5) / env.height));
        total += weights.back();
      }
  }
  // The texel a direction falls in, and sin(theta).
  std::pair<uint32_t, double> texel(Vec3 direction) const {
    const D3 d = D3(direction) * (1 / length(D3(direction)));
    const double sinTheta = std::sqrt(d.x * d.x + d.z * d.z), twoPi = 2 * std::acos(-1.0);
    double phi = std::atan2(d.x, -d.z);
    if (phi < 0) phi += twoPi;
    const double theta = std::atan2(sinTheta, d.y);
    const auto x = std::min(uint32_t(phi / twoPi * env.width), env.width - 1);
    const auto y = std::min(uint32_t(theta / std::acos(-1.0) * env.height), env.height - 1);
    return {y * env.width + x, sinTheta};
  }
  double pdf(Vec3 direction) const {
    const auto [i, sinTheta] = texel(direction);
    if (!(sinTheta > 0)) return 0;
    return pmf * weights[i] / total * env.width * env.height / (2 * kPi * kPi * sinTheta);
  }
  // How far pdf may be off, relatively, where the sampler's probabilities are those of whole cells of
  // u's 2^-24 grid (Distribution1D): its row's and, within it, its texel's each by a cell at most.
  double cellTolerance(Vec3 direction) const {
    const uint32_t i = texel(direction).first, row = i / env.width;
    if (weights[i] == 0) return 0;  // then exactly 0
    double rowWeight = 0;
    for (uint32_t x = 0; x < env.width; ++x) rowWeight += weights[row * env.width + x];
    return 0x1p-24 * (total / rowWeight + rowWeight / weights[i]);
  }
};

}  // namespace

TEST_CASE("Environment map: sampled directions against the map's density", "[lights][chi2][environment]") {
  const TempDir dir("light-sampling-env");
  const Image map = makeSkyMap(32, 16);
  const Scene scene = loadSkyScene(dir, map);
  const Environment& env = scene.environment;
  REQUIRE(env.width == 32);
  REQUIRE(env.height == 16);
  for (uint32_t y = 0; y < 16; ++y)
    for (uint32_t x = 0; x < 32; ++x) REQUIRE(env.texels[y * 32 + x].g == 0.5f * map.at(int(x), int(y), 1));

  // Lights: the point light, then the environment, chosen by power: 4 pi I for the point light, and
  // pi^2 r^2 times the mean radiance for the environment, r the scene's bounding radius.
  REQUIRE(scene.lights.size() == 2);
  REQUIRE(scene.lights[1].type == LightType::Environment);
  double meanRadiance = 0;  // luminance, over the sphere, with each texel's exact solid angle
  for (uint32_t y = 0; y < 16; ++y)
    for (uint32_t x = 0; x < 32; ++x)
      meanRadiance += luminance(env.texels[y * 32 + x]) * (2 * kPi / 32) *
                      (std::cos(kPi * y / 16) - std::cos(kPi * (y + 1) / 16)) / (4 * kPi);
  const double r = 0.5 * std::sqrt(2 * 2 + 2 * 2), envPower = kPi * kPi * r * r * meanRadiance, pointPower = 10;
  const double pmfEnv = scene.lightDistribution.pmf(1);
  // The loader's mean takes sin(theta) at row centres: within (pi/16)^2 / 24 of the exact one.
  CHECK(pmfEnv == Approx(envPower / (envPower + pointPower)).epsilon(2e-3));
  INFO("environment chosen with probability " << pmfEnv);

  const EnvironmentReference reference(env, pmfEnv);
  SECTION("environmentLightPdf matches the reference, near the poles too") {
    Rng rng(5);
    std::vector<Vec3> directions;
    for (int i = 0; i < 100000; ++i) directions.push_back(sampleUniformSphere(rng.uniform2()));
    for (float theta = 1e-5f; theta < 0.1f; theta *= 1.1f)
      for (float phi : {0.3f, 2.0f, 4.4f})
        for (float pole : {1.0f, -1.0f})
          directions.push_back(
              {std::sin(theta) * std::cos(phi), pole * std::cos(theta), std::sin(theta) * std::sin(phi)});
    SampleChecks checks;
    for (Vec3 d : directions) {
      const double expected = reference.pdf(d), got = environmentLightPdf(scene, d);
      if (!relClose(got, expected, 1e-4 + reference.cellTolerance(d)))
        checks.fail("environmentLightPdf " + std::to_string(got) + " but " + std::to_string(expected) + " at " +
                    chi2::detail::str(d));
    }
    INFO(checks.first);
    CHECK(checks.wrong == 0);
  }

  SECTION("chi-square test of sampleLight's directions; point-light samples are failures") {
    SampleChecks checks;
    auto sampler = [&](Rng& rng) {
      const float uLight = rng.uniform();
      const LightSample s = sampleLight(scene, {0.2f, 0.1f, -0.3f}, uLight, rng.uniform2());
      if (s.delta) return DirectionSample{{}, 0.0f};
      if (s.distance != kInf) checks.fail("finite distance " + std::to_string(s.distance));
      const float pdf = environmentLightPdf(scene, s.wi);
      if (!relClose(s.pdf, pdf, 1e-4))
        checks.fail("pdf " + std::to_string(s.pdf) + " but environmentLightPdf " + std::to_string(pdf) + " at " +
                    chi2::detail::str(s.wi));
      if (!(s.radiance == env.texels[reference.texel(s.wi).first]))
        checks.fail("radiance not the texel's at " + chi2::detail::str(s.wi));
      return DirectionSample{s.wi, s.pdf};
    };
    const chi2::Options opt{.thetaBins = 16, .phiBins = 32, .axis = {0, 1, 0}, .mass = pmfEnv};
    CHECK_CHI2_PASS(chi2::testSphere(
        sampler, [&](Vec3 d) { return float(reference.pdf(d)); }, opt));
    INFO(checks.first);
    CHECK(checks.wrong == 0);
  }
}

TEST_CASE("Environment map: negative controls", "[lights][chi2][environment]") {
  const TempDir dir("light-sampling-env-controls");
  const Scene scene = loadSkyScene(dir, makeSkyMap(32, 16));
  const EnvironmentReference reference(scene.environment, scene.lightDistribution.pmf(1));
  auto pdf = [&](Vec3 d) { return float(reference.pdf(d)); };
  const chi2::Options opt{.thetaBins = 16, .phiBins = 32, .axis = {0, 1, 0}, .mass = std::nullopt};
  // `turn` maps the sampled direction; the claim is the reference density there.
  auto claimingReference = [&](const Scene& sampled, auto turn) {
    return [&, sampledScene = &sampled, turn](Rng& rng) {
      const float uLight = rng.uniform();
      const LightSample s = sampleLight(*sampledScene, {0, 0, 0}, uLight, rng.uniform2());
      if (s.delta || !(s.pdf > 0)) return DirectionSample{{}, 0.0f};
      const Vec3 d = turn(s.wi);
      return DirectionSample{d, pdf(d)};
    };
  };
  SECTION("texels weighted by luminance without sin(theta)") {
    Scene wrong = scene;
    Environment& env = wrong.environment;
    std::vector<float> weights;
    for (const Rgb& t : env.texels) weights.push_back(t.luminance());
    env.distribution = Distribution2D(weights, env.width, env.height);
    CHECK_CHI2_REJECT(chi2::testSphere(claimingReference(wrong, [](Vec3 d) { return d; }), pdf, opt));
  }
  SECTION("the map sampled half a turn away from where it is looked up (u = 0 at +z)") {
    auto halfTurn = [](Vec3 d) { return Vec3(-d.x, d.y, -d.z); };
    CHECK_CHI2_REJECT(chi2::testSphere(claimingReference(scene, halfTurn), pdf, opt));
  }
}

TEST_CASE("Constant environment: uniform over the sphere", "[lights][chi2][environment]") {
  // With an emissive triangle beside it, whose samples are failures here.
  Scene scene;
  addTriangle(scene, {-1, 0, -1}, {1, 0, -1}, {0, 0, 1}, test::addMaterial(scene, Material{}, "white"));
  addTriangleFacing(scene, {-1, 2, -1}, {1, 2, -1}, {0, 2, 1}, emitter(scene, Rgb(3.0f), "light"), {0, 0, 0}, true);
  scene.environment.present = true;
  scene.environment.radiance = {0.3f, 0.4f, 0.5f};
  finalizeScene(scene);
  REQUIRE(scene.lights.size() == 2);
  // Power: pi * area * luminance(Ke) for the triangle, pi^2 r^2 luminance(L) for the environment.
  const double r = 0.5 * std::sqrt(2 * 2 + 2 * 2 + 2 * 2);
  const double envPower = kPi * kPi * r * r * luminance(scene.environment.radiance), triPower = kPi * 2 * 3;
  const double pmfEnv = scene.lightDistribution.pmf(1);
  CHECK(pmfEnv == Approx(envPower / (envPower + triPower)).epsilon(1e-5));

  SampleChecks checks;
  auto sampler = [&](Rng& rng) {
    const float uLight = rng.uniform();
    const LightSample s = sampleLight(scene, {0, 1, 0}, uLight, rng.uniform2());
    if (s.distance != kInf) return DirectionSample{{}, 0.0f};
    if (s.delta || !(s.radiance == scene.environment.radiance) || s.pdf != environmentLightPdf(scene, s.wi))
      checks.fail("sample along " + chi2::detail::str(s.wi) + " with pdf " + std::to_string(s.pdf));
    return DirectionSample{s.wi, s.pdf};
  };
  auto pdf = [&](Vec3) { return float(pmfEnv / (4 * kPi)); };
  CHECK_CHI2_PASS(chi2::testSphere(sampler, pdf, {.seed = 3, .mass = pmfEnv}));
  INFO(checks.first);
  CHECK(checks.wrong == 0);
}

TEST_CASE("Point and directional lights: direction, distance and radiance", "[lights]") {
  const TempDir dir("light-sampling-delta");
  std::ofstream(dir.path / "tri.obj") << "v -1 0 -1\nv 1 0 -1\nv 0 0 1\nf 1 2 3\n";
  std::ofstream(dir.path / "scene.json") << R"({
    "camera": { "eye": [0, 5, 0], "look_at": [0, 0, 0.001], "up": [0, 0, 1], "fov_y": 40, "resolution": [8, 8] },
    "meshes": [ { "obj": "tri.obj" } ],
    "lights": [ { "type": "point", "position": [1, 2, 3], "power": [40, 20, 10] },
                { "type": "directional", "direction": [1, -2, 0.5], "irradiance": [2, 3, 4] } ] })";
  const Scene scene = loadScene((dir.path / "scene.json").string(), {true});
  REQUIRE(scene.lights.size() == 2);
  // An isotropic point light of power P has intensity P / (4 pi).
  const Rgb intensity = Rgb(40, 20, 10) / (4 * kPi);
  CHECK(scene.lights[0].value.r == Approx(intensity.r));
  CHECK(scene.lights[0].value.b == Approx(intensity.b));
  const D3 position(1, 2, 3), travel = D3(1, -2, 0.5) * (1 / std::sqrt(5.25));
  const double pmf[2] = {scene.lightDistribution.pmf(0), scene.lightDistribution.pmf(1)};
  Rng rng(8);
  for (Vec3 receiver : {Vec3(0.5f, -1, 2), Vec3(0, 0, 0), Vec3(-3, 1, 0.2f), Vec3(1, 2, 2.99f)}) {
    INFO("receiver " << chi2::detail::str(receiver));
    for (int k = 0; k < 20; ++k) {
      // uLight inside the point light's share of [0, 1), then inside the directional light's.
      const float share = rng.uniform();
      const LightSample p = sampleLight(scene, receiver, float(share * pmf[0]), rng.uniform2());
      const LightSample d = sampleLight(scene, receiver, float(pmf[0] + share * pmf[1]), rng.uniform2());
      const D3 toLight = position - D3(receiver);
      const double dist = length(toLight);
      CHECK(p.delta);
      CHECK(p.pdf == Approx(pmf[0]));
      CHECK(p.distance == Approx(dist).epsilon(1e-6));
      CHECK(length(D3(p.wi) - toLight * (1 / dist)) < 1e-6);
      for (int c = 0; c < 3; ++c) CHECK(p.radiance[c] == Approx(intensity[c] / (dist * dist)).epsilon(1e-5));
      CHECK(d.delta);
      CHECK(d.pdf == Approx(pmf[1]));
      CHECK(d.distance == kInf);
      CHECK(length(D3(d.wi) + travel) < 1e-6);
      CHECK(d.radiance == Rgb(2, 3, 4));
    }
  }
}

namespace {

// Every kind of light: the three emitters facing the receiver and the one turning its back from
// triangleLightScene, two point lights, a directional light, and a constant environment.
Scene mixedLightScene() {
  Scene scene = triangleLightScene(false);
  scene.lights.push_back({LightType::Point, 0, {0.5f, 1, 0.5f}, Rgb(2, 1, 1)});
  scene.lights.push_back({LightType::Point, 0, {-1, 2, 0}, Rgb(0.2f, 0.3f, 1)});
  scene.lights.push_back({LightType::Directional, 0, normalize(Vec3(0.3f, -1, 0.2f)), Rgb(1.5f)});
  scene.environment.present = true;
  scene.environment.radiance = {0.1f, 0.2f, 0.3f};
  finalizeScene(scene);
  return scene;
}

// The index of the light that a sample came from, told from what the sample is; lights.size() if
// none fits.
uint32_t sampledLight(const Scene& scene, Vec3 receiver, const LightSample& s) {
  const auto n = uint32_t(scene.lights.size());
  for (uint32_t i = 0; i < n; ++i) {
    const Light& l = scene.lights[i];
    const bool fits =
        (l.type == LightType::Point && s.delta && length(receiver + s.wi * s.distance - l.vector) < 1e-4f) ||
        (l.type == LightType::Directional && s.delta && s.distance == kInf && length(s.wi + l.vector) < 1e-6f) ||
        (l.type == LightType::Environment && !s.delta && s.distance == kInf);
    if (fits) return i;
  }
  if (s.delta || s.distance == kInf) return n;
  const int64_t t = sampledTriangle(scene, receiver, s);
  return t < 0 ? n : uint32_t(scene.triangleLight[t]);
}

}  // namespace

TEST_CASE("Light choice: each light as often as its share of the estimated power, point lights among themselves "
          "by power over squared distance", "[lights][chi2]") {
  const Scene scene = mixedLightScene();
  const auto n = uint32_t(scene.lights.size());
  REQUIRE(n == 8);
  // Power estimates: pi A luminance(Ke) per emitter, 4 pi luminance(I) per point light, pi r^2
  // luminance(E) for the directional light and pi^2 r^2 luminance(L) for the environment, with r the
  // bounding radius (the floor spans 6 x 6, the emitters reach up to y = 3).
  const double r = 0.5 * std::sqrt(6.0 * 6.0 + 4.0 * 4.0 + 6.0 * 6.0);
  std::vector<double> power;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    const double emission = luminance(scene.materials[scene.materialIds[t]].ke);
    const D3 p0(scene.vertex(t, 0)), p1(scene.vertex(t, 1)), p2(scene.vertex(t, 2));
    if (emission > 0) power.push_back(kPi * 0.5 * length(cross(p1 - p0, p2 - p0)) * emission);
  }
  power.push_back(4 * kPi * luminance({2, 1, 1}));
  power.push_back(4 * kPi * luminance({0.2f, 0.3f, 1}));
  power.push_back(kPi * r * r * 1.5);
  power.push_back(kPi * kPi * r * r * luminance({0.1f, 0.2f, 0.3f}));
  double total = 0;
  for (double p : power) total += p;
  for (uint32_t i = 0; i < n; ++i) CHECK(scene.lightDistribution.pmf(i) == Approx(power[i] / total).epsilon(1e-4));

  const Vec3 receiver{0, 0, 0};
  // The two point lights (4 and 5, at squared distances 1.5 and 5 from the receiver) keep their
  // share of the power; between them, power over squared distance decides.
  const double near4 = power[4] / 1.5, near5 = power[5] / 5.0, pointShare = (power[4] + power[5]) / total;
  REQUIRE(scene.nearbyLights == std::vector<uint32_t>{4, 5});
  auto pmf = [&](uint32_t i) {
    return float(i == 4 ? pointShare * near4 / (near4 + near5) : i == 5 ? pointShare * near5 / (near4 + near5) : power[i] / total);
  };
  auto sampler = [&](const Scene& sampled) {
    return [&, sampledScene = &sampled](Rng& rng) {
      const float uLight = rng.uniform();
      const LightSample s = sampleLight(*sampledScene, receiver, uLight, rng.uniform2());
      if (!(s.pdf > 0)) return IndexSample{0, 0.0f};
      const uint32_t i = sampledLight(scene, receiver, s);
      return IndexSample{i, i < n ? pmf(i) : 1.0f};
    };
  };
  // The emitter that turns its back on the receiver gives failures instead of samples.
  const uint32_t away = uint32_t(scene.triangleLight[4]);
  auto visiblePmf = [&](uint32_t i) { return i == away ? 0.0f : pmf(i); };
  SECTION("by power") {
    CHECK_CHI2_PASS(chi2::testDiscrete(sampler(scene), visiblePmf, n, {.seed = 4, .mass = 1 - pmf(away)}));
  }
  SECTION("negative control: the point lights by power alone") {
    Scene wrong = scene;
    wrong.nearbyLights.clear();
    CHECK_CHI2_REJECT(chi2::testDiscrete(sampler(wrong), visiblePmf, n, {.seed = 6, .mass = std::nullopt}));
  }
  SECTION("negative control: the first point light's weight 5% too high") {
    Scene wrong = scene;
    std::vector<float> weights;
    for (uint32_t i = 0; i < n; ++i) weights.push_back(float(power[i] * (i == 4 ? 1.05 : 1.0)));
    wrong.lightDistribution = Distribution1D(weights);
    CHECK_CHI2_REJECT(chi2::testDiscrete(sampler(wrong), visiblePmf, n, {.seed = 5, .mass = std::nullopt}));
  }
}

TEST_CASE("Light choice: a light's probability is its share of u's grid exactly, and no delta light goes unchosen",
          "[lights]") {
  // mixedLightScene with a third point light and a second directional light of 1e-12 the others'
  // power, each narrower than a cell of u's 2^-24 grid by power. Every u a sampler can draw,
  // k 2^-24, is chosen once: a light's count must be the pmf that chooseLight returns with it x 2^24,
  // the same for each of its u; the lights other than the nearby point lights keep the pmf that MIS
  // reads back (lightDistribution's); each delta light is chosen at least once.
  Scene scene = mixedLightScene();
  scene.lights.push_back({LightType::Point, 0, {40, 30, -20}, Rgb(1e-12f)});
  scene.lights.push_back({LightType::Directional, 0, normalize(Vec3(0, -1, 0.1f)), Rgb(1e-12f)});
  finalizeScene(scene);
  const auto n = uint32_t(scene.lights.size());
  REQUIRE(n == 10);
  REQUIRE(scene.nearbyLights == std::vector<uint32_t>{4, 5, 7});
  const Distribution1D& power = scene.lightDistribution;
  for (const Vec3 receiver : {Vec3(0, 0, 0), Vec3(39, 29, -19)}) {
    INFO("receiver " << chi2::detail::str(receiver));
    std::vector<uint64_t> count(n, 0);
    std::vector<float> pmf(n, -1.0f);
    uint64_t inconsistent = 0, outside = 0;
    for (uint32_t k = 0; k < Distribution1D::kCells; ++k) {
      float remapped = -1;
      const LightChoice c = chooseLight(scene, receiver, float(k) * 0x1p-24f, &remapped);
      if (pmf[c.light] < 0) pmf[c.light] = c.pmf;
      inconsistent += pmf[c.light] != c.pmf;
      outside += !(remapped >= 0 && remapped < 1);
      ++count[c.light];
    }
    CHECK(inconsistent == 0);
    CHECK(outside == 0);
    double nearbyWeight[3], nearbyTotal = 0;
    uint64_t nearbyCells = 0;
    for (int j = 0; j < 3; ++j) {
      const uint32_t i = scene.nearbyLights[size_t(j)];
      nearbyCells += power.cellCount(i);
      nearbyTotal += nearbyWeight[j] = power.pmf(i) / nearbyWeightDistance2(scene.lights[i], receiver);
    }
    for (uint32_t i = 0; i < n; ++i) {
      INFO("light " << i << ": chosen " << count[i] << " times, pmf " << pmf[i]);
      if (isDeltaLight(scene.lights[i])) CHECK(count[i] >= 1);
      if (count[i] == 0) continue;
      CHECK(double(count[i]) == double(pmf[i]) * 0x1p24);
      const auto near = std::find(scene.nearbyLights.begin(), scene.nearbyLights.end(), i);
      if (near == scene.nearbyLights.end()) {
        CHECK(pmf[i] == power.pmf(i));
      } else {  // the nearby lights' cells shared by power over squared distance, one at least each
        const double share = double(nearbyCells) * nearbyWeight[near - scene.nearbyLights.begin()] / nearbyTotal;
        CHECK(std::abs(double(count[i]) - share) <= 4);
      }
    }
  }
}

TEST_CASE("Spot lights: KHR_lights_punctual's falloff, its integral, and emission that carries it", "[lights]") {
  Light spot;
  spot.type = LightType::Spot;
  spot.vector = {1, 2, 3};
  spot.axis = normalize(Vec3{0.3f, -1, 0.2f});
  spot.value = Rgb(2.0f, 3.0f, 4.0f);
  const double inner = 0.3, outer = 0.7;
  spot.angleScale = float(1 / (std::cos(inner) - std::cos(outer)));
  spot.angleOffset = float(-std::cos(outer) * spot.angleScale);
  const Frame frame(spot.axis);
  // The falloff: 1 inside the inner cone, 0 outside the outer, the square of the linear ramp in the
  // cosine between (the extension's formula, written out).
  for (const double angle : {0.0, 0.29, 0.31, 0.5, 0.69, 0.71, 1.5, 3.0}) {
    const Vec3 d = frame.toWorld(test::directionAt(angle, 0.4));
    const double ramp = std::clamp((std::cos(angle) - std::cos(outer)) / (std::cos(inner) - std::cos(outer)), 0.0, 1.0);
    CHECK(spotFalloff(spot, d) == Approx(ramp * ramp).margin(2e-5));
  }
  // Its integral over the sphere, by the midpoint rule in the cosine.
  double integral = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double c = -1 + (i + 0.5) * 2.0 / n;
    const double a = std::clamp(c * spot.angleScale + spot.angleOffset, 0.0, 1.0);
    integral += a * a * 2 * kPi * 2.0 / n;
  }
  CHECK(spotSolidAngle(spot) == Approx(integral).epsilon(1e-4));
  // Emission from the spot alone carries its flux, I times that integral, and leaves within the
  // outer cone only.
  Scene scene;
  Material grey;
  test::addBox(scene, {-10, -10, -10}, {10, 10, 10}, test::addMaterial(scene, grey, "grey"), true);
  scene.lights.push_back(spot);
  finalizeScene(scene);
  Rng rng(8);
  double sum = 0, sum2 = 0;
  const int samples = 200000;
  for (int i = 0; i < samples; ++i) {
    const float uLight = rng.uniform();
    const Vec2 uPosition = rng.uniform2(), uDirection = rng.uniform2();
    const EmissionSample e = sampleEmission(scene, uLight, uPosition, uDirection, nullptr, 0);
    REQUIRE(dot(e.ray.direction, spot.axis) >= std::cos(outer) - 1e-5);
    sum += e.power.g, sum2 += double(e.power.g) * e.power.g;
  }
  const double mean = sum / samples, error = std::sqrt((sum2 / samples - mean * mean) / samples);
  CHECK(std::abs(mean - 3.0 * integral) <= 4.5 * error);
  // Seen from a receiver, its radiance is the intensity times the falloff over the squared distance.
  const Vec3 receiver = spot.vector + frame.toWorld(test::directionAt(0.5, 1.0)) * 4.0f;
  const LightSample ls = deltaLightSample(spot, receiver);
  const double ramp = (std::cos(0.5) - std::cos(outer)) / (std::cos(inner) - std::cos(outer));
  CHECK(ls.radiance.b == Approx(4.0 * ramp * ramp / 16.0).epsilon(1e-4));
  CHECK(ls.delta);
}
