// Calibration of compare's verdicts on simulated renders whose truth is known: the false rejections
// of --test and false failures of --within under no difference stay at most 1.5 alpha, runs find a
// 2% bias in one region of sixteen, and a bias beyond the margin is not passed. Three noise models,
// written here: pixels independent (Lucent's own renders); noise shared between neighbours (a
// tent pixel filter whose samples land in three pixels a side) plus a per-run offset of the whole
// image (a renderer's random sequence shared by every pixel); and heavy tails (each pixel the mean
// of 4 Pareto samples of shape 2.5: finite variance, rare large values, like fireflies). Trials run
// in parallel, each from its own seed, so the counts do not depend on the threads.
// The tables are printed (docs/validation.md records them).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <tbb/parallel_for.h>
#include <string>
#include <vector>

#include "lucent/image/noise_tests.h"

using namespace lucent;

namespace {

// SplitMix64 (Steele, Lea and Flood 2014): fast and good enough to simulate noise.
struct Random {
  using result_type = uint64_t;
  uint64_t state;
  static constexpr uint64_t min() { return 0; }
  static constexpr uint64_t max() { return ~uint64_t(0); }
  uint64_t operator()() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
};

enum class Model { Independent, Correlated, HeavyTailed };
const char* modelName(Model m) {
  return m == Model::Independent ? "independent" : m == Model::Correlated ? "correlated" : "heavy-tailed";
}

constexpr int kSide = 64;  // 64 blocks of 8 x 8, 16 regions of 16 x 16
constexpr int kBiasedTile = 6;  // the region (1-based, row by row) that a bias is put into

double trueMean(int x, int y, int c) { return 0.6 + 0.3 * std::sin(0.15 * (x + 2 * y)) + 0.1 * c; }

bool inBiasedTile(int x, int y) {
  const int tile = 1 + (y * 4 / kSide) * 4 + (x * 4 / kSide);
  return tile == kBiasedTile;
}

// One run of a renderer: the true mean (times 1 + bias in the biased tile, or everywhere with
// `whole`) plus noise of the model. Per-pixel relative noise about 10%.
Image simulatedRun(Model model, double bias, bool whole, Random& rng, bool offset = true) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Image run(kSide, kSide, {"R", "G", "B"});
  std::vector<double> field(size_t(kSide + 2) * size_t(kSide + 2));
  if (model == Model::Correlated)
    for (double& e : field) e = normal(rng);
  const double shift = model == Model::Correlated ? 0.01 * normal(rng) : 0.0;
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const double shared = [&] {
        if (model != Model::Correlated) return 0.0;
        // A separable tent of radius 1 pixel over a field of white noise, shared by the channels.
        double s = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            s += (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25) * field[size_t(y + 1 + dy) * size_t(kSide + 2) + size_t(x + 1 + dx)];
        return s;
      }();
      for (int c = 0; c < 3; ++c) {
        const double mean = trueMean(x, y, c) * (1 + ((whole || inBiasedTile(x, y)) ? bias : 0.0));
        double value = 0;
        switch (model) {
          case Model::Independent: value = mean * (1 + 0.1 * normal(rng)); break;
          case Model::Correlated: value = mean * (1 + 0.16 * shared + 0.05 * normal(rng) + (offset ? shift : 0.0)); break;
          case Model::HeavyTailed: {
            // Pareto of shape 2.5 scaled to mean 1: standard deviation 0.89, so the mean of 4 has 45%.
            constexpr double shape = 2.5, scale = (shape - 1) / shape;
            double sum = 0;
            for (int k = 0; k < 4; ++k) sum += scale * std::exp(-std::log(1 - uniform(rng)) / shape);
            value = mean * sum / 4;
            break;
          }
        }
        run.at(x, y, c) = float(value);
      }
    }
  return run;
}

