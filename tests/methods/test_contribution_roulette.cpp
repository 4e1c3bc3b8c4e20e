// Contribution roulette and the light choice learnt from its pilot
// (src/methods/pathtrace/contribution_roulette.h): the scales, the pilot's pixels, the choice's
// arithmetic, and that the path tracer's images with them are those of throughput roulette and of the
// choice by power, noise apart.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "methods/pathtrace/contribution_roulette.h"
#include "test_support.h"

using namespace lucent;

namespace {

// A scene of the repository at width x height pixels.
Scene sceneAt(const char* file, int width, int height) {
  Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + file, {true});
  scene.camera.width = width;
  scene.camera.height = height;
  return scene;
}

// The path tracer with independent samples (so that the images' pixels are independent for the
// agreement tests), spp of them.
PathTraceOptions independentSamples(int spp) {
  PathTraceOptions opt;
  opt.common.spp = spp;
  opt.sampler = SamplerKind::Independent;
  return opt;
}

}  // namespace

TEST_CASE("Roulette scales are K M / (I + 0.01), I over the pixel's 5 x 5 neighbourhood, M over the lattice",
          "[pathtrace][roulette]") {
  // Left half dark (0.01, with a dim blue), right half bright (1), 24 x 16 pixels.
  const Image pilot = test::rgbImage(24, 16, [](int x, int) { return x < 12 ? Rgb(0.01f, 0.01f, 0.002f) : Rgb(1.0f); });
  const RouletteScales scales(pilot, {0, 0, 24, 16});
  // The lattice (every fourth pixel of every fourth row) is half dark, half bright.
  const float mean = (3 * (0.01f + 0.01f + 0.002f) / 3 + 3 * 1.0f) / 6;
  auto at = [&](int x, int y) { return scales.at(uint64_t(y) * 24 + uint64_t(x)); };
  // Away from the edge between the halves, the neighbourhood is the pixel's value.
  CHECK(at(3, 8).r == Approx(2 * mean / (0.01f + 0.01f)).epsilon(1e-5));
  CHECK(at(3, 8).b == Approx(2 * mean / (0.002f + 0.01f)).epsilon(1e-5));
  CHECK(at(20, 8).g == Approx(2 * mean / (1.0f + 0.01f)).epsilon(1e-5));
  // Two pixels from the edge, the neighbourhood holds one bright column of five: (4 x 0.01 + 1) / 5.
  CHECK(at(10, 8).r == Approx(2 * mean / ((4 * 0.01f + 1.0f) / 5 + 0.01f)).epsilon(1e-5));
  // At the image's corner, the neighbourhood is the 3 x 3 pixels inside it.
  CHECK(at(0, 0).r == Approx(2 * mean / (0.01f + 0.01f)).epsilon(1e-5));

  // A crop's scales are the whole image's at the same pixels.
  const RouletteScales crop(pilot, {8, 3, 15, 9});
  for (int y = 3; y < 9; ++y)
    for (int x = 8; x < 15; ++x) {
      CAPTURE(x, y);
      CHECK(crop.at(uint64_t(y) * 24 + uint64_t(x)).g == at(x, y).g);
    }

  // A pixel filter's negative lobes can make pixel means negative: I counts as zero there, so that
  // every path keeps a chance to go on (a scale of zero or less would end them all: bias).
  const Image lobed = test::rgbImage(24, 16, [](int x, int) { return x < 12 ? Rgb(-0.05f, 0.01f, -0.002f) : Rgb(1.0f); });
  const RouletteScales lobes(lobed, {0, 0, 24, 16});
  const float lobedMean = (3 * (-0.05f + 0.01f - 0.002f) / 3 + 3 * 1.0f) / 6;
  const Rgb darkSide = lobes.at(8 * 24 + 3);
  CHECK(darkSide.r == Approx(2 * lobedMean / 0.01f).epsilon(1e-5));
  CHECK(darkSide.g == Approx(2 * lobedMean / (0.01f + 0.01f)).epsilon(1e-5));
  CHECK(darkSide.b == Approx(2 * lobedMean / 0.01f).epsilon(1e-5));

  // A pilot that met no light gives throughput roulette.
  const RouletteScales dark(test::rgbImage(8, 8, [](int, int) { return Rgb(0.0f); }), {0, 0, 8, 8});
  CHECK(dark.at(27).r == 1.0f);
  CHECK(dark.at(27).b == 1.0f);
}

TEST_CASE("The pilot's pixels: the region, two pixels around it, and the lattice", "[pathtrace][roulette]") {
  const std::vector<uint32_t> samples = pilotPixels(20, 12, {5, 4, 9, 6});
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 20; ++x) {
      CAPTURE(x, y);
      const bool wanted = (x >= 3 && x < 11 && y >= 2 && y < 8) || (x % 4 == 0 && y % 4 == 0);
      CHECK(samples[size_t(y) * 20 + size_t(x)] == (wanted ? kPilotSamples : 0u));
    }
}

