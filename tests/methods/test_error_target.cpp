// The path tracer's error target (--target-error): its estimate of the image's relMSE is honest
// against converged references, its passes are planned as error_target.h says, and the image stays
// deterministic and unbiased.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "lucent/core/parallel.h"
#include "lucent/image/metrics.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "methods/pathtrace/error_target.h"
#include "test_support.h"

using namespace lucent;

namespace {

double measured(const RenderOutput& out, const std::string& name) {
  for (const auto& [key, value] : out.measured)
    if (key == name) return value;
  FAIL("no measured value " << name);
  return 0;
}

// A reference of references/ averaged over blocks of factor x factor pixels: the reference of the
// same camera at a resolution `factor` times lower (a pixel is the mean of the light over its
// area), R, G, B only; and its own expected relMSE against the converged image, from its pixels'
// variances (independent samples), which adds to any image's relMSE measured against it.
struct Reference {
  Image image;
  double relMse = 0;
};
Reference downsampledReference(const std::string& name, int factor) {
  const Image full = readImage(LUCENT_SOURCE_DIR "/references/" + name + ".exr");
  Reference ref;
  ref.image = Image(full.width() / factor, full.height() / factor, {"R", "G", "B"});
  double relMse = 0;
  for (int y = 0; y < ref.image.height(); ++y)
    for (int x = 0; x < ref.image.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const char* names[] = {"R", "G", "B"};
        const int value = full.channelIndex(names[c]), variance = full.channelIndex(std::string("variance.") + names[c]);
        double sum = 0, varianceSum = 0;
        for (int dy = 0; dy < factor; ++dy)
          for (int dx = 0; dx < factor; ++dx) {
            sum += full.at(x * factor + dx, y * factor + dy, value);
            varianceSum += full.at(x * factor + dx, y * factor + dy, variance);
          }
        const double n = double(factor * factor), mean = sum / n;
        ref.image.at(x, y, c) = float(mean);
        relMse += varianceSum / (n * n) / ((mean + 0.01) * (mean + 0.01));
      }
  ref.relMse = relMse / (3.0 * ref.image.width() * ref.image.height());
  return ref;
}

Scene sceneAt(const std::string& name, int width, int height) {
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/" + name + ".json", {true});
  scene.camera.width = width, scene.camera.height = height;
  return scene;
}

}  // namespace

TEST_CASE("Renders to an error target reach it, measured against converged references", "[error-target]") {
  // Each scene at a quarter of its reference's resolution, so that the reference (4 x 4 of its
  // pixels per pixel) holds 16 x 8,192 samples a pixel and its own error is far below the targets'
  // (checked). Diffuse, glossy and caustic light; targets from a draft to a reference.
  for (const char* name : {"cornell-box", "cornell-box-glossy", "ring"}) {
    const Reference ref = downsampledReference(name, 4);
    const Scene scene = sceneAt(name, ref.image.width(), ref.image.height());
    const Visibility vis(scene);
    CAPTURE(name, ref.relMse);
    REQUIRE(ref.relMse < 0.0003 / 16);
    for (const double target : {0.01, 0.001, 0.0003}) {
      PathTraceOptions o;
      o.targetError = target;
      o.common.spp = 1 << 20;
      o.common.seed = 11;
      const RenderOutput out = renderPathTraced(scene, vis, o);
      const double estimate = measured(out, "estimated_relmse");
      const double truth = compareImages(out.image, ref.image).overall.relmse - ref.relMse;
      CAPTURE(target, estimate, truth, measured(out, "samples_spent") / double(scene.camera.width * scene.camera.height));
      CHECK(estimate <= target);
      CHECK(truth >= 0.5 * target);
      CHECK(truth <= 1.5 * target);
    }
  }
}