// One image with variance layers, as a renderer writes it: the independent model as the mean of 16
// samples and the heavy-tailed one of 4, each with its samples' variance over n (their spread,
// which is large where a large sample is); the correlated model with each pixel's exact variance
// (0.16^2 x 0.140625, its tent's weights squared, + 0.05^2) and without its per-run offset (a
// renderer that splats samples but draws its own random numbers per pixel).
Image simulatedImageWithLayers(Model model, double bias, Random& rng) {
  const Image run = simulatedRun(model, bias, false, rng, false);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Image image(kSide, kSide, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x)
      for (int c = 0; c < 3; ++c) {
        const double mean = trueMean(x, y, c) * (1 + (inBiasedTile(x, y) ? bias : 0.0));
        if (model == Model::Correlated) {
          const double relative = 0.0256 * 0.140625 + 0.0025;
          image.at(x, y, c) = run.at(x, y, c), image.at(x, y, 3 + c) = float(relative * mean * mean);
          continue;
        }
        // The mean of n samples and their variance over n: 16 Gaussian samples of 40% (the mean's
        // 10%), or 4 Pareto samples of shape 2.5.
        constexpr double shape = 2.5, scale = (shape - 1) / shape;
        const int n = model == Model::Independent ? 16 : 4;
        double samples[16], sum = 0, squares = 0;
        for (int k = 0; k < n; ++k)
          sum += samples[k] = model == Model::Independent ? mean * (1 + 0.4 * normal(rng))
                                                          : mean * scale * std::exp(-std::log(1 - uniform(rng)) / shape);
        for (int k = 0; k < n; ++k) squares += (samples[k] - sum / n) * (samples[k] - sum / n);
        image.at(x, y, c) = float(sum / n), image.at(x, y, 3 + c) = float(squares / (n - 1) / n);
      }
  return image;
}

// A reference of 64 times the samples, with its exact variance layer (pixels independent).
Image simulatedReference(Random& rng, int side = kSide) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Image reference(side, side, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      for (int c = 0; c < 3; ++c) {
        const double sd = 0.1 / 8 * trueMean(x, y, c);
        reference.at(x, y, c) = float(trueMean(x, y, c) + sd * normal(rng));
        reference.at(x, y, 3 + c) = float(sd * sd);
      }
  return reference;
}

struct Rates {
  int trials = 0, testFailed = 0, withinFailed = 0, withinPassed = 0;
};

Rates simulate(Model model, int runs, double bias, bool whole, double alpha, double within, int trials, uint64_t seed,
               bool noiseTest = true) {
  std::vector<Verdict> tests(static_cast<size_t>(trials), Verdict::Pass), equivalences = tests;
  tbb::parallel_for(0, trials, [&](int t) {
    Random rng{seed * 100003 + uint64_t(t)};
    const Image reference = simulatedReference(rng);
    std::vector<Image> images;
    for (int i = 0; i < runs; ++i) images.push_back(simulatedRun(model, bias, whole, rng));
    const Candidate candidate(std::move(images));
    if (noiseTest) tests[size_t(t)] = testWithinNoise(candidate, reference, alpha).verdict;
    equivalences[size_t(t)] = testEquivalence(candidate, reference, within, alpha).verdict;
  });
  Rates rates;
  rates.trials = trials;
  for (int t = 0; t < trials; ++t) {
    rates.testFailed += tests[size_t(t)] == Verdict::Fail;
    rates.withinFailed += equivalences[size_t(t)] == Verdict::Fail;
    rates.withinPassed += equivalences[size_t(t)] == Verdict::Pass;
  }
  return rates;
}

}  // namespace

TEST_CASE("Runs: false rejections at most 1.5 alpha for 2, 4 and 8 runs of three noise models", "[compare][calibration]") {
  constexpr double alpha = 0.05, within = 0.05;
  constexpr int trials = 200;
  std::printf("noise model     runs  --test false rejections  --within 0.05 false failures  --within passes\n");
  for (Model model : {Model::Independent, Model::Correlated, Model::HeavyTailed})
    for (int runs : {2, 4, 8}) {
      const Rates r = simulate(model, runs, 0.0, false, alpha, within, trials, 1000 + uint64_t(runs) + 10 * uint64_t(model));
      std::printf("%-14s %5d  %23d  %28d  %15d   (of %d)\n", modelName(model), runs, r.testFailed, r.withinFailed,
                  r.withinPassed, r.trials);
      INFO(modelName(model) << ", " << runs << " runs: --test failed " << r.testFailed << ", --within failed "
                            << r.withinFailed << " of " << trials);
      CHECK(r.testFailed <= 1.5 * alpha * trials);
      CHECK(r.withinFailed <= 1.5 * alpha * trials);
    }
}

