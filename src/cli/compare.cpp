// lucent compare IMAGE REFERENCE [--metric rmse|relmse|smape|mae] [--max-error X]
//                [--heatmap OUT.png]
// Exit status: 0 passed (or no threshold), 1 the chosen metric exceeds --max-error or the image
// has NaN or infinite values, 2 error (the reference's NaN or infinite values among them).
// 8-bit images (PNG, JPEG) are decoded from sRGB to linear before they are compared.
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli/commands.h"
#include "lucent/image/metrics.h"

namespace lucent::cli {

namespace {

struct CompareOptions {
  std::string image, reference, metric = "relmse", heatmap;
  std::optional<double> maxError;
};

nlohmann::ordered_json metricsJson(const ChannelError& e) {
  return {{"rmse", e.rmse}, {"mae", e.mae}, {"relmse", e.relmse}, {"smape", e.smape}};
}

int runCompare(const CompareOptions& opt) {
  const ErrorMetric metric = parseErrorMetric(opt.metric);
  if (!opt.heatmap.empty()) {
    std::error_code ec;
    const auto heatmap = std::filesystem::weakly_canonical(opt.heatmap, ec);
    for (const std::string& input : {opt.image, opt.reference})
      if (heatmap == std::filesystem::weakly_canonical(input, ec))
        throw std::invalid_argument("--heatmap '" + opt.heatmap + "' is one of the images compared");
  }
  const Image image = readLinearImage(opt.image);
  const Image reference = readLinearImage(opt.reference);
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
  const bool passed = error.nonFinite == 0 && (!opt.maxError || value <= *opt.maxError);
  if (opt.maxError) out["max_error"] = *opt.maxError;
  out["passed"] = passed;
  if (!opt.heatmap.empty()) {
    writePng(errorHeatmap(image, reference, metric), opt.heatmap);
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
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--heatmap", opt->heatmap, "Write a false-colour PNG of the per-pixel error");
  cmd->callback([opt, &exitCode] {
    // Errors exit 2 so that scripts can tell them from a comparison that failed the threshold.
    try {
      exitCode = runCompare(*opt);
    } catch (const std::exception& e) {
      std::cerr << "lucent compare: error: " << e.what() << "\n";
      exitCode = 2;
    }
  });
}

}  // namespace lucent::cli