TEST_CASE("A pass's samples go where the neighbourhood's error is, never by a pixel's own", "[error-target]") {
  const int w = 32, h = 16;
  std::vector<uint32_t> taken(w * h, 8);
  std::vector<float> error(w * h);
  // The right half's per-sample variance four times the left's; one pixel on the left very noisy.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) error[y * w + x] = x < w / 2 ? 0.01f : 0.04f;
  const int lone = 8 * w + 5;
  error[lone] = 100;
  const PassPlan plan = planNextPass(error, taken, w, h, 0.003, 1.0, 1 << 20, 1 << 20);
  uint64_t total = 0;
  double predicted = 0;
  for (int i = 0; i < w * h; ++i) {
    CHECK(plan.samples[i] >= taken[i]);
    CHECK(plan.samples[i] % 2 == 0);  // a pair at a time: one sample per stream
    total += plan.samples[i];
    predicted += error[i] * double(taken[i]) / plan.samples[i];
  }
  CHECK(plan.total == total);
  CHECK(plan.predictedRelMse == Approx(predicted / (w * h)).epsilon(1e-12));
  CHECK(plan.predictedRelMse <= 0.003 * 1.02);  // the aim, but for rounding to pairs
  CHECK(plan.predictedRelMse >= 0.003 * 0.9);
  // Far from the lone pixel and the halves' border, samples go as the square root of the variance.
  const double left = plan.samples[2 * w + 1], right = plan.samples[2 * w + w - 2];
  CHECK(right / left == Approx(2).epsilon(0.05));
  // The lone pixel does not raise its own count (it equals a pixel's out of its reach)...
  const int far = 8 * w + 10;
  CHECK(plan.samples[lone] == plan.samples[far]);
  // ...but its neighbours within 4 pixels get more than those farther off.
  CHECK(plan.samples[lone + 4] > 4 * plan.samples[lone]);
  CHECK(plan.samples[lone + w * 5] == plan.samples[far]);
}

TEST_CASE("A pass adds a tenth at least, stays within its limit and the per-pixel cap", "[error-target]") {
  const int w = 8, h = 8;
  std::vector<uint32_t> taken(w * h, 10);
  std::vector<float> error(w * h);
  for (int i = 0; i < w * h; ++i) error[i] = 0.001f * float(1 + i % 5);
  uint64_t takenTotal = 10 * w * h;
  // An aim already met: still a tenth more samples.
  const PassPlan small = planNextPass(error, taken, w, h, 1.0, 1.0, 1 << 20, 1 << 20);
  CHECK(small.total >= takenTotal + takenTotal / 10);
  CHECK(small.total <= takenTotal + takenTotal / 10 + 2 * w * h);
  // An aim far off: the limit, and no more.
  const PassPlan limited = planNextPass(error, taken, w, h, 1e-9, 1.0, 500, 1 << 20);
  CHECK(limited.total <= takenTotal + 500);
  CHECK(limited.total >= takenTotal + 500 - 2 * w * h);
  CHECK(limited.totalForAim > 1000 * takenTotal);
  // The per-pixel cap.
  const PassPlan capped = planNextPass(error, taken, w, h, 1e-9, 1.0, 1 << 20, 30);
  for (const uint32_t s : capped.samples) CHECK(s == 30);
  const PassPlan full = planNextPass(error, capped.samples, w, h, 1e-9, 1.0, 1 << 20, 30);
  CHECK(full.total == capped.total);  // nothing left to add: the render stops
  // No error anywhere: nothing to plan.
  const std::vector<float> none(w * h, 0.0f);
  CHECK(planNextPass(none, taken, w, h, 1e-9, 1.0, 1 << 20, 1 << 20).total == takenTotal);
}

TEST_CASE("The error's rate of fall is measured between passes and kept within 1 and 2", "[error-target]") {
  CHECK(errorRate(0.02, 100, 0.01, 200) == Approx(1));
  CHECK(errorRate(0.04, 100, 0.01, 200) == Approx(2));
  CHECK(errorRate(0.02, 100, 0.0141421356, 200) == Approx(1));   // slower than 1/n: 1
  CHECK(errorRate(0.08, 100, 0.01, 200) == Approx(2));           // faster than 1/n^2: 2
  CHECK(errorRate(0.03, 100, 0.01, 200) == Approx(std::log(3.0) / std::log(2.0)));
  CHECK(errorRate(0, 100, 0.01, 200) == 1);
  CHECK(errorRate(0.02, 100, 0.01, 100) == 1);
  // A pass planned with a rate: the prediction is its power of the samples' ratio.
  const std::vector<float> error(16, 0.01f);
  const std::vector<uint32_t> taken(16, 8);
  const PassPlan plan = planNextPass(error, taken, 4, 4, 0.0025, 2.0, 1 << 20, 1 << 20);
  for (const uint32_t s : plan.samples) CHECK(s == 16);  // (8/16)^2 = 1/4
}