TEST_CASE("Runs: a bias at the margin itself fails --within at most 1.5 alpha", "[compare][calibration]") {
  // A failure needs one interval of the 3 x 17 wholly beyond the margin. Each at level alpha, a
  // bias of exactly D (not beyond it) failed 160 to 178 times in 200 with runs of independent noise,
  // 71 to 135 with the other two models.
  constexpr double alpha = 0.05, within = 0.05;
  constexpr int trials = 200;
  std::printf("noise model     runs  5%% over the image: --within 0.05 fails\n");
  for (Model model : {Model::Independent, Model::Correlated, Model::HeavyTailed})
    for (int runs : {2, 4, 8}) {
      const Rates r = simulate(model, runs, within, true, alpha, within, trials, 13000 + uint64_t(runs) + 10 * uint64_t(model),
                               false);
      std::printf("%-14s %5d  %38d   (of %d)\n", modelName(model), runs, r.withinFailed, r.trials);
      INFO(modelName(model) << ", " << runs << " runs: --within failed " << r.withinFailed << " of " << trials);
      CHECK(r.withinFailed <= 1.5 * alpha * trials);
    }
}

TEST_CASE("Runs: a 2% bias in one region of sixteen is found, a bias beyond the margin is not passed", "[compare][calibration]") {
  constexpr double alpha = 0.01;
  constexpr int trials = 200;
  std::printf("noise model     runs  2%% bias in one region: --test fails   6%% over the image: --within 0.05 passes\n");
  for (Model model : {Model::Independent, Model::Correlated, Model::HeavyTailed})
    for (int runs : {2, 4, 8}) {
      const Rates local = simulate(model, runs, 0.02, false, alpha, 0.05, trials, 5000 + uint64_t(runs) + 10 * uint64_t(model));
      const Rates beyond = simulate(model, runs, 0.06, true, alpha, 0.05, trials, 9000 + uint64_t(runs) + 10 * uint64_t(model));
      std::printf("%-14s %5d  %38d  %38d   (of %d)\n", modelName(model), runs, local.testFailed, beyond.withinPassed, trials);
      INFO(modelName(model) << ", " << runs << " runs: the 2% bias found " << local.testFailed << " times; 6% passed "
                            << beyond.withinPassed << " times, of " << trials);
      // Size: a bias beyond the margin passes at most alpha of the time (with slack for 200 trials).
      CHECK(beyond.withinPassed <= 1.5 * alpha * trials + 2);
      // Power with 8 runs. Pixels independent: the region's relative standard error is 0.2%, the
      // bias 10 of them, found always. Correlated: per run the region's sum varies 1.45% (the
      // image's offset 1%, the shared field 1%, the pixels' own 0.3%), their mean of 8 0.51%, so
      // the bias is 3.9 standard errors, at the threshold (z 3.9 for alpha / (2 x 3 x 17)): about
      // half found. Heavy tails (45% noise per pixel, and the variance floor): rarely.
      if (runs == 8 && model == Model::Independent) CHECK(local.testFailed >= 0.95 * trials);
      if (runs == 8 && model == Model::Correlated) CHECK(local.testFailed >= 0.35 * trials);
    }
}

