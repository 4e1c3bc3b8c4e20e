// Scene loading: every broken input in tests/data/bad gives one SceneError naming the file and the
// line or JSON key (in process and through `lucent render`, which must exit non-zero and write nothing);
// valid scenes load with the expected geometry, materials, lights and camera.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "lucent/core/stats.h"
#include "lucent/scene/loader.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace lucent;

namespace {

const std::string kSource = LUCENT_SOURCE_DIR;

// A broken scene, tests/data/bad/<dir>/scene.json, and what its error message must contain: first the
// file (with its folder, so that it is the right one) and its line, then the key or the problem.
struct BadCase {
  std::string dir;
  std::vector<std::string> expected;
};

const std::vector<BadCase> kBadCases = {
    // OBJ
    {"obj-truncated-line", {"obj-truncated-line/mesh.obj:8:", "'v' expects 3 numbers"}},
    {"obj-truncated-face", {"obj-truncated-face/mesh.obj:14:", "at least 3 vertices"}},
    {"obj-missing", {"obj-missing/scene.json", "meshes[0].obj", "nothere.obj", "not found"}},
    {"obj-directory", {"obj-directory/scene.json", "meshes[0].obj", "not a regular file"}},
    {"obj-symlink-loop", {"obj-symlink-loop/scene.json", "meshes[0].obj", "loop.obj", "symbolic links"}},
    {"obj-nan-vertex", {"obj-nan-vertex/mesh.obj:3:", "non-finite"}},
    {"obj-inf-vertex", {"obj-inf-vertex/mesh.obj:4:", "non-finite"}},
    {"obj-overflow-vertex", {"obj-overflow-vertex/mesh.obj:4:", "'1e39' is out of range"}},
    {"obj-face-out-of-range", {"obj-face-out-of-range/mesh.obj:14:", "vertex 9 but only 8"}},
    {"obj-face-empty-texcoord", {"obj-face-empty-texcoord/mesh.obj:12:", "malformed face vertex '1/'"}},
    {"obj-face-empty-normal", {"obj-face-empty-normal/mesh.obj:12:", "malformed face vertex '1//'"}},
    {"obj-texcoord-out-of-range", {"obj-texcoord-out-of-range/mesh.obj:14:", "texture coordinate 1 but only 0"}},
    {"obj-unknown-statement", {"obj-unknown-statement/mesh.obj:13:", "unsupported OBJ statement 'l'"}},
    {"obj-usemtl-undefined", {"obj-usemtl-undefined/mesh.obj:13:", "material 'lamp' is not defined"}},
    {"obj-only-degenerate", {"obj-only-degenerate/scene.json", "meshes", "no (non-degenerate) triangles"}},
    {"obj-huge-emitter", {"obj-huge-emitter/mesh.mtl:4:", "material 'light'", "overflows"}},
    // MTL
    {"mtl-missing", {"mtl-missing/mesh.obj:2:", "material library 'nothere.mtl' not found"}},
    {"mtl-unknown-key", {"mtl-unknown-key/mesh.mtl:3:", "unknown MTL key 'Pr'"}},
    {"mtl-key-before-newmtl", {"mtl-key-before-newmtl/mesh.mtl:1:", "before any 'newmtl'"}},
    {"mtl-two-numbers", {"mtl-two-numbers/mesh.mtl:2:", "'Kd' expects 3 numbers"}},
    {"mtl-duplicate-material", {"mtl-duplicate-material/mesh.mtl:7:", "'floor' is defined twice (first at line 1)"}},
    {"mtl-negative-ke", {"mtl-negative-ke/mesh.mtl:6:", "'Ke' must not be negative"}},
    {"mtl-missing-texture", {"mtl-missing-texture/mesh.mtl:3:", "texture 'wood.png' not found"}},
    {"mtl-texture-not-image", {"mtl-texture-not-image/mesh.mtl:3:", "material 'floor' map_Kd", "cannot read image"}},
    {"mtl-energy", {"mtl-energy/mesh.mtl:1:", "material 'floor'", "Kd + Ks exceeds 1"}},
    {"mtl-emission-overflow", {"mtl-emission-overflow/mesh.mtl:6:", "exceeds 1e15"}},
    // JSON syntax and structure
    {"json-malformed", {"json-malformed/scene.json", "invalid JSON", "line 3"}},
    {"json-duplicate-key", {"json-duplicate-key/scene.json: camera.fov_y: the key is given twice in one object"}},
    // A file that is not an OBJ: a short excerpt of its first line, escape bytes escaped.
    {"obj-not-an-obj", {"obj-not-an-obj/mesh.obj:1: unsupported OBJ statement '\\x1b]0;owned\\x07secret...'"}},
    {"json-number-overflow", {"json-number-overflow/scene.json", "invalid JSON", "the number 1e400 is beyond a double's range (at line 2, column 84)"}},
    {"json-not-object", {"json-not-object/scene.json", "top level: expected an object"}},
    {"json-unknown-key", {"json-unknown-key/scene.json", ": shadows: unknown key"}},
    {"json-wrong-type", {"json-wrong-type/scene.json", "camera.fov_y: expected a number"}},
    {"meshes-empty", {"meshes-empty/scene.json", "meshes: expected a non-empty array"}},
    // camera
    {"camera-unknown-key", {"camera-unknown-key/scene.json", "camera.aperture: unknown key"}},
    {"camera-zero-fov", {"camera-zero-fov/scene.json", "camera.fov_y:"}},
    {"camera-fov-180", {"camera-fov-180/scene.json", "camera.fov_y:"}},
    {"camera-zero-resolution", {"camera-zero-resolution/scene.json", "camera.resolution:"}},
    {"camera-up-parallel", {"camera-up-parallel/scene.json", "camera.up:", "parallel"}},
    {"camera-overflow", {"camera-overflow/scene.json", "camera.eye: must be finite"}},
    {"camera-huge-eye", {"camera-huge-eye/scene.json", "camera.eye: must be finite and at most 1e15"}},
    {"camera-huge-look-at", {"camera-huge-look-at/scene.json", "camera.look_at: must be finite and at most 1e15"}},
    {"camera-huge-resolution", {"camera-huge-resolution/scene.json", "camera.resolution: more than 2^26 pixels"}},
    // material overrides
    {"material-unknown-key", {"material-unknown-key/scene.json", "materials.floor.Kr: unknown key"}},
    {"material-negative-ke", {"material-negative-ke/scene.json", "materials.light.Ke: must not be negative"}},
    {"material-missing-texture", {"material-missing-texture/scene.json", "materials.floor.map_Kd:", "wood.png"}},
    {"material-energy", {"material-energy/scene.json", "materials.floor:", "Kd + Ks exceeds 1"}},
    {"material-unused", {"material-unused/scene.json", "materials.ceiling: no mesh uses"}},
    {"material-unknown-type", {"material-unknown-type/scene.json", "materials.floor.type:"}},
    {"material-double-sided-not-bool", {"material-double-sided-not-bool/scene.json", "materials.floor.double_sided: expected true or false"}},
    {"material-glass-without-ni", {"material-glass-without-ni/scene.json", "materials.floor", "glass needs an index"}},
    // lights
    {"no-light", {"no-light/scene.json", "no light"}},
    {"light-unknown-key", {"light-unknown-key/scene.json", "lights[0].color: unknown key"}},
    {"light-unknown-type", {"light-unknown-type/scene.json", "lights[0].type:"}},
    {"light-negative-power", {"light-negative-power/scene.json", "lights[0].power: must not be negative"}},
    {"light-huge-direction", {"light-huge-direction/scene.json", "lights[0].direction: must be finite and at most 1e15"}},
    {"env-map-missing", {"env-map-missing/scene.json", "lights[0].map:", "sky.exr", "not found"}},
    {"env-map-not-image", {"env-map-not-image/scene.json", "lights[0].map:", "cannot read image"}},
    {"env-map-negative", {"env-map-negative/scene.json", "lights[0].map:", "sky.exr", "negative texels, down to -1.000000, more than 1% of its texels' mean magnitude (1.000000)"}},
    // A Radiance header claiming 19,854,521 x 2 pixels, for which OpenImageIO would allocate 61 GB.
    {"env-map-huge-header", {"env-map-huge-header/scene.json", "lights[0].map:", "sky.hdr", "its header claims", "more than its 60 bytes can hold"}},
};

std::string badScene(const std::string& dir) { return kSource + "/tests/data/bad/" + dir + "/scene.json"; }
std::string goodScene(const std::string& dir) { return kSource + "/tests/data/good/" + dir + "/scene.json"; }

using test::quoted;
using test::TempDir;

using test::runLucent;

std::string renderArgs(const std::string& scene, const TempDir& out, const std::string& extra = "") {
  return "render " + quoted(scene) + " -o " + quoted(out / "out.exr") + " --png " + quoted(out / "out.png") +
         " --spp 1 --quiet " + extra;
}

uint32_t materialNamed(const Scene& scene, const std::string& name) {
  for (uint32_t i = 0; i < scene.materialNames.size(); ++i)
    if (scene.materialNames[i] == name) return i;
  FAIL("no material named " << name);
  return 0;
}

void checkRgb(Rgb actual, Rgb expected) {
  for (int c = 0; c < 3; ++c) CHECK(actual[c] == Approx(expected[c]).margin(1e-6));
}

}  // namespace

