// The path tracer's light split by path (--paths): parts that add up to the image, bounces that
// match renders cut at that depth, and a diffuse/glossy split that is unbiased for each lobe.
#include <catch2/catch.hpp>

#include <cmath>
#include <nlohmann/json.hpp>

#include "lucent/image/metrics.h"
#include "lucent/image/noise_tests.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

namespace {

Scene glossyCornell(int size) {
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-glossy.json", {true});
  scene.camera.width = scene.camera.height = size;
  return scene;
}

float channel(const Image& image, const std::string& name, int x, int y) { return image.at(x, y, image.channelIndex(name)); }

// Layer a + layer b + ... at a pixel's channel c ("R", "G", "B").
double layerSum(const Image& image, std::initializer_list<const char*> layers, int x, int y, const char* c) {
  double sum = 0;
  for (const char* layer : layers) sum += channel(image, std::string("paths.") + layer + "." + c, x, y);
  return sum;
}

// A pixel left out of a noise test: no light, and a variance that makes any difference of zero
// count for nothing.
void neutral(Image& image, int x, int y) {
  for (const char* c : {"R", "G", "B"}) image.at(x, y, image.channelIndex(c)) = 0;
  for (const char* c : {"variance.R", "variance.G", "variance.B"}) image.at(x, y, image.channelIndex(c)) = 1e-20f;
}

}  // namespace

TEST_CASE("Light split by path: the parts add up to the image, which is the image without them", "[pathtrace][paths]") {
  const Scene scene = glossyCornell(40);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 16;
  opt.sampler = SamplerKind::Independent;
  opt.variance = true;
  const Image plain = renderPathTraced(scene, vis, opt).image;
  opt.paths = true;
  const Image split = renderPathTraced(scene, vis, opt).image;
  REQUIRE(split.channelIndex("paths.indirect.3+.glossy.variance.B") >= 0);
  for (const char* c : {"R", "G", "B", "variance.R", "variance.G", "variance.B"})
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) REQUIRE(channel(split, c, x, y) == channel(plain, c, x, y));
  double largest = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x)
      for (const char* c : {"R", "G", "B"}) {
        const double image = channel(split, c, x, y), tolerance = 1e-5 * image + 1e-7;
        largest = std::max(largest, image);
        CHECK(layerSum(split, {"emission", "direct", "indirect.1", "indirect.2", "indirect.3+"}, x, y, c) ==
              Approx(image).margin(tolerance));
        CHECK(layerSum(split, {"emission", "diffuse", "glossy"}, x, y, c) == Approx(image).margin(tolerance));
        for (const char* bounce : {"direct", "indirect.1", "indirect.2", "indirect.3+"}) {
          const std::string b = bounce;
          CHECK(layerSum(split, {bounce}, x, y, c) ==
                Approx(channel(split, "paths." + b + ".diffuse." + c, x, y) + channel(split, "paths." + b + ".glossy." + c, x, y))
                    .margin(tolerance));
        }
      }
  REQUIRE(largest > 1);  // the light is in view
}

TEST_CASE("Light split by path: emission and direct light are the image at depth 1, and the first bounce adds depth 2's",
          "[pathtrace][paths]") {
  const Scene scene = glossyCornell(40);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 8;
  opt.paths = true;
  const Image split = renderPathTraced(scene, vis, opt).image;
  opt.paths = false;
  opt.maxDepth = 1;
  const Image depth1 = renderPathTraced(scene, vis, opt).image;
  opt.maxDepth = 2;
  const Image depth2 = renderPathTraced(scene, vis, opt).image;
  double indirect = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x)
      for (const char* c : {"R", "G", "B"}) {
        const double d1 = channel(depth1, c, x, y), d2 = channel(depth2, c, x, y);
        CHECK(layerSum(split, {"emission", "direct"}, x, y, c) == Approx(d1).margin(1e-5 * d1 + 1e-7));
        CHECK(layerSum(split, {"emission", "direct", "indirect.1"}, x, y, c) == Approx(d2).margin(1e-5 * d2 + 1e-7));
        indirect += layerSum(split, {"indirect.1"}, x, y, c);
      }
  REQUIRE(indirect > 0);
}