TEST_CASE("One image with variance layers: neighbours' correlated noise found, verdicts it undermines inconclusive",
          "[compare][calibration]") {
  // Variance layers count pixels as independent. Where a renderer splats samples into neighbours
  // (the correlated model, its per-run offset left out: one image cannot tell that from a bias) its
  // blocks' and regions' sums vary about 4.6 times what the layers say, and --test failed correct
  // images; the measured correlation of neighbours' differences (about 0.39) now makes a failure
  // inconclusive. Independent pixels are left as they were (alpha 0.05; and a 2% bias in one
  // region, alpha 0.01, is found as often as before: about 89 times in 200).
  constexpr double alpha = 0.05;
  constexpr int trials = 200;
  std::printf("noise model     --test: fails  inconclusive  passes   --within 0.05: fails  inconclusive  passes   "
              "2%% bias found   (of %d)\n", trials);
  for (Model model : {Model::Independent, Model::Correlated, Model::HeavyTailed}) {
    std::vector<Verdict> tests(static_cast<size_t>(trials), Verdict::Pass), withins = tests, biased = tests;
    std::vector<std::string> undecided(static_cast<size_t>(trials));
    tbb::parallel_for(0, trials, [&](int t) {
      Random rng{31000 + 1000 * uint64_t(model) + uint64_t(t)};
      const Image reference = simulatedReference(rng);
      const Candidate image(simulatedImageWithLayers(model, 0.0, rng));
      const NoiseTest test = testWithinNoise(image, reference, alpha);
      tests[size_t(t)] = test.verdict, undecided[size_t(t)] = test.noise.undecided;
      withins[size_t(t)] = testEquivalence(image, reference, 0.05, alpha).verdict;
      biased[size_t(t)] = testWithinNoise(Candidate(simulatedImageWithLayers(model, 0.02, rng)), reference, 0.01).verdict;
    });
    const auto count = [&](const std::vector<Verdict>& v, Verdict which) { return int(std::count(v.begin(), v.end(), which)); };
    std::printf("%-14s %14d  %12d  %6d   %20d  %12d  %6d   %14d\n", modelName(model), count(tests, Verdict::Fail),
                count(tests, Verdict::Inconclusive), count(tests, Verdict::Pass), count(withins, Verdict::Fail),
                count(withins, Verdict::Inconclusive), count(withins, Verdict::Pass), count(biased, Verdict::Fail));
    INFO(modelName(model));
    CHECK(count(tests, Verdict::Fail) <= 1.5 * alpha * trials);
    CHECK(count(withins, Verdict::Fail) <= 1.5 * alpha * trials);
    if (model == Model::Independent) {  // the correlation's z reaches 4 by chance, if ever
      CHECK(count(tests, Verdict::Inconclusive) <= 2);
      CHECK(count(biased, Verdict::Inconclusive) <= 2);
    }
    if (model == Model::Correlated) {
      CHECK(count(withins, Verdict::Pass) == 0);  // intervals from the layers are too narrow
      for (const std::string& why : undecided)
        if (!why.empty()) CHECK_THAT(why, Catch::Contains("correlated") && Catch::Contains("runs"));
    }
  }
}

// One image with variance layers from a renderer that splats each sample into pixels up to 2 x
// `radius` apart: a field of white noise under a separable tent of that radius (6% of the mean per
// pixel) plus the pixel's own noise (2%), the layers each pixel's exact variance; `bias` in the
// biased tile.
Image splattedImageWithLayers(int radius, double bias, Random& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> taps;
  double sum = 0;
  for (int k = -radius; k <= radius; ++k) sum += taps.emplace_back(radius + 1 - std::abs(k));
  double squares = 0;
  for (double& t : taps) t /= sum, squares += t * t;
  const int side = kSide + 2 * radius;
  std::vector<double> field(size_t(side) * size_t(side));
  for (double& e : field) e = normal(rng);
  Image image(kSide, kSide, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      double shared = 0;
      for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx)
          shared += taps[size_t(dx + radius)] * taps[size_t(dy + radius)] *
                    field[size_t(y + radius + dy) * size_t(side) + size_t(x + radius + dx)];
      shared /= squares;  // unit variance: the tent's weights squared sum to squares^2 over both axes
      for (int c = 0; c < 3; ++c) {
        const double mean = trueMean(x, y, c) * (1 + (inBiasedTile(x, y) ? bias : 0.0));
        image.at(x, y, c) = float(mean * (1 + 0.06 * shared + 0.02 * normal(rng)));
        image.at(x, y, 3 + c) = float((0.0036 + 0.0004) * mean * mean);
      }
    }
  return image;
}