TEST_CASE("loader: every broken scene throws a SceneError naming the file and the line or key", "[loader]") {
  for (const BadCase& bad : kBadCases) {
    CAPTURE(bad.dir);
    REQUIRE(fs::exists(badScene(bad.dir)));
    std::string message;
    try {
      loadScene(badScene(bad.dir), {true});
    } catch (const SceneError& e) {
      message = e.what();
    }
    CAPTURE(message);
    REQUIRE(!message.empty());  // a SceneError, not another exception (which Catch reports) or none
    for (const auto& part : bad.expected) CHECK_THAT(message, Catch::Matchers::Contains(part));
  }
}

TEST_CASE("loader: lucent render rejects every broken scene: message, non-zero status, no files", "[loader][cli]") {
  for (const BadCase& bad : kBadCases) {
    CAPTURE(bad.dir);
    TempDir out;
    const test::CliRun run = runLucent(renderArgs(badScene(bad.dir), out));
    CAPTURE(run.output);
    CHECK(run.status == 1);
    CHECK_THAT(run.output, Catch::Matchers::Contains("lucent: error: "));
    CHECK_THAT(run.output, Catch::Matchers::Contains(bad.expected.front()));
    CHECK(out.entries().empty());
  }
}

TEST_CASE("loader: lucent render rejects impossible options before writing anything", "[loader][cli]") {
  const std::string scene = goodScene("base");
  SECTION("the valid base scene renders, leaving exactly the two images") {
    TempDir out;
    const test::CliRun run = runLucent(renderArgs(scene, out));
    CAPTURE(run.output);
    CHECK(run.status == 0);
    auto names = out.entries();
    std::sort(names.begin(), names.end());
    CHECK(names == std::vector<std::string>{"out.exr", "out.png"});
  }
  SECTION("impossible resolution, spp, method, seed or time budget") {
    for (const std::string extra : {"--resolution 10x0", "--resolution 10", "--spp 0", "--method nonsense", "--seed -1",
                                    "--time-budget nan"}) {
      CAPTURE(extra);
      TempDir out;
      const test::CliRun run = runLucent(renderArgs(scene, out, extra));
      CAPTURE(run.output);
      CHECK(run.status != 0);
      CHECK(!run.output.empty());
      CHECK(out.entries().empty());
    }
  }
  SECTION("an EXR output without .exr") {
    TempDir out;
    const test::CliRun run = runLucent("render " + quoted(scene) + " -o " + quoted(out / "out.png") + " --spp 1 --quiet");
    CAPTURE(run.output);
    CHECK(run.status != 0);
    CHECK_THAT(run.output, Catch::Matchers::Contains("must end in .exr"));
    CHECK(out.entries().empty());
  }
  SECTION("an output directory that does not exist") {
    TempDir out;
    const test::CliRun run = runLucent("render " + quoted(scene) + " -o " + quoted(out / "missing/out.exr") +
                           " --png " + quoted(out / "out.png") + " --spp 1 --quiet");
    CAPTURE(run.output);
    CHECK(run.status != 0);
    CHECK_THAT(run.output, Catch::Matchers::Contains("does not exist"));
    CHECK(out.entries().empty());
  }
}