TEST_CASE("Renders to an error target are bit-identical whatever the thread count and tile size", "[error-target][determinism]") {
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-glossy.json", {true});
  scene.camera.width = 40, scene.camera.height = 32;
  PathTraceOptions o;
  o.targetError = 0.01;
  o.common.spp = 4096;
  o.common.layers = true;
  o.paths = true;
  o.common.seed = 3;
  for (const SamplerKind sampler : {SamplerKind::Independent, SamplerKind::Sobol}) {
    o.sampler = sampler;
    std::vector<float> reference;
    std::vector<std::pair<std::string, double>> measuredReference;
    for (const auto& [threads, tile] : {std::pair{1, 16}, std::pair{2, 16}, std::pair{2, 7}}) {
      ParallelScope scope(threads);
      const Visibility vis(scene);
      o.tileSize = tile;
      const RenderOutput out = renderPathTraced(scene, vis, o);
      CHECK(measured(out, "passes") > 2);  // adaptive passes, not one
      if (reference.empty()) {
        reference = out.image.pixels(), measuredReference = out.measured;
      } else {
        INFO("sampler " << int(sampler) << ", " << threads << " threads, tile size " << tile);
        REQUIRE(out.image.pixels() == reference);
        REQUIRE(out.measured == measuredReference);
      }
    }
  }
}

TEST_CASE("A render to an error target takes contribution roulette's pilot from its first pass", "[error-target][roulette]") {
  // Its first pass (8 samples) is the pilot; from its second on, paths end by contribution
  // roulette: the same passes with throughput roulette give another image.
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  scene.camera.width = 32, scene.camera.height = 24;
  const Visibility vis(scene);
  PathTraceOptions o;
  o.targetError = 0.01;
  o.common.spp = 4096;
  const RenderOutput contribution = renderPathTraced(scene, vis, o);
  REQUIRE(measured(contribution, "passes") > 1);
  o.roulette = RouletteKind::Throughput;
  const RenderOutput throughput = renderPathTraced(scene, vis, o);
  CHECK(contribution.image.pixels() != throughput.image.pixels());
  // One pass only (the target met at once): the pilot's samples alone, the same with either roulette.
  o.targetError = 1;
  const Image firstPass = renderPathTraced(scene, vis, o).image;
  o.roulette = RouletteKind::Contribution;
  CHECK(renderPathTraced(scene, vis, o).image.pixels() == firstPass.pixels());
}

TEST_CASE("render --target-error records its estimate and samples, and its image is unbiased", "[error-target][cli]") {
  // Independent samples with their variance, so that lucent compare --test can judge the image
  // against the reference: samples spent where a pixel's neighbours are noisy must not bias it.
  const test::TempDir dir("error-target");
  const std::string exr = dir / "target.exr";
  const test::CliRun r = test::runLucent("render " LUCENT_SOURCE_DIR "/scenes/cornell-box.json --target-error 0.003 "
                                         "--spp 100000 --sampler independent --variance --seed 4 --resolution 128x128 "
                                         "--quiet -o " + test::quoted(exr));
  INFO(r.output);
  REQUIRE(r.status == 0);
  const nlohmann::json summary = nlohmann::json::parse(r.output);
  const double estimate = summary["estimated_relmse"], spent = summary["samples_spent"];
  CHECK(estimate <= 0.003);
  CHECK(estimate > 0.001);
  ImageMetadata meta;
  readImage(exr, &meta);
  auto header = [&](const std::string& key) {
    for (const auto& [k, v] : meta)
      if (k == key) return v;
    return std::string("absent");
  };
  CHECK(std::stod(header("lucent:estimated_relmse")) == Approx(estimate).epsilon(1e-12));
  CHECK(header("lucent:samples_spent") == std::to_string(uint64_t(spent)));
  // Adaptive: the fewest samples a pixel has (lucent:spp, the summary's spp) is below the mean; the
  // summary gives the least, mean and most beside it.
  CHECK(std::stod(header("lucent:spp")) < spent / (128 * 128) * 0.8);
  REQUIRE(summary.contains("spp_per_pixel"));
  CHECK(summary["spp_per_pixel"]["least"] == summary["spp"]);
  CHECK(summary["spp_per_pixel"]["mean"].get<double>() == Approx(spent / (128 * 128)).epsilon(1e-9));
  CHECK(summary["spp_per_pixel"]["most"].get<double>() > summary["spp_per_pixel"]["mean"].get<double>());
  test::checkAgreesWithinNoise(exr, LUCENT_SOURCE_DIR "/references/cornell-box.exr");
}