TEST_CASE("One image with variance layers: noise shared up to 8 pixels apart leaves a failure inconclusive",
          "[compare][calibration]") {
  // Counting the 24 pixels within 2 of each at the neighbours' rho, tents of radius 2, 3 and 4
  // failed --test 0, 7 and 35 times in 200: their blocks' sums vary more than 1 + 24 rho times the
  // layers' sum. The correlations of pixels 3 to 8 apart raise the bound.
  constexpr double alpha = 0.05;
  constexpr int trials = 200;
  std::printf("tent radius  --test: fails  inconclusive  passes   30%% bias in one region found   (of %d)\n", trials);
  for (int radius : {2, 3, 4}) {
    std::vector<Verdict> tests(static_cast<size_t>(trials), Verdict::Pass), biased = tests;
    tbb::parallel_for(0, trials, [&](int t) {
      Random rng{47000 + 1000 * uint64_t(radius) + uint64_t(t)};
      const Image reference = simulatedReference(rng);
      tests[size_t(t)] = testWithinNoise(Candidate(splattedImageWithLayers(radius, 0.0, rng)), reference, alpha).verdict;
      biased[size_t(t)] = testWithinNoise(Candidate(splattedImageWithLayers(radius, 0.3, rng)), reference, alpha).verdict;
    });
    const auto count = [&](const std::vector<Verdict>& v, Verdict which) { return int(std::count(v.begin(), v.end(), which)); };
    std::printf("%11d  %13d  %12d  %6d   %29d\n", radius, count(tests, Verdict::Fail), count(tests, Verdict::Inconclusive),
                count(tests, Verdict::Pass), count(biased, Verdict::Fail));
    INFO("tent radius " << radius);
    CHECK(count(tests, Verdict::Fail) <= 1.5 * alpha * trials);
    CHECK(count(biased, Verdict::Fail) >= 0.9 * trials);  // a gross error still fails
  }
}

// One image with variance layers from a renderer whose pixels share random numbers within tiles of
// 16 x 16: each pixel's noise (10% of the mean) a share `rho` of its tile's and the rest its own,
// the tile's shared by the channels; the layers each pixel's exact variance. `bias` in the 32 x 32
// region at (32, 32), `overall` everywhere.
Image tileSharedImageWithLayers(int side, double rho, double bias, Random& rng, double overall = 0) {
  std::normal_distribution<double> normal(0.0, 1.0);
  constexpr int tile = 16;
  const int tiles = (side + tile - 1) / tile;
  std::vector<double> shared(size_t(tiles) * size_t(tiles));
  for (double& e : shared) e = normal(rng);
  Image image(side, side, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const double common = shared[size_t(y / tile) * size_t(tiles) + size_t(x / tile)];
      const bool biased = x >= 32 && x < 64 && y >= 32 && y < 64;
      for (int c = 0; c < 3; ++c) {
        const double mean = trueMean(x, y, c) * (1 + (biased ? bias : 0.0)) * (1 + overall);
        const double noise = std::sqrt(rho) * common + std::sqrt(1 - rho) * normal(rng);
        image.at(x, y, c) = float(mean * (1 + 0.1 * noise));
        image.at(x, y, 3 + c) = float(0.01 * mean * mean);
      }
    }
  return image;
}

TEST_CASE("One image with variance layers: noise shared by tiles of pixels leaves a failure inconclusive",
          "[compare][calibration]") {
  // Pixels sharing 2-3% of their noise within 16 x 16 tiles: too little for the neighbours' rho
  // (0.05 at z 4) to show, yet their 8 x 8 blocks' sums vary 2.3-2.9 times and the tiles' 6-9 times
  // what the layers say: --test failed 200 and 199 correct images of 200. The blocks' dispersion
  // shows it (at 128 x 128: 128 pairs of blocks); a region 30% too bright still fails, and
  // independent pixels (rho 0) fail as before.
  constexpr double alpha = 0.05;
  constexpr int trials = 200, side = 128;
  std::printf("shared rho  --test: fails  inconclusive  passes   30%% bias in one region found   3%% everywhere   "
              "(of %d)\n", trials);
  for (double rho : {0.0, 0.02, 0.03}) {
    std::vector<Verdict> tests(static_cast<size_t>(trials), Verdict::Pass), biased = tests, brighter = tests;
    tbb::parallel_for(0, trials, [&](int t) {
      Random rng{53000 + uint64_t(1000 * rho * 100) + uint64_t(t)};
      const Image reference = simulatedReference(rng, side);
      tests[size_t(t)] = testWithinNoise(Candidate(tileSharedImageWithLayers(side, rho, 0.0, rng)), reference, alpha).verdict;
      biased[size_t(t)] = testWithinNoise(Candidate(tileSharedImageWithLayers(side, rho, 0.3, rng)), reference, alpha).verdict;
      brighter[size_t(t)] =
          testWithinNoise(Candidate(tileSharedImageWithLayers(side, rho, 0.0, rng, 0.03)), reference, alpha).verdict;
    });
    const auto count = [&](const std::vector<Verdict>& v, Verdict which) { return int(std::count(v.begin(), v.end(), which)); };
    std::printf("%10.2f  %13d  %12d  %6d   %29d   %13d\n", rho, count(tests, Verdict::Fail),
                count(tests, Verdict::Inconclusive), count(tests, Verdict::Pass), count(biased, Verdict::Fail),
                count(brighter, Verdict::Fail));
    INFO("rho " << rho);
    CHECK(count(tests, Verdict::Fail) <= 1.5 * alpha * trials);
    CHECK(count(biased, Verdict::Fail) >= 0.9 * trials);  // a gross error still fails
    if (rho > 0) continue;
    // Independent pixels: as before, and an image 3% too bright everywhere, whose blocks' differences
    // follow the image's contrast, fails rather than passing for shared noise.
    CHECK(count(tests, Verdict::Inconclusive) <= 2);
    CHECK(count(brighter, Verdict::Fail) >= 0.9 * trials);
  }
}