TEST_CASE("loader: the Cornell box loads with its geometry, materials, lights and camera", "[loader]") {
  const Scene scene = loadScene(kSource + "/scenes/cornell-box.json", {true});
  // 18 quads in the OBJ (the front wall is commented out), two triangles each.
  CHECK(scene.triangleCount() == 36);
  CHECK(scene.droppedDegenerateTriangles == 0);

  const Material& white = scene.materials[materialNamed(scene, "white")];
  CHECK(white.type == MaterialType::Diffuse);
  checkRgb(white.kd, {0.725f, 0.71f, 0.68f});
  checkRgb(white.ke, Rgb(0.0f));
  checkRgb(scene.materials[materialNamed(scene, "red")].kd, {0.63f, 0.065f, 0.05f});
  checkRgb(scene.materials[materialNamed(scene, "green")].kd, {0.14f, 0.45f, 0.091f});
  const uint32_t lightId = materialNamed(scene, "light");
  const Material& light = scene.materials[lightId];
  CHECK(light.type == MaterialType::Diffuse);
  checkRgb(light.kd, Rgb(0.0f));
  checkRgb(light.ke, {17, 12, 4});

  REQUIRE(scene.lights.size() == 2);
  for (const Light& l : scene.lights) {
    CHECK(l.type == LightType::Triangle);
    CHECK(scene.materialIds[l.triangle] == lightId);
    CHECK(scene.geometricNormal(l.triangle).y == Approx(-1));  // emits down into the box
  }
  int emissive = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) emissive += scene.triangleLight[t] >= 0;
  CHECK(emissive == 2);

  const Camera& c = scene.camera;
  CHECK((c.eye.x == 278 && c.eye.y == 273 && c.eye.z == -800));
  CHECK((c.lookAt.x == 278 && c.lookAt.y == 273 && c.lookAt.z == 0));
  CHECK((c.up.x == 0 && c.up.y == 1 && c.up.z == 0));
  CHECK(c.fovY == Approx(39.3077f));
  CHECK((c.width == 512 && c.height == 512));
  CHECK(!scene.environment.present);
}

