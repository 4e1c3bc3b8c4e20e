// Scene loading: every broken input in tests/data/bad gives one SceneError naming the file and the
// line or JSON key (in process and through `lucent render`, which must exit non-zero and write nothing);
// valid scenes load with the expected geometry, materials, lights and camera.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

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
    {"obj-nan-vertex", {"obj-nan-vertex/mesh.obj:3:", "non-finite"}},
    {"obj-inf-vertex", {"obj-inf-vertex/mesh.obj:4:", "non-finite"}},
    {"obj-overflow-vertex", {"obj-overflow-vertex/mesh.obj:4:", "'1e39' is out of range"}},
    {"obj-face-out-of-range", {"obj-face-out-of-range/mesh.obj:14:", "vertex 9 but only 8"}},
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
    {"mtl-texture-not-image", {"mtl-texture-not-image/mesh.mtl:1:", "material 'floor'", "cannot read image"}},
    {"mtl-energy", {"mtl-energy/mesh.mtl:1:", "material 'floor'", "Kd + Ks exceeds 1"}},
    {"mtl-emission-overflow", {"mtl-emission-overflow/mesh.mtl:6:", "exceeds 1e15"}},
    // JSON syntax and structure
    {"json-malformed", {"json-malformed/scene.json", "invalid JSON", "line 3"}},
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
    {"material-glass-without-ni", {"material-glass-without-ni/scene.json", "materials.floor", "glass needs an index"}},
    // lights
    {"no-light", {"no-light/scene.json", "no light"}},
    {"light-unknown-key", {"light-unknown-key/scene.json", "lights[0].color: unknown key"}},
    {"light-unknown-type", {"light-unknown-type/scene.json", "lights[0].type:"}},
    {"light-negative-power", {"light-negative-power/scene.json", "lights[0].power: must not be negative"}},
    {"light-huge-direction", {"light-huge-direction/scene.json", "lights[0].direction: must be finite and at most 1e15"}},
    {"env-map-missing", {"env-map-missing/scene.json", "lights[0].map:", "sky.exr", "not found"}},
    {"env-map-not-image", {"env-map-not-image/scene.json", "lights[0].map:", "cannot read image"}},
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

TEST_CASE("loader: zero-area triangles are dropped and counted", "[loader]") {
  const Scene base = loadScene(goodScene("base"), {true});
  CHECK(base.triangleCount() == 4);
  CHECK(base.droppedDegenerateTriangles == 0);
  const Scene scene = loadScene(goodScene("degenerate"), {true});
  CHECK(scene.triangleCount() == 4);
  CHECK(scene.droppedDegenerateTriangles == 1);
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) CHECK(scene.triangleArea(t) > 0);
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
  checkRgb(material("grey").kd, Rgb(0.6f));  // one number is grey (tinyobjloader alone reads 0.6 0 0)
  CHECK(material("forced").type == MaterialType::Diffuse);  // Kd + Ks in the MTL, "type": "diffuse" in JSON
  checkRgb(material("forced").ks, Rgb(0.0f));
  checkRgb(material("overridden").kd, {0.2f, 0.3f, 0.4f});  // JSON Kd replaces the MTL's 0.5
  checkRgb(material("light").ke, Rgb(1.0f));
  CHECK(scene.lights.size() == 1);
}

TEST_CASE("loader: the scenes shipped in scenes/ load", "[loader]") {
  for (const char* name : {"cornell-box-spheres.json", "cornell-box-glossy.json"}) {
    CAPTURE(name);
    const Scene scene = loadScene(kSource + "/scenes/" + name, {true});
    CHECK(scene.triangleCount() > 0);
    CHECK(!scene.lights.empty());
  }
  const Scene spheres = loadScene(kSource + "/scenes/cornell-box-spheres.json", {true});
  CHECK(spheres.materials[materialNamed(spheres, "leftSphere")].type == MaterialType::Mirror);
  CHECK(spheres.materials[materialNamed(spheres, "rightSphere")].type == MaterialType::Glass);
}

TEST_CASE("loader: Sponza loads when the shared scene is present", "[loader]") {
  if (!fs::exists(kSource + "/../shared/scenes/sponza-dabrovic/sponza.obj")) {
    WARN("skipped: ../shared/scenes/sponza-dabrovic/sponza.obj not found next to the repository");
    return;
  }
  const Scene scene = loadScene(kSource + "/scenes/sponza.json", {true});
  CHECK(scene.triangleCount() + scene.droppedDegenerateTriangles == 66454);
  CHECK(scene.environment.present);
  CHECK(scene.textures.size() > 0);
}