TEST_CASE("One image with variance layers: a NaN fails however widely its noise is shared", "[compare]") {
  // Noise shared by tiles makes a failure stand only where it survives the blocks' dispersion; a
  // NaN, which no noise explains, fails whatever the inflation.
  Random rng{59001};
  const Image reference = simulatedReference(rng, 128);
  Image image = tileSharedImageWithLayers(128, 0.03, 0.0, rng);
  image.at(70, 40, 1) = std::numeric_limits<float>::quiet_NaN();
  const NoiseTest test = testWithinNoise(Candidate(image), reference, 0.05);
  INFO(test.noise.undecided);
  CHECK(test.noise.blockDispersionLow > 1);  // the shared noise is shown
  CHECK(test.verdict == Verdict::Fail);
}

TEST_CASE("One image with variance layers: under noise shared by tiles, only blocks of at most 8 x 8 carry a failure",
          "[compare]") {
  // The blocks' dispersion is measured over 8 x 8 blocks: a larger block's sum may vary more, so a
  // failure that blocks of 16 x 16 find is inconclusive, one that blocks of 8 x 8 find stands.
  Random rng{59002};
  const Image reference = simulatedReference(rng, 128);
  const Candidate image(tileSharedImageWithLayers(128, 0.03, 0.3, rng));
  const NoiseTest small = testWithinNoise(image, reference, 0.05, kRegionGrid, 8);
  const NoiseTest large = testWithinNoise(image, reference, 0.05, kRegionGrid, 16);
  CHECK(large.noise.blockDispersionLow > 1);  // the shared noise is shown
  CHECK(small.verdict == Verdict::Fail);
  INFO(large.noise.undecided);
  CHECK(large.verdict == Verdict::Inconclusive);
}

TEST_CASE("Student's t: p-values and quantiles", "[compare]") {
  // Known values: t = 12.706 has two-sided p 0.05 at 1 degree of freedom, 2.262 at 9, 1.960 for
  // the normal distribution; t = 1 at 1 degree of freedom has p 0.5 (Cauchy).
  CHECK(studentTwoSidedP(12.7062047, 1) == Approx(0.05).epsilon(1e-6));
  CHECK(studentTwoSidedP(2.26215716, 9) == Approx(0.05).epsilon(1e-6));
  CHECK(studentTwoSidedP(1.0, 1) == Approx(0.5).epsilon(1e-12));
  CHECK(studentTwoSidedP(1.95996398, INFINITY) == Approx(0.05).epsilon(1e-6));
  CHECK(studentTwoSidedP(0.0, 3) == Approx(1.0));
  CHECK(studentTwoSidedQuantile(0.05, 9) == Approx(2.26215716).epsilon(1e-7));
  CHECK(studentTwoSidedQuantile(0.01, 7) == Approx(3.49948329).epsilon(1e-7));
  CHECK(studentTwoSidedQuantile(1e-6, 2) == Approx(std::sqrt(2 / (1e-6 * (2 - 1e-6)) - 2)).epsilon(1e-6));
}