namespace {

// A scene of one OBJ face in the plane y = 0, lit from above, written to `dir`: the polygon's
// vertices (x, z), then `faceLine`.
std::string writePolygonScene(const TempDir& dir, const std::vector<Vec2>& polygon, const std::string& faceLine) {
  std::ofstream obj(dir / "mesh.obj");
  obj.precision(9);  // every float exactly
  for (const Vec2& p : polygon) obj << "v " << p.x << " 0 " << p.y << "\n";
  obj << faceLine << "\n";
  obj.close();
  std::ofstream json(dir / "scene.json");
  json << R"({"camera": {"eye": [0, 5, 0.1], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45, "resolution": [8, 8]},)"
       << R"("meshes": [{"obj": "mesh.obj"}], "lights": [{"type": "directional", "direction": [0, -1, 0], )"
       << R"("irradiance": [1, 1, 1]}]})";
  return dir / "scene.json";
}

std::string faceOf(size_t n, const std::string& suffix = "") {
  std::string f = "f";
  for (size_t k = 1; k <= n; ++k) {
    f += ' ';
    f += std::to_string(k);  // += rather than + dodges a GCC 12 -Wrestrict false positive
  }
  f += suffix;
  return f;
}

// The signed area of a simple polygon (shoelace formula), and of the triangles it was split into.
double polygonArea(const std::vector<Vec2>& p) {
  double a = 0;
  for (size_t k = 0; k < p.size(); ++k) {
    const Vec2 u = p[k], v = p[(k + 1) % p.size()];
    a += double(u.x) * v.y - double(v.x) * u.y;
  }
  return std::abs(a) / 2;
}
double totalArea(const Scene& scene) {
  double a = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) a += scene.triangleArea(t);
  return a;
}

}  // namespace