TEST_CASE("Contribution roulette converges to throughput roulette's image", "[pathtrace][roulette]") {
  // Contribution roulette keeps dark pixels' paths longer and ends bright pixels' sooner: a
  // survivor scaled by another probability than its own survival's (throughput roulette's: z near
  // -17 on the Cornell box) would brighten or darken the image, most in the dark pixels, which are
  // also tested alone.
  for (const char* file : {"/scenes/cornell-box.json", "/scenes/cornell-box-glossy.json"}) {
    const Scene scene = sceneAt(file, 48, 48);
    const Visibility vis(scene);
    PathTraceOptions opt = independentSamples(256);
    opt.roulette = RouletteKind::Throughput;
    opt.common.seed = 1;
    const RenderOutput throughput = renderPathTraced(scene, vis, opt);
    opt.roulette = RouletteKind::Contribution;
    opt.common.seed = 2;
    const RenderOutput contribution = renderPathTraced(scene, vis, opt);
    // Not vacuous: contribution roulette traced paths of other lengths.
    CHECK(contribution.stats.counter("rays") != throughput.stats.counter("rays"));
    // The darkest third of the pixels, where paths go on longest, chosen by a third image: chosen by
    // one of the two, they would be those where its noise happened to be low.
    opt.common.spp = 64;
    opt.common.seed = 3;
    const Image chooser = renderPathTraced(scene, vis, opt).image;
    std::vector<float> values;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x) values.push_back(chooser.at(x, y, 0) + chooser.at(x, y, 1));
    std::vector<float> sorted = values;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 3, sorted.end());
    const float darkBelow = sorted[sorted.size() / 3];
    Image darkA(48, 48, {"R", "G", "B"}), darkB = darkA;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x)
        if (values[size_t(y) * 48 + size_t(x)] < darkBelow)
          for (int c = 0; c < 3; ++c) darkA.at(x, y, c) = throughput.image.at(x, y, c), darkB.at(x, y, c) = contribution.image.at(x, y, c);
    for (int c = 0; c < 3; ++c) {
      const double z = test::agreementZ(throughput.image, contribution.image, c);
      const double zDark = test::agreementZ(darkA, darkB, c);
      INFO(file << ", channel " << c << ": z = " << z << ", dark pixels' z = " << zDark);
      CHECK(std::abs(z) < 4.5);
      CHECK(std::abs(zDark) < 4.5);
    }
  }
}

TEST_CASE("The learnt light choice: groups by the root of their samples' second moments, a tenth by power",
          "[pathtrace][roulette]") {
  // The primitives under the sun and the sky: two groups, the sky's by power about a sixth.
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/primitives.json", {true});
  REQUIRE(scene.lights.size() == 2);
  REQUIRE(learnsLightChoice(scene));
  const uint32_t sun = scene.lights[0].type == LightType::Directional ? 0 : 1, sky = 1 - sun;
  const float sunPower = scene.lightDistribution.pmf(sun), skyPower = scene.lightDistribution.pmf(sky);
  LightMoments moments;
  for (int i = 0; i < 3; ++i) moments.add(LightType::Directional, Rgb(2.0f, 1.0f, 3.0f));  // c = 2, c^2 = 4
  moments.add(LightType::Environment, Rgb(0.5f));                                          // c^2 = 0.25
  const Distribution1D choice = learntLightChoice(scene, moments);
  const double sunLearnt = std::sqrt(sunPower * 12.0), skyLearnt = std::sqrt(skyPower * 0.25);
  CHECK(choice.pmf(sun) == Approx(0.9 * sunLearnt / (sunLearnt + skyLearnt) + 0.1 * sunPower).epsilon(1e-5));
  CHECK(choice.pmf(sky) == Approx(0.9 * skyLearnt / (sunLearnt + skyLearnt) + 0.1 * skyPower).epsilon(1e-5));
  // Moments gathered in two parts add up to the same choice, bit for bit.
  LightMoments first, second;
  for (int i = 0; i < 3; ++i) first.add(LightType::Directional, Rgb(2.0f, 1.0f, 3.0f));
  second.add(LightType::Environment, Rgb(0.5f));
  first.add(second);
  CHECK(learntLightChoice(scene, first).pmf(sky) == choice.pmf(sky));
  // No light brought anything: by power.
  CHECK(learntLightChoice(scene, LightMoments{}).pmf(sky) == skyPower);
  // The Cornell box has one kind of light: nothing to learn.
  CHECK_FALSE(learnsLightChoice(loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true})));
}

TEST_CASE("The learnt light choice converges to the image of the choice by power", "[pathtrace][roulette]") {
  // Sun and sky on the primitives, and sun and sky through Sponza's courtyard: a light chosen with
  // one probability and weighted by another (in next-event estimation, or in MIS at a BSDF-sampled
  // hit of the sky) would brighten or darken the image.
  for (const char* file : {"/scenes/primitives.json", "/scenes/sponza.json"}) {
    const Scene scene = sceneAt(file, 40, 24);
    const Visibility vis(scene);
    PathTraceOptions opt = independentSamples(128);
    opt.lightChoice = LightChoiceKind::Power;
    opt.common.seed = 1;
    const Image power = renderPathTraced(scene, vis, opt).image;
    opt.lightChoice = LightChoiceKind::Learned;
    opt.common.seed = 2;
    const Image learnt = renderPathTraced(scene, vis, opt).image;
    for (int c = 0; c < 3; ++c) {
      const double z = test::agreementZ(power, learnt, c);
      INFO(file << ", channel " << c << ": z = " << z);
      CHECK(std::abs(z) < 4.5);
    }
  }
}