TEST_CASE("By surface: each material's interval covers its own bias, at least 1 - 1.5 x 2 alpha of the time",
          "[compare][calibration]") {
  // The simulated reference gains surface layers: material 0 the left half, 1 the right half, 2 an
  // emitter in the biased tile; the runs' right half is 6% dark. Each interval is a (1 - 2 alpha)
  // one: it must hold the true difference (0 left, -6% right, 0 the emitter) in at least
  // 1 - 1.5 x 2 alpha of the trials, and with 8 runs of independent or correlated noise tell the
  // right half's bias from 0.
  constexpr double alpha = 0.05, bias = -0.06;
  constexpr int trials = 200;
  const std::vector<std::string> names = {"left", "right", "lamp"};
  auto materialAt = [](int x, int y) { return inBiasedTile(x, y) ? 2 : x < kSide / 2 ? 0 : 1; };
  std::printf("noise model     runs  covered: left  right  lamp  emitters  non-emitters  right's bias shown   (of %d)\n", trials);
  for (Model model : {Model::Independent, Model::Correlated, Model::HeavyTailed})
    for (int runs : {2, 4, 8}) {
      std::vector<std::vector<SurfaceDifference>> results(static_cast<size_t>(trials));
      tbb::parallel_for(0, trials, [&](int t) {
        Random rng{77000 + 1000 * uint64_t(model) + 100 * uint64_t(runs) + uint64_t(t)};
        const Image plain = simulatedReference(rng);
        Image reference(kSide, kSide, {"R", "G", "B", "variance.R", "variance.G", "variance.B", "surface.material", "surface.emitter"});
        for (int y = 0; y < kSide; ++y)
          for (int x = 0; x < kSide; ++x) {
            for (int c = 0; c < 6; ++c) reference.at(x, y, c) = plain.at(x, y, c);
            reference.at(x, y, 6) = float(materialAt(x, y));
            reference.at(x, y, 7) = materialAt(x, y) == 2 ? 1.0f : 0.0f;
          }
        std::vector<Image> images;
        for (int i = 0; i < runs; ++i) {
          Image run = simulatedRun(model, 0.0, false, rng);
          for (int y = 0; y < kSide; ++y)
            for (int x = 0; x < kSide; ++x)
              if (materialAt(x, y) == 1)
                for (int c = 0; c < 3; ++c) run.at(x, y, c) *= float(1 + bias);
          images.push_back(std::move(run));
        }
        results[size_t(t)] = differenceBySurface(Candidate(std::move(images)), reference, names, alpha);
      });
      // Per unit (left, right, lamp, emitters, all but emitters): trials whose interval holds the truth.
      // The non-emitters: the left half less the lamp, and the right half (6% dark), by their light.
      double left = 0, right = 0;
      for (int y = 0; y < kSide; ++y)
        for (int x = 0; x < kSide; ++x)
          for (int c = 0; c < 3; ++c) {
            if (materialAt(x, y) == 0) left += trueMean(x, y, c);
            if (materialAt(x, y) == 1) right += trueMean(x, y, c);
          }
      const double truths[5] = {0, bias, 0, 0, bias * right / (left + right)};
      std::vector<int> covered(5, 0);
      int shown = 0;
      for (const auto& result : results) {
        REQUIRE(result.size() == 5);
        CHECK(result[1].name == "right");
        CHECK(result[3].kind == SurfaceDifference::Kind::Emitters);
        CHECK(result[3].pixels == 16 * 16);
        for (size_t u = 0; u < 5; ++u) covered[u] += result[u].low <= truths[u] && truths[u] <= result[u].high;
        shown += result[1].high < 0;
      }
      std::printf("%-14s %5d  %13d  %5d  %4d  %8d  %12d  %18d\n", modelName(model), runs, covered[0], covered[1],
                  covered[2], covered[3], covered[4], shown);
      INFO(modelName(model) << ", " << runs << " runs");
      for (size_t u = 0; u < 5; ++u) CHECK(covered[u] >= (1 - 1.5 * 2 * alpha) * trials);
      if (runs == 8 && model != Model::HeavyTailed) CHECK(shown >= 0.95 * trials);
    }
}
