// Helpers shared by the test files: temporary directories, running the CLI, image statistics.
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "lucent/image/image.h"

namespace lucent::test {

// A fresh, empty directory, removed with everything in it at the end of the scope.
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "test") {
    static std::atomic<int> counter{0};
    path = std::filesystem::temp_directory_path() /
           ("lucent-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
            std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& name) const { return (path / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path)) names.push_back(e.path().filename().string());
    return names;
  }
  std::filesystem::path path;
};

inline std::string quoted(const std::string& s) {
  std::string q = "'";
  q += s;  // += rather than + dodges a GCC 12 -Wrestrict false positive
  q += "'";
  return q;
}

struct CliRun {
  int status = -1;  // exit status, or 128 + signal
  std::string output;  // stdout and stderr together
};

// Runs a shell command line, its stdout and stderr captured together.
inline CliRun runCommand(const std::string& command) {
  CliRun run;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return run;
  char buffer[4096];
  for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) run.output.append(buffer, n);
  const int status = ::pclose(pipe);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return run;
}

// Runs the built `lucent` executable with ARGS (already shell-quoted where needed).
inline CliRun runLucent(const std::string& args) { return runCommand(quoted(LUCENT_CLI) + " " + args); }

// `lucent compare IMAGE REFERENCE --test` (both with variance layers): no block of 8 x 8 pixels
// and no region (the whole image, a 4 x 4 grid) rejected at alpha 0.01, and the whole image's
// relative difference within 1%.
inline void checkAgreesWithinNoise(const std::string& image, const std::string& reference) {
  const CliRun compare = runLucent("compare " + quoted(image) + " " + quoted(reference) + " --test");
  INFO(compare.output);
  REQUIRE(compare.status != 2);
  const nlohmann::json test = nlohmann::json::parse(compare.output)["test"];
  CHECK(test["blocks_rejected"] == 0);
  for (const auto& region : test["regions"]) CHECK(region["rejected"] == false);
  CHECK(std::abs(test["regions"][0]["relative_difference"].get<double>()) < 0.01);
}

// An R,G,B image whose pixel (x, y) is colourAt(x, y).
template <class ColourAt>
Image rgbImage(int width, int height, ColourAt colourAt) {
  Image image(width, height, {"R", "G", "B"});
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Rgb c = colourAt(x, y);
      for (int k = 0; k < 3; ++k) image.at(x, y, k) = c[k];
    }
  return image;
}

struct MeanAndError {
  double mean = 0, standardError = 0;
};

// The mean of n samples and its standard error, from their sum and sum of squares.
inline MeanAndError meanFromSums(double sum, double sum2, double n) {
  const double mean = sum / n;
  const double variance = std::max(0.0, sum2 / n - mean * mean) * n / (n - 1);
  return {mean, std::sqrt(variance / n)};
}

// Mean of one channel over the image, with its standard error estimated from the spread of the
// pixels, which are independent estimates when every pixel has its own random streams.
inline MeanAndError channelMean(const Image& image, int channel) {
  double sum = 0, sum2 = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      const double v = image.at(x, y, channel);
      sum += v;
      sum2 += v * v;
    }
  return meanFromSums(sum, sum2, double(image.width()) * image.height());
}

// Mean of independent estimates, with its standard error from their spread.
inline MeanAndError meanOf(const std::vector<double>& values) {
  double sum = 0, sum2 = 0;
  for (const double v : values) sum += v, sum2 += v * v;
  return meanFromSums(sum, sum2, double(values.size()));
}

// Renders repeated over seeds: kSeeds of them, and Student's t for their mean's standard error (7
// degrees of freedom) at p = 1e-3, two-sided and one-sided (4.785, rounded up).
constexpr int kSeeds = 8;
constexpr double kStudentTwoSided = 5.41, kStudentOneSided = 4.8;

// Requires the image's mean in R, G and B to match `expected` within 4.5 standard errors (two-sided
// p ~ 7e-6 per channel at a fixed seed; a NaN pixel makes the mean NaN and fails). It also requires
// the standard error below 2% of the expected value, so the test has the power to see a 10% error.
inline void requireImageMean(const Image& image, Rgb expected) {
  for (int c = 0; c < 3; ++c) {
    const MeanAndError s = channelMean(image, c);
    INFO("channel " << c << ": mean " << s.mean << " +- " << s.standardError << ", expected " << expected[c]);
    REQUIRE(s.standardError < 0.02 * expected[c]);
    REQUIRE(std::abs(s.mean - expected[c]) <= 4.5 * s.standardError + 1e-6 * expected[c]);
  }
}

// Sum of per-pixel differences over the square root of the sum of their squares: close to a
// standard normal when the two images estimate the same thing with independent pixels.
inline double agreementZ(const Image& a, const Image& b, int channel) {
  double sum = 0, sum2 = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) {
      const double d = double(a.at(x, y, channel)) - b.at(x, y, channel);
      sum += d;
      sum2 += d * d;
    }
  return sum / std::sqrt(sum2);
}

}  // namespace lucent::test