TEST_CASE("loader: faces with more than three vertices are split into triangles that cover them exactly", "[loader]") {
  TempDir dir;
  SECTION("a convex face of 64,000 vertices, in linear time") {
    std::vector<Vec2> circle;
    for (int k = 0; k < 64000; ++k) circle.push_back({float(std::cos(2 * M_PI * k / 64000)), float(std::sin(2 * M_PI * k / 64000))});
    const std::string path = writePolygonScene(dir, circle, faceOf(circle.size(), " # a trailing comment"));
    Stopwatch clock;
    const Scene scene = loadScene(path, {true});
    CHECK(clock.seconds() < 2.0);  // ear clipping took 25 s
    CHECK(scene.triangleCount() + scene.droppedDegenerateTriangles == 63998);
    CHECK(totalArea(scene) == Approx(polygonArea(circle)).epsilon(1e-4));
  }
  SECTION("non-convex faces by ear clipping, whichever way they wind") {
    // A comb: a base 0 < z < 1 and four teeth up to z = 3, so that a fan from any vertex would
    // leave the face.
    std::vector<Vec2> comb = {{0, 0}, {7, 0}, {7, 3}};
    for (int gap = 2; gap >= 0; --gap)
      comb.insert(comb.end(), {{2.0f * gap + 2, 3}, {2.0f * gap + 2, 1}, {2.0f * gap + 1, 1}, {2.0f * gap + 1, 3}});
    comb.push_back({0, 3});
    for (bool reversed : {false, true}) {
      CAPTURE(reversed);
      std::vector<Vec2> face = comb;
      if (reversed) std::reverse(face.begin(), face.end());
      const Scene scene = loadScene(writePolygonScene(dir, face, faceOf(face.size())), {true});
      CHECK(scene.triangleCount() + scene.droppedDegenerateTriangles == face.size() - 2);
      CHECK(totalArea(scene) == Approx(polygonArea(face)).epsilon(1e-6));
      // Every triangle lies inside the comb: its centroid is not in a gap between teeth.
      for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
        const Vec3 c = (scene.vertex(t, 0) + scene.vertex(t, 1) + scene.vertex(t, 2)) / 3.0f;
        const bool inGap = c.z > 1 && std::fmod(c.x, 2.0f) > 1;
        CHECK_FALSE(inGap);
      }
    }
  }
  SECTION("narrow notches and random simple faces, each covered exactly") {
    // A notch's tip turns back on itself: its corner's sine is as small as a straight corner's.
    std::vector<std::vector<Vec2>> faces;
    for (const float width : {1e-1f, 1e-3f, 1e-5f})
      for (const float depth : {0.5f, 3.0f, 3.999f}) {
        faces.push_back({{0, 0}, {4, 0}, {4, 4}, {2 + width, 4}, {2, 4 - depth}, {2 - width, 4}, {0, 4}});
        faces.push_back({{0, 0}, {0, 4}, {2 - width, 4}, {2, 4 - depth}, {2 + width, 4}, {4, 4}, {4, 0}});
      }
    // Star-shaped about the origin (every angular gap below pi), with spikes and near-centre dents.
    std::mt19937 random(7);
    std::uniform_real_distribution<float> uniform(0, 1);
    for (int f = 0; f < 200; ++f) {
      const int n = 5 + f % 30;
      std::vector<Vec2> face;
      for (int k = 0; k < n; ++k) {
        const float a = (float(k) + 0.9f * uniform(random)) * 2 * kPi / float(n);
        const float r = k % 3 == 0 ? 0.02f : 0.05f + uniform(random);
        face.push_back({r * std::cos(a), r * std::sin(a)});
      }
      faces.push_back(face);
    }
    for (size_t f = 0; f < faces.size(); ++f) {
      CAPTURE(f);
      const std::vector<Vec2>& face = faces[f];
      const Scene scene = loadScene(writePolygonScene(dir, face, faceOf(face.size())), {true});
      CHECK(scene.triangleCount() + scene.droppedDegenerateTriangles == face.size() - 2);
      CHECK(totalArea(scene) == Approx(polygonArea(face)).epsilon(1e-5));
    }
  }
  SECTION("a non-convex face too large to split quickly, and one that crosses itself, are refused") {
    std::vector<Vec2> star;
    for (int k = 0; k < 300; ++k) {
      const float r = k % 2 ? 1.0f : 0.5f, a = 2 * kPi * k / 300.0f;
      star.push_back({r * std::cos(a), r * std::sin(a)});
    }
    std::string message;
    try {
      loadScene(writePolygonScene(dir, star, faceOf(star.size())), {true});
    } catch (const SceneError& e) {
      message = e.what();
    }
    CHECK_THAT(message, Catch::Matchers::Contains("mesh.obj:301: a non-convex face with 300 vertices"));
    // Bow ties, of four and of five vertices.
    for (const std::vector<Vec2>& bowTie : {std::vector<Vec2>{{0, 0}, {2, 2}, {2, 0}, {0, 2}},
                                            std::vector<Vec2>{{0, 0}, {2, 2}, {2, 0}, {1, -1}, {0, 2}}}) {
      CAPTURE(bowTie.size());
      message.clear();
      try {
        loadScene(writePolygonScene(dir, bowTie, faceOf(bowTie.size())), {true});
      } catch (const SceneError& e) {
        message = e.what();
      }
      CHECK_THAT(message, Catch::Matchers::Contains("mesh.obj:" + std::to_string(bowTie.size() + 1) +
                                                    ": the face crosses itself"));
    }
  }
}

