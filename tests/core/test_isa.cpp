// Instruction sets: every method renders the same image whichever versions of the lane loops run
// (AVX-512, AVX2, baseline: bit for bit), and nearly the same whichever of Embree's kernels trace
// the rays, for every instruction set this CPU runs, so that an AVX-512 machine checks what an
// AVX2 or older one renders.
#include <catch2/catch.hpp>

#include <functional>

#include "lucent/core/lane_clones.h"
#include "lucent/image/metrics.h"
#include "lucent/methods/methods.h"
#include "lucent/scene/loader.h"
#include "test_support.h"

using namespace lucent;

namespace {

// Every method with a lane loop or not, with light settings, at 16 x 16: the spheres box (mirror,
// glass, diffuse walls), and for the environment-lighting method the primitives under a sky and sun.
struct IsaRender {
  std::string method;
  OptionValues values;
  const char* scene = "cornell-box-spheres";
};
const std::vector<IsaRender> kRenders = {
    {"pt", {{"spp", "12"}}},  // contribution roulette from the ninth sample
    {"purcell", {{"photons", "20000"}, {"caustic_photons", "20000"}, {"light_samples", "2"}, {"map", "sort"}}},
    {"purcell", {{"photons", "20000"}, {"caustic_photons", "20000"}, {"light_samples", "2"}, {"map", "stencil"}}},
    {"pmfg", {{"photons", "20000"}, {"caustic_photons", "20000"}, {"gather_rays", "8"}, {"light_samples", "2"}}},
    {"micro", {{"light_samples", "2"}, {"buffer_size", "8"}}},
    {"envpbgi", {{"points", "4096"}}, "primitives"},
};

Scene sceneOf(const IsaRender& render) {
  Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR "/scenes/") + render.scene + ".json", {true});
  scene.camera.width = scene.camera.height = 16;
  scene.contentHash = sceneContentHash(scene);
  return scene;
}

// Restores the lane loops this CPU picks at the end of the scope.
struct LaneIsaScope {
  LaneIsa saved = laneIsa();
  ~LaneIsaScope() { setLaneIsa(saved); }
};

}  // namespace

TEST_CASE("Every version of the lane loops renders every method's image bit for bit", "[isa]") {
  LaneIsaScope restore;
  REQUIRE(supportedLaneIsas().size() >= 2);  // x86-64 machines run the baseline and, nearly all, AVX2
  for (const auto& [method, values, sceneName] : kRenders) {
    const Scene scene = sceneOf({method, values, sceneName});
    const Visibility vis(scene);
    std::vector<float> reference;
    for (const LaneIsa isa : supportedLaneIsas()) {
      setLaneIsa(isa);
      CAPTURE(method, laneIsaName(isa));
      const Image image = renderingMethod(method).render(scene, vis, values).image;
      if (reference.empty()) reference = image.pixels();
      else CHECK(image.pixels() == reference);
    }
  }
}

TEST_CASE("Every instruction set's Embree kernels render every method's image alike", "[isa]") {
  // Embree's kernels round hit distances and barycentrics differently (its AVX2 and AVX-512
  // kernels contract into FMAs) and may give a ray through an edge to either triangle, robust mode
  // or not. A path that then decides differently (Russian roulette, a lobe) takes other random
  // numbers after: images agree to a thousandth of the noise between two seeds, not bit for bit.
  const std::vector<std::string> isas = supportedEmbreeIsas();
  REQUIRE(isas.size() >= 2);
  for (const bool robust : {false, true})
    for (auto [method, values, sceneName] : kRenders) {
      const Scene scene = sceneOf({method, values, sceneName});
      VisibilityOptions nativeOptions;
      nativeOptions.robust = robust;
      const Visibility native(scene, nativeOptions);
      const Image reference = renderingMethod(method).render(scene, native, values).image;
      values.emplace_back("seed", "1");
      const double noise = compareImages(renderingMethod(method).render(scene, native, values).image, reference).overall.relmse;
      values.pop_back();
      REQUIRE(noise > 0);
      for (const std::string& isa : isas) {
        CAPTURE(robust, method, isa, noise);
        const Visibility vis(scene, {.robust = robust, .isa = isa});
        CHECK(compareImages(renderingMethod(method).render(scene, vis, values).image, reference).overall.relmse <=
              1e-3 * noise);
      }
    }
}

TEST_CASE("lucent render --isa runs as an older CPU would, and refuses what this CPU lacks", "[isa][cli]") {
  const test::TempDir dir("isa");
  for (const std::string& isa : supportedEmbreeIsas()) {
    const test::CliRun r = test::runLucent("render " LUCENT_SOURCE_DIR "/scenes/cornell-box.json --spp 1 --resolution 8x8 --isa " +
                                           isa + " --quiet -o " + test::quoted(dir / "x.exr"));
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.output, Catch::Contains("\"embree_isa\":\"" + isa + "\""));
    CHECK_THAT(r.output, Catch::Contains(std::string("\"lane_isa\":\"") +
                                         (isa == "avx512" ? "avx512" : isa == "avx2" ? "avx2" : "baseline") + "\""));
  }
  const test::CliRun bad = test::runLucent("render " LUCENT_SOURCE_DIR "/scenes/cornell-box.json --isa neon --quiet -o " +
                                           test::quoted(dir / "y.exr"));
  CHECK(bad.status == 1);
  CHECK_THAT(bad.output, Catch::Contains("--isa 'neon'"));
}