TEST_CASE("Light split by path: the diffuse and glossy parts each equal the render with the other lobe removed",
          "[pathtrace][paths]") {
  // At depth 1 the diffuse part of direct light is what a scene without the glossy lobes (Ks = 0)
  // reflects, and the glossy part what one without the diffuse lobes (Kd = 0) reflects; the split
  // by the diffuse lobe's share of f is unbiased for each whichever lobe light or BSDF sampling took.
  const Scene scene = glossyCornell(32);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 256;
  opt.maxDepth = 1;
  opt.sampler = SamplerKind::Independent;
  opt.variance = true;
  opt.paths = true;
  opt.common.seed = 1;
  const Image split = renderPathTraced(scene, vis, opt).image;
  opt.paths = false;
  for (const bool glossy : {false, true}) {
    Scene without = scene;
    for (Material& m : without.materials)
      if (m.ke.isBlack()) (glossy ? m.kd : m.ks) = Rgb(0.0f);
    const Visibility withoutVis(without);
    opt.common.seed = glossy ? 3 : 2;
    Image reference = renderPathTraced(without, withoutVis, opt).image;
    Image part = *layerImage(split, glossy ? "direct.glossy" : "direct.diffuse");
    // The light's own pixels show its emission, a part of neither: left out.
    int emitters = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        if (layerSum(split, {"emission"}, x, y, "G") > 0) {
          ++emitters;
          for (Image* image : {&reference, &part})
            neutral(*image, x, y);
        }
    REQUIRE(emitters > 0);
    // Blocks whose light is below a millionth of the brightest block's hold only the far tails of
    // the glossy lobes, found by one sampling and missed by the other: variance estimates of such
    // rare events mean nothing, and their light nothing to the image. Left out alike.
    std::vector<double> blockLight(16, 0.0);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        for (int c = 0; c < 3; ++c) blockLight[size_t(y / 8 * 4 + x / 8)] += reference.at(x, y, c);
    const double brightest = *std::max_element(blockLight.begin(), blockLight.end());
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        if (blockLight[size_t(y / 8 * 4 + x / 8)] < 1e-6 * brightest)
          for (Image* image : {&reference, &part})
            neutral(*image, x, y);
    double total = 0;
    for (const float v : part.pixels()) total += v;
    REQUIRE(total > 0);
    const NoiseTest test = testWithinNoise(part, reference, 0.01);
    INFO((glossy ? "glossy" : "diffuse") << ": whole-image bias " << test.regions[0].relativeDifference << ", z "
                                         << test.regions[0].z);
    INFO("blocks rejected " << test.blocksRejected << " of " << test.blocks << ", least p " << test.minBlockPValue);
    CHECK(test.verdict == Verdict::Pass);
  }
}