TEST_CASE("loader: zero-area triangles are dropped and counted", "[loader]") {
  const Scene base = loadScene(goodScene("base"), {true});
  CHECK(base.triangleCount() == 4);
  CHECK(base.droppedDegenerateTriangles == 0);
  const Scene scene = loadScene(goodScene("degenerate"), {true});
  CHECK(scene.triangleCount() == 4);
  CHECK(scene.droppedDegenerateTriangles == 1);
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) CHECK(scene.triangleArea(t) > 0);
}

TEST_CASE("loader: an environment map's slightly negative texels are clamped to 0 and counted", "[loader]") {
  // Poly Haven's courtyard (lossy DWAB compression): 1,188 texels with a channel below 0, down to
  // -0.0032 (envmaps/SOURCE.txt).
  const Scene scene = loadScene(kSource + "/scenes/primitives-courtyard.json", {true});
  CHECK(scene.environment.clampedTexels == 1188);
  CHECK(scene.environment.mostNegativeTexel == Approx(-0.0032).margin(1e-4));
  for (const Rgb& t : scene.environment.texels) REQUIRE((t.r >= 0 && t.g >= 0 && t.b >= 0));
  const test::TempDir dir("loader");
  const test::CliRun r = runLucent("render " + kSource + "/scenes/primitives-courtyard.json --method pt --spp 1 "
                                   "--resolution 8x8 -o " + test::quoted(dir / "x.exr"));
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("clamped 1188 slightly negative texels"));
}

TEST_CASE("loader: MTL entries are classified as in docs/scene-format.md, and scene overrides win", "[loader]") {
  const Scene scene = loadScene(goodScene("classify"), {true});
  const auto material = [&](const char* name) { return scene.materials[materialNamed(scene, name)]; };
  CHECK(material("glass").type == MaterialType::Glass);  // illum 7
  CHECK(material("glass").ni == 1.5f);
  CHECK(material("mirror").type == MaterialType::Mirror);  // illum 5
  checkRgb(material("mirror").ks, Rgb(0.9f));
  CHECK(material("shiny").type == MaterialType::Mirror);  // Ks only, Ns 1000
  const Material phong = material("phong");
  CHECK(phong.type == MaterialType::Phong);  // Kd + Ks
  checkRgb(phong.kd, Rgb(0.4f));
  checkRgb(phong.ks, Rgb(0.3f));
  CHECK(phong.ns == 20);
  CHECK(material("matte").type == MaterialType::Diffuse);  // Kd only
  checkRgb(material("matte").kd, {0.5f, 0.5f, 0.0f});      // 1e-50 underflows to zero
  CHECK(material("grey").type == MaterialType::Diffuse);
  checkRgb(material("grey").kd, Rgb(0.6f));  // one number is a grey
  CHECK(material("forced").type == MaterialType::Diffuse);  // Kd + Ks in the MTL, "type": "diffuse" in JSON
  checkRgb(material("forced").ks, Rgb(0.0f));
  checkRgb(material("overridden").kd, {0.2f, 0.3f, 0.4f});  // JSON Kd replaces the MTL's 0.5
  checkRgb(material("light").ke, Rgb(1.0f));
  CHECK(material("light").emitsBackFace == 1);  // "double_sided": true in JSON
  CHECK(material("matte").emitsBackFace == 0);  // not an emitter
  CHECK(scene.lights.size() == 1);
}

TEST_CASE("loader: the scenes shipped in scenes/ load", "[loader]") {
  for (const char* name : {"cornell-box-spheres.json", "cornell-box-glossy.json", "primitives.json",
                           "primitives-white.json", "primitives-glossy.json", "primitives-courtyard.json", "sponza-courtyard.json",
                           "sponza-white.json"}) {
    CAPTURE(name);
    const Scene scene = loadScene(kSource + "/scenes/" + name, {true});
    CHECK(scene.triangleCount() > 0);
    CHECK(!scene.lights.empty());
  }
  const Scene spheres = loadScene(kSource + "/scenes/cornell-box-spheres.json", {true});
  CHECK(spheres.materials[materialNamed(spheres, "leftSphere")].type == MaterialType::Mirror);
  CHECK(spheres.materials[materialNamed(spheres, "rightSphere")].type == MaterialType::Glass);
}

TEST_CASE("loader: Sponza loads with its textures", "[loader]") {
  const Scene scene = loadScene(kSource + "/scenes/sponza.json", {true});
  CHECK(scene.triangleCount() + scene.droppedDegenerateTriangles == 66454);
  CHECK(scene.environment.present);
  CHECK(scene.textures.size() > 0);
}