TEST_CASE("render --target-error without --spp is met: its pixels take up to 65536 samples", "[error-target][cli]") {
  // The declared default of 64 would stop this render short of its target (its pixels need up to
  // some 270 samples); --spp given stays the cap (the next test).
  const test::TempDir dir("error-target");
  const test::CliRun r = test::runLucent("render " LUCENT_SOURCE_DIR "/scenes/cornell-box.json --target-error 0.002 "
                                         "--resolution 64x64 --quiet -o " + test::quoted(dir / "met.exr"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(r.output.find("not reached") == std::string::npos);
  const nlohmann::json summary = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  CHECK(summary["options"]["spp"] == 65536);
  CHECK(summary["estimated_relmse"].get<double>() <= 0.002);
  CHECK(summary["spp_per_pixel"]["most"].get<int>() > 64);
}

TEST_CASE("render --target-error stops at --spp and at the time budget, saying the target was not reached",
          "[error-target][cli]") {
  const test::TempDir dir("error-target");
  const std::string scene = LUCENT_SOURCE_DIR "/scenes/cornell-box.json";
  {
    const test::CliRun r = test::runLucent("render " + scene + " --target-error 1e-6 --spp 24 --resolution 16x16 "
                                           "--quiet -o " + test::quoted(dir / "cap.exr"));
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK(r.output.find("lucent: warning: --target-error 1e-06 not reached") != std::string::npos);
    CHECK(r.output.find("the pixels that need more samples have --spp 24") != std::string::npos);
    const nlohmann::json summary = nlohmann::json::parse(r.output.substr(r.output.find('{')));
    CHECK(summary["samples_spent"] == 24 * 16 * 16);
    CHECK(summary["spp"] == 24);
    CHECK(summary["estimated_relmse"].get<double>() > 1e-6);
  }
  {
    const test::CliRun r = test::runLucent("render " + scene + " --target-error 1e-7 --spp 10000000 --time-budget 1 "
                                           "--resolution 32x32 --quiet -o " + test::quoted(dir / "budget.exr"));
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK(r.output.find("the time budget of 1 s ended the render") != std::string::npos);
    const nlohmann::json summary = nlohmann::json::parse(r.output.substr(r.output.find('{')));
    CHECK(summary["complete"] == true);
    CHECK(summary["stages"]["trace_paths"].get<double>() < 3);
  }
  // What it cannot be combined with, and impossible targets: refused before anything is written.
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"--target-error 0.01 --samples 0:8", "--target-error"},
           {"--target-error 0.01 --crop 0,0,8,8", "--target-error"},
           {"--target-error 0.01 --checkpoint 60", "--target-error"},
           {"--target-error 0.01 --spp 4", "at least 8 samples"},
           {"--target-error -1", "--target-error"},
           {"--target-error 2", "--target-error"},
           {"--target-error nan", "--target-error"},
           {"--method pmfg --target-error 0.01", "--target-error"}}) {
    const test::CliRun r = test::runLucent("render " + scene + " " + args + " --resolution 16x16 --quiet -o " +
                                           test::quoted(dir / "refused.exr"));
    INFO(args << ": " << r.output);
    CHECK(r.status == 1);
    CHECK(r.output.find(message) != std::string::npos);
    CHECK(!std::filesystem::exists(dir / "refused.exr"));
  }
}
