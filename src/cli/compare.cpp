// lucent compare IMAGE REFERENCE [--metric rmse|relmse|smape|mae|flip] [--max-error X]
//                [--test [--block N]] [--within D] [--alpha A] [--heatmap OUT.png]
//                [--ppd P] [--start-exposure S] [--stop-exposure S]
//                [--layer NAME [--image-layer NAME]]
// Exit status: 0 passed (or no threshold), 1 the chosen metric exceeds --max-error, the image
// has NaN or infinite values, --test finds it differs from the reference by more than their
// noise, or --within cannot show it within D of the reference; 2 error (the reference's NaN or
// infinite values among them).
// 8-bit images (PNG, JPEG) are decoded from sRGB to linear before they are compared. FLIP is
// LDR-FLIP where both images are 8-bit sRGB files, HDR-FLIP otherwise.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli/commands.h"
#include "cli/comparison_options.h"
#include "cli/output_paths.h"
#include "lucent/core/text.h"
#include "lucent/image/flip.h"
#include "lucent/image/metrics.h"

namespace lucent::cli {

namespace {

struct CompareOptions {
  std::string image, reference, metric = "relmse", heatmap, layer, imageLayer;
  std::optional<double> maxError, within, startExposure, stopExposure;
  double pixelsPerDegree = kFlipPixelsPerDegree;
  bool test = false;
  int block = 8;
  double alpha = 0.01;
};

nlohmann::ordered_json testJson(const NoiseTest& t) {
  nlohmann::ordered_json out;
  out["alpha"] = t.alpha;
  out["passed"] = t.passed;
  out["candidate_variance"] = t.candidateHasVariance;
  out["block"] = t.block;
  out["blocks"] = t.blocks;
  out["fraction_rejected_at_alpha"] = double(t.blocksRejectedAtAlpha) / double(t.blocks);
  out["blocks_rejected"] = t.blocksRejected;
  out["min_block_p_value"] = t.minBlockPValue;
  out["regions"] = nlohmann::ordered_json::array();
  for (const RegionTest& r : t.regions)
    out["regions"].push_back({{"region", {r.x0, r.y0, r.x1, r.y1}},
                              {"relative_difference", r.relativeDifference},
                              {"z", r.z},
                              {"p_value", r.pValue},
                              {"rejected", r.rejected}});
  return out;
}

nlohmann::ordered_json equivalenceJson(const EquivalenceTest& t) {
  nlohmann::ordered_json out;
  out["within"] = t.within;
  out["alpha"] = t.alpha;
  out["passed"] = t.passed;
  out["candidate_variance"] = t.candidateHasVariance;
  out["regions"] = nlohmann::ordered_json::array();
  for (const EquivalenceRegion& r : t.regions)
    out["regions"].push_back({{"region", {r.x0, r.y0, r.x1, r.y1}},
                              {"relative_difference", r.relativeDifference},
                              {"interval", {r.low, r.high}},
                              {"equivalent", r.equivalent}});
  return out;
}

nlohmann::ordered_json metricsJson(const ChannelError& e) {
  return {{"rmse", e.rmse}, {"mae", e.mae}, {"relmse", e.relmse}, {"smape", e.smape}};
}

nlohmann::ordered_json flipJson(const FlipResult& f, double pixelsPerDegree) {
  nlohmann::ordered_json out;
  out["mean"] = f.mean;
  out["weighted_median"] = f.weightedMedian;
  out["weighted_quartiles"] = {f.weightedQuartile1, f.weightedQuartile3};
  out["range"] = f.hdr ? "hdr" : "ldr";
  out["pixels_per_degree"] = pixelsPerDegree;
  if (f.hdr) out["exposures"] = {{"start", f.startExposure}, {"stop", f.stopExposure}, {"count", f.exposures}};
  return out;
}

int runCompare(const CompareOptions& opt) {
  // Ranges checked here (CLI11's range checks print their bounds with 309 digits and let NaN
  // through, which no error would ever exceed).
  if (opt.maxError && !(std::isfinite(*opt.maxError) && *opt.maxError >= 0))
    throw std::invalid_argument("--max-error must be a finite number of at least 0");
  if (!(opt.alpha >= 1e-12 && opt.alpha <= 0.25)) throw std::invalid_argument("--alpha must lie in [1e-12, 0.25]");
  if (opt.block < 1 || opt.block > 4096) throw std::invalid_argument("--block must lie in [1, 4096]");
  if (opt.within && !(std::isfinite(*opt.within) && *opt.within > 0 && *opt.within <= 10))
    throw std::invalid_argument("--within must lie in (0, 10]");
  checkPixelsPerDegree(opt.pixelsPerDegree);
  for (const auto& [name, value] : {std::pair{"--start-exposure", opt.startExposure}, {"--stop-exposure", opt.stopExposure}})
    if (value && !(std::abs(*value) <= 100)) throw std::invalid_argument(std::string(name) + " must lie in [-100, 100]");
  if (opt.startExposure && opt.stopExposure && *opt.startExposure > *opt.stopExposure)
    throw std::invalid_argument("--start-exposure must not exceed --stop-exposure");
  const bool statistical = opt.test || opt.within.has_value();
  const bool flip = opt.metric == "flip";
  const ErrorMetric metric = flip ? ErrorMetric::RelMse : parseErrorMetric(opt.metric);
  if (!opt.heatmap.empty()) checkOutputFile(opt.heatmap, ".png", "--heatmap", {opt.image, opt.reference});
  // Sizes and channels from the headers first: a mismatch is reported before any pixel is decoded.
  {
    const ImageHeader image = readImageHeader(opt.image), reference = readImageHeader(opt.reference);
    try {
      checkComparable(image, reference, statistical || !opt.layer.empty());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + opt.image + "' vs '" + opt.reference + "': " + e.what());
    }
  }
  ImageMetadata candidateMetadata, referenceMetadata;
  Image candidateFile = readLinearImage(opt.image, &candidateMetadata);
  Image referenceFile = readLinearImage(opt.reference, &referenceMetadata);
  std::optional<LayerChoice> layer;
  if (!opt.layer.empty()) {
    try {
      layer = chooseLayer(candidateFile, referenceFile, opt.layer, opt.imageLayer);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + opt.image + "' vs '" + opt.reference + "': " + e.what());
    }
    candidateFile = std::move(layer->candidate);
    referenceFile = std::move(layer->reference);
  }
  // The test reads the variance layers; the metrics compare the colours.
  std::optional<NoiseTest> test;
  std::optional<EquivalenceTest> equivalence;
  std::optional<FlipResult> flipResult;
  try {
    if (flip) {
      FlipOptions options = flipOptions(isSrgbEncoded(opt.image, candidateMetadata),
                                        isSrgbEncoded(opt.reference, referenceMetadata), opt.pixelsPerDegree);
      options.startExposure = opt.startExposure;
      options.stopExposure = opt.stopExposure;
      flipResult = computeFlip(candidateFile, referenceFile, options);
    }
    if (opt.test) test = testWithinNoise(candidateFile, referenceFile, opt.alpha, 4, opt.block);
    if (opt.within) equivalence = testEquivalence(candidateFile, referenceFile, *opt.within, opt.alpha);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("'" + opt.image + "' vs '" + opt.reference + "': " + e.what());
  }
  const Image image = statistical ? rgbChannels(candidateFile) : candidateFile;
  const Image reference = statistical ? rgbChannels(referenceFile) : referenceFile;
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
  if (layer) out["layer"] = {{"image", layer->candidateLayer}, {"reference", layer->referenceLayer}};
  const double value = flipResult ? flipResult->mean : errorValue(error.overall, metric);
  out["value"] = value;
  out["overall"] = metricsJson(error.overall);
  out["channels"] = nlohmann::ordered_json::object();
  for (const ChannelError& c : error.perChannel) out["channels"][c.channel] = metricsJson(c);
  out["non_finite"] = error.nonFinite;
  // A NaN error must fail, hence "<=" rather than "not >".
  const bool passed = error.nonFinite == 0 && (!opt.maxError || value <= *opt.maxError) && (!test || test->passed) &&
                      (!equivalence || equivalence->passed);
  if (opt.maxError) out["max_error"] = *opt.maxError;
  if (test) out["test"] = testJson(*test);
  if (equivalence) out["equivalence"] = equivalenceJson(*equivalence);
  if (flipResult) out["flip"] = flipJson(*flipResult, opt.pixelsPerDegree);
  out["passed"] = passed;
  if (!opt.heatmap.empty()) {
    writePng(flipResult ? valueHeatmap(flipResult->map, 1)
             : test     ? valueHeatmap(test->statistic, 5)
                        : errorHeatmap(image, reference, metric),
             opt.heatmap);
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
      ->check(CLI::IsMember({"rmse", "relmse", "smape", "mae", "flip"}));
  cmd->add_option("--max-error", opt->maxError, "Fail (exit 1) when the metric exceeds this");
  cmd->add_option("--heatmap", opt->heatmap,
                  "Write a false-colour PNG of the per-pixel error (with --test: of |z|, 0 to 5; with --metric "
                  "flip: of FLIP, 0 to 1)");
  addLayerOptions(cmd, opt->layer, opt->imageLayer, "the image");
  CLI::Option* ppd = cmd->add_option("--ppd", opt->pixelsPerDegree, std::string("With --metric flip: ") + kPixelsPerDegreeHelp);
  CLI::Option* startExposure = cmd->add_option(
      "--start-exposure", opt->startExposure,
      "With --metric flip on HDR images: the first exposure in stops (default from the reference's largest luminance)");
  CLI::Option* stopExposure = cmd->add_option(
      "--stop-exposure", opt->stopExposure,
      "With --metric flip on HDR images: the last exposure in stops (default from the reference's median luminance)");
  CLI::Option* testFlag = cmd->add_flag("--test", opt->test,
                "Test whether the image differs from the reference by more than both images' noise "
                "(the reference needs variance layers: render it with --variance)");
  cmd->add_option("--block", opt->block,
                  "With --test: pixels per side of the blocks tested (default 8; 1 tests single pixels)")
      ->needs(testFlag);
  CLI::Option* within = cmd->add_option(
      "--within", opt->within,
      "Pass when, with confidence 1 - alpha, the image's relative difference from the reference lies inside "
      "+-D over the image and in each of 4 x 4 regions (for biased methods; the reference needs variance layers)");
  CLI::Option* alpha =
      cmd->add_option("--alpha", opt->alpha, "Significance of --test and --within, in [1e-12, 0.25] (default 0.01)");
  cmd->callback([opt, &exitCode, alpha, testFlag, within, ppd, startExposure, stopExposure] {
    // Errors exit 2 so that scripts can tell them from a comparison that failed the threshold.
    try {
      if (alpha->count() > 0 && testFlag->count() == 0 && within->count() == 0)
        throw std::invalid_argument("--alpha needs --test or --within");
      for (const CLI::Option* o : {ppd, startExposure, stopExposure})
        if (o->count() > 0 && opt->metric != "flip") throw std::invalid_argument(o->get_name() + " needs --metric flip");
      exitCode = runCompare(*opt);
    } catch (const std::exception& e) {
      std::cerr << "lucent compare: error: " << printable(e.what()) << "\n";
      exitCode = 2;
    }
  });
}

}  // namespace lucent::cli