TEST_CASE("lucent compare --layer compares a layer, or a layer with a whole image", "[pathtrace][paths][cli]") {
  test::TempDir dir;
  const std::string scene = test::quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box-glossy.json");
  const std::string common = " --method pt --resolution 24x24 --sampler independent --variance --paths --quiet -o ";
  REQUIRE(test::runLucent("render " + scene + " --spp 64" + common + test::quoted((dir.path / "ref.exr").string())).status == 0);
  REQUIRE(test::runLucent("render " + scene + " --spp 16 --seed 2" + common + test::quoted((dir.path / "img.exr").string())).status == 0);
  const std::string files = test::quoted((dir.path / "img.exr").string()) + " " + test::quoted((dir.path / "ref.exr").string());
  const test::CliRun run = test::runLucent("compare " + files + " --layer indirect.1 --test");
  REQUIRE(run.status <= 1);
  const nlohmann::json out = nlohmann::json::parse(run.output);
  CHECK(out["layer"]["image"] == "paths.indirect.1");
  CHECK(out["layer"]["reference"] == "paths.indirect.1");
  // The same layer saved as an image of its own (another renderer's one-bounce image) compares alike.
  const Image whole = readImage((dir.path / "img.exr").string());
  writeExr(*layerImage(whole, "indirect.1"), (dir.path / "alone.exr").string());
  const test::CliRun alone = test::runLucent("compare " + test::quoted((dir.path / "alone.exr").string()) + " " +
                                             test::quoted((dir.path / "ref.exr").string()) + " --layer indirect.1 --test");
  REQUIRE(alone.status <= 1);
  const nlohmann::json aloneOut = nlohmann::json::parse(alone.output);
  CHECK(aloneOut["layer"]["image"] == "");
  CHECK(aloneOut["overall"] == out["overall"]);
  CHECK(aloneOut["test"]["regions"] == out["test"]["regions"]);
  // Under a name of its own (--image-layer), as another renderer's layers are named.
  const Image layer = *layerImage(whole, "indirect.1");
  Image renamed(24, 24, {"R", "G", "B", "bounce.R", "bounce.G", "bounce.B"});
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x)
      for (int c = 0; c < 3; ++c) renamed.at(x, y, 3 + c) = layer.at(x, y, c), renamed.at(x, y, c) = 7;
  writeExr(renamed, (dir.path / "renamed.exr").string());
  const std::string renamedFiles =
      test::quoted((dir.path / "renamed.exr").string()) + " " + test::quoted((dir.path / "ref.exr").string());
  const test::CliRun named = test::runLucent("compare " + renamedFiles + " --layer indirect.1 --image-layer bounce");
  REQUIRE(named.status <= 1);
  CHECK(nlohmann::json::parse(named.output)["overall"] == out["overall"]);
  const test::CliRun unnamed = test::runLucent("compare " + renamedFiles + " --layer indirect.1 --image-layer other");
  CHECK(unnamed.status == 2);
  CHECK(unnamed.output.find("the image has no layer 'other' (its layers: bounce)") != std::string::npos);
  const test::CliRun missing = test::runLucent("compare " + files + " --layer indirect.9");
  CHECK(missing.status == 2);
  CHECK(missing.output.find("the reference has no layer 'indirect.9' (its layers: paths.diffuse, paths.direct,") !=
        std::string::npos);
}

TEST_CASE("Light split by path: a layer holding all the light has the image's values and variance",
          "[pathtrace][paths]") {
  // An emitting enclosure seen directly and through a mirror box: every contribution is emission
  // seen directly, so the emission layer sums the very terms the image sums.
  Scene scene;
  Material emitter, mirror;
  emitter.kd = Rgb(0.0f);
  emitter.ke = Rgb(1.0f, 2.0f, 3.0f);
  mirror.type = MaterialType::Mirror;
  mirror.ks = Rgb(0.6f);
  test::addBox(scene, {-5, -5, -5}, {5, 5, 5}, test::addMaterial(scene, emitter, "emitter"), true);
  test::addBox(scene, {-1, -1, -1}, {1, 1, 1}, test::addMaterial(scene, mirror, "mirror"), false);
  scene.camera = test::testCamera({0, 0.5f, 4}, {0, 0, 0}, 16, 16, 60);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 8;
  opt.sampler = SamplerKind::Independent;
  opt.variance = true;
  opt.paths = true;
  const Image image = renderPathTraced(scene, vis, opt).image;
  for (const char* c : {"R", "G", "B"})
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        REQUIRE(channel(image, std::string("paths.emission.") + c, x, y) == channel(image, c, x, y));
        REQUIRE(channel(image, std::string("paths.emission.variance.") + c, x, y) ==
                channel(image, std::string("variance.") + c, x, y));
        REQUIRE(channel(image, std::string("paths.direct.") + c, x, y) == 0);
      }
}
