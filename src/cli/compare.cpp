// lucent compare IMAGE REFERENCE [--metric rmse|relmse|smape|mae] [--max-error X]
//                [--test [--alpha A]] [--heatmap OUT.png]
// Exit status: 0 passed (or no threshold), 1 the chosen metric exceeds --max-error, the image
// has NaN or infinite values, or --test finds it differs from the reference by more than their
// noise; 2 error (the reference's NaN or infinite values among them).
// 8-bit images (PNG, JPEG) are decoded from sRGB to linear before they are compared.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli/commands.h"
#include "cli/output_paths.h"
#include "lucent/core/text.h"
#include "lucent/image/metrics.h"

namespace lucent::cli {

namespace {

struct CompareOptions {
  std::string image, reference, metric = "relmse", heatmap;
  std::optional<double> maxError;
  bool test = false;
  double alpha = 0.01;
};

nlohmann::ordered_json testJson(const NoiseTest& t) {
  nlohmann::ordered_json out;
  out["alpha"] = t.alpha;
  out["passed"] = t.passed;
  out["candidate_variance"] = t.candidateHasVariance;
  out["pixels"] = t.pixels;
  out["fraction_rejected_at_alpha"] = double(t.pixelsRejectedAtAlpha) / double(t.pixels);
  out["pixels_rejected"] = t.pixelsRejected;
  out["min_pixel_p_value"] = t.minPixelPValue;
  out["regions"] = nlohmann::ordered_json::array();
  for (const RegionTest& r : t.regions)
    out["regions"].push_back({{"region", {r.x0, r.y0, r.x1, r.y1}},
                              {"relative_difference", r.relativeDifference},
                              {"z", r.z},
                              {"p_value", r.pValue},
                              {"rejected", r.rejected}});
  return out;
}

nlohmann::ordered_json metricsJson(const ChannelError& e) {
  return {{"rmse", e.rmse}, {"mae", e.mae}, {"relmse", e.relmse}, {"smape", e.smape}};
}

int runCompare(const CompareOptions& opt) {
  // Ranges checked here (CLI11's range checks print their bounds with 309 digits and let NaN
  // through, which no error would ever exceed).
  if (opt.maxError && !(std::isfinite(*opt.maxError) && *opt.maxError >= 0))
    throw std::invalid_argument("--max-error must be a finite number of at least 0");
  if (!(opt.alpha >= 1e-12 && opt.alpha <= 0.5)) throw std::invalid_argument("--alpha must lie in [1e-12, 0.5]");
  const ErrorMetric metric = parseErrorMetric(opt.metric);
  if (!opt.heatmap.empty()) checkOutputFile(opt.heatmap, ".png", "--heatmap", {opt.image, opt.reference});
  // Sizes and channels from the headers first: a mismatch is reported before any pixel is decoded.
  {
    const ImageHeader image = readImageHeader(opt.image), reference = readImageHeader(opt.reference);
    try {
      checkComparable(image, reference, opt.test);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + opt.image + "' vs '" + opt.reference + "': " + e.what());
    }
  }
  const Image candidateFile = readLinearImage(opt.image);
  const Image referenceFile = readLinearImage(opt.reference);
  // The test reads the variance layers; the metrics compare the colours.
  std::optional<NoiseTest> test;
  if (opt.test) {
    try {
      test = testWithinNoise(candidateFile, referenceFile, opt.alpha);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + opt.image + "' vs '" + opt.reference + "': " + e.what());
    }
  }
  const Image image = opt.test ? rgbChannels(candidateFile) : candidateFile;
  const Image reference = opt.test ? rgbChannels(referenceFile) : referenceFile;
  ImageError error;
  try {
    error = compareImages(image, reference);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("'" + opt.image + "' vs '" + opt.reference + "': " + e.what());
  }

  nlohmann::ordered_json out;
  out["image"] = opt.image;
  out["reference"] = opt.reference;
  out["width"] = image.width();
  out["height"] = image.height();
  out["metric"] = opt.metric;
  const double value = errorValue(error.overall, metric);
  out["value"] = value;
  out["overall"] = metricsJson(error.overall);
  out["channels"] = nlohmann::ordered_json::object();
  for (const ChannelError& c : error.perChannel) out["channels"][c.channel] = metricsJson(c);
  out["non_finite"] = error.nonFinite;
  // A NaN error must fail, hence "<=" rather than "not >".
  const bool passed = error.nonFinite == 0 && (!opt.maxError || value <= *opt.maxError) && (!test || test->passed);
  if (opt.maxError) out["max_error"] = *opt.maxError;
  if (test) out["test"] = testJson(*test);
  out["passed"] = passed;
  if (!opt.heatmap.empty()) {
    writePng(test ? statisticHeatmap(test->statistic) : errorHeatmap(image, reference, metric), opt.heatmap);
    out["heatmap"] = opt.heatmap;
  }
  std::cout << out.dump() << std::endl;
  return passed ? 0 : 1;
}

}  // namespace

void addCompareCommand(CLI::App& app, int& exitCode) {
  auto opt = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare an image against a reference");
  cmd->add_option("image", opt->image, "Image to evaluate")->required();
  cmd->add_option("reference", opt->reference, "Reference image")->required();
  cmd->add_option("--metric", opt->metric, "Metric tested against --max-error (default relmse)")
      ->check(CLI::IsMember({"rmse", "relmse", "smape", "mae"}));
  cmd->add_option("--max-error", opt->maxError, "Fail (exit 1) when the metric exceeds this")
;
  cmd->add_option("--heatmap", opt->heatmap,
                  "Write a false-colour PNG of the per-pixel error (with --test: of |z|, 0 to 5)");
  CLI::Option* testFlag = cmd->add_flag("--test", opt->test,
                "Test whether the image differs from the reference by more than both images' noise "
                "(the reference needs variance layers: render it with --variance)");
  cmd->add_option("--alpha", opt->alpha, "Significance of --test, in [1e-12, 0.5] (default 0.01)")->needs(testFlag);
  cmd->callback([opt, &exitCode] {
    // Errors exit 2 so that scripts can tell them from a comparison that failed the threshold.
    try {
      exitCode = runCompare(*opt);
    } catch (const std::exception& e) {
      std::cerr << "lucent compare: error: " << printable(e.what()) << "\n";
      exitCode = 2;
    }
  });
}

}  // namespace lucent::cli
