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
#include "core/json_text.h"
#include "lucent/core/text.h"
#include "lucent/image/comparison.h"
#include "lucent/image/metrics.h"

namespace lucent::cli {

namespace {

struct CompareOptions {
  std::string image, reference, heatmap;
  ComparisonSettings settings;
};

int runCompare(const CompareOptions& opt) {
  checkComparisonSettings(opt.settings);
  const ComparisonSettings& s = opt.settings;
  if (!opt.heatmap.empty()) checkOutputFile(opt.heatmap, ".png", "--heatmap", {opt.image, opt.reference});
  // Sizes and channels from the headers first: a mismatch is reported before any pixel is decoded.
  const bool statistical = s.test || s.within.has_value();
  const std::string pair = "'" + opt.image + "' vs '" + opt.reference + "': ";
  {
    const ImageHeader image = readImageHeader(opt.image), reference = readImageHeader(opt.reference);
    try {
      checkComparable(image, reference, statistical || !s.layer.empty());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(pair + e.what());
    }
  }
  ImageMetadata candidateMetadata, referenceMetadata;
  Image candidate = readLinearImage(opt.image, &candidateMetadata);
  Image reference = readLinearImage(opt.reference, &referenceMetadata);
  ComparisonSettings settings = s;
  settings.heatmap = !opt.heatmap.empty();
  ImageComparison result;
  try {
    result = compareImagePair(std::move(candidate), std::move(reference), settings,
                              isSrgbEncoded(opt.image, candidateMetadata), isSrgbEncoded(opt.reference, referenceMetadata));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(pair + e.what());
  }
  nlohmann::ordered_json out;
  out["image"] = opt.image;
  out["reference"] = opt.reference;
  const nlohmann::ordered_json computed = nlohmann::ordered_json::parse(result.json);
  for (const auto& [key, value] : computed.items()) out[key] = value;
  if (!opt.heatmap.empty()) {
    writePng(result.heatmap, opt.heatmap);
    out["heatmap"] = opt.heatmap;
  }
  std::cout << jsonText(out) << std::endl;
  return result.passed ? 0 : 1;
}

}  // namespace

void addCompareCommand(CLI::App& app, int& exitCode) {
  auto opt = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare an image against a reference");
  cmd->add_option("image", opt->image, "Image to evaluate")->required();
  cmd->add_option("reference", opt->reference, "Reference image")->required();
  cmd->add_option("--metric", opt->settings.metric, "Metric tested against --max-error (default relmse)")
      ->check(CLI::IsMember({"rmse", "relmse", "smape", "mae", "flip"}));
  cmd->add_option("--max-error", opt->settings.maxError, "Fail (exit 1) when the metric exceeds this");
  cmd->add_option("--heatmap", opt->heatmap,
                  "Write a false-colour PNG of the per-pixel error (with --test: of |z|, 0 to 5; with --metric "
                  "flip: of FLIP, 0 to 1)");
  addLayerOptions(cmd, opt->settings.layer, opt->settings.imageLayer, "the image");
  CLI::Option* ppd = cmd->add_option("--ppd", opt->settings.pixelsPerDegree, std::string("With --metric flip: ") + kPixelsPerDegreeHelp);
  CLI::Option* startExposure = cmd->add_option(
      "--start-exposure", opt->settings.startExposure,
      "With --metric flip on HDR images: the first exposure in stops (default from the reference's largest luminance)");
  CLI::Option* stopExposure = cmd->add_option(
      "--stop-exposure", opt->settings.stopExposure,
      "With --metric flip on HDR images: the last exposure in stops (default from the reference's median luminance)");
  cmd->add_flag("--ldr", opt->settings.ldr,
                "The image is an 8-bit display image: compare it with the reference clipped to [0, 1] (without it, "
                "an 8-bit image against a reference brighter than 1 is refused)");
  CLI::Option* testFlag = cmd->add_flag("--test", opt->settings.test,
                "Test whether the image differs from the reference by more than both images' noise "
                "(the reference needs variance layers: render it with --variance)");
  cmd->add_option("--block", opt->settings.block,
                  "With --test: pixels per side of the blocks tested (default 8; 1 tests single pixels)")
      ->needs(testFlag);
  CLI::Option* within = cmd->add_option(
      "--within", opt->settings.within,
      "Pass when, with confidence 1 - alpha, the image's relative difference from the reference lies inside "
      "+-D over the image and in each of 4 x 4 regions (for biased methods; the reference needs variance layers)");
  CLI::Option* alpha =
      cmd->add_option("--alpha", opt->settings.alpha, "Significance of --test and --within, in [1e-12, 0.25] (default 0.01)");
  cmd->callback([opt, &exitCode, alpha, testFlag, within, ppd, startExposure, stopExposure] {
    // Errors exit 2 so that scripts can tell them from a comparison that failed the threshold.
    try {
      if (alpha->count() > 0 && testFlag->count() == 0 && within->count() == 0)
        throw std::invalid_argument("--alpha needs --test or --within");
      for (const CLI::Option* o : {ppd, startExposure, stopExposure})
        if (o->count() > 0 && opt->settings.metric != "flip") throw std::invalid_argument(o->get_name() + " needs --metric flip");
      exitCode = runCompare(*opt);
    } catch (const std::exception& e) {
      std::cerr << "lucent compare: error: " << printable(e.what()) << "\n";
      exitCode = 2;
    }
  });
}

}  // namespace lucent::cli
