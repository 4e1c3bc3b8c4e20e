// lucent compare IMAGE... REFERENCE [--metric rmse|relmse|smape|mae|flip] [--max-error X]
//                [--test [--block N]] [--within D] [--alpha A] [--heatmap OUT.png] [--json]
//                [--ppd P] [--start-exposure S] [--stop-exposure S]
//                [--layer NAME [--image-layer NAME]] [--ldr]
// Two or more images before the reference are independent runs of one renderer (other seeds):
// their mean is compared, and their spread is the noise --test and --within use.
// Exit status: 0 pass (or no threshold); 1 fail: the chosen metric exceeds --max-error, the image
// has NaN or infinite values, --test finds it differs from the reference by more than their
// noise, or --within shows it outside +-D; 2 bad input (the reference's NaN or infinite values
// among them); 3 inconclusive: the candidate's noise is unknown (one image without variance
// layers, or with half-float ones) or --within neither passes nor fails (an interval reaches across
// +-D, or lies beyond it at alpha but not at alpha over both sides of every interval).
// Prints the verdict in words when stdout is a terminal, compare's JSON line otherwise or with
// --json. 8-bit images (PNG, JPEG) are decoded from sRGB to linear before they are compared. FLIP
// is LDR-FLIP where both images are 8-bit sRGB files, HDR-FLIP otherwise.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli/commands.h"
#include "cli/comparison_options.h"
#include "render/output_paths.h"
#include "core/json_text.h"
#include "lucent/core/text.h"
#include "lucent/image/comparison.h"
#include "lucent/image/metrics.h"

namespace lucent::cli {

namespace {

struct CompareOptions {
  std::vector<std::string> images;  // the candidate's runs, then the reference
  std::string heatmap;
  ComparisonSettings settings;
  bool json = false;
};


int runCompare(const CompareOptions& opt) {
  checkComparisonSettings(opt.settings);
  const ComparisonSettings& s = opt.settings;
  if (opt.images.size() < 2) throw std::invalid_argument("give an image (or its runs) and the reference");
  const std::vector<std::string> runs(opt.images.begin(), opt.images.end() - 1);
  const std::string& referencePath = opt.images.back();
  if (runs.size() > 1 && !(s.test || s.within))
    throw std::invalid_argument("several images before the reference are runs for --test or --within: give one of them");
  if (!opt.heatmap.empty()) checkOutputFile(opt.heatmap, ".png", "--heatmap", opt.images);
  // Sizes and channels from the headers first: a mismatch is reported before any pixel is decoded.
  const bool statistical = s.test || s.within.has_value();
  const std::string pair = "'" + runs[0] + (runs.size() > 1 ? "' (and its other runs)" : "'") + " vs '" + referencePath + "': ";
  bool halfVariance = false;
  const ImageHeader referenceHeader = readImageHeader(referencePath);
  std::vector<ImageHeader> headers;
  for (const std::string& path : runs) {
    const ImageHeader& image = headers.emplace_back(readImageHeader(path));
    halfVariance = halfVariance || image.hasHalfVariance();
    try {
      checkComparable(image, referenceHeader, statistical || !s.layer.empty());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + path + "' vs '" + referencePath + "': " + e.what());
    }
  }
  ImageMetadata candidateMetadata, referenceMetadata;
  std::vector<Image> images;
  bool candidateIsSrgb = false;
  std::vector<StoredRounding> rounding;
  for (size_t k = 0; k < runs.size(); ++k) {
    images.push_back(readLinearImage(runs[k], &candidateMetadata));
    const bool srgb = isSrgbEncoded(runs[k], candidateMetadata);
    candidateIsSrgb = candidateIsSrgb || srgb;
    rounding.push_back(storedRoundingOf(headers[k], srgb));
  }
  Image reference = readLinearImage(referencePath, &referenceMetadata);
  Candidate candidate = images.size() == 1 ? Candidate(std::move(images[0]), halfVariance) : Candidate(std::move(images));
  candidate.rounding = std::move(rounding);
  candidate.referenceRounding = storedRoundingOf(referenceHeader, isSrgbEncoded(referencePath, referenceMetadata));
  ComparisonSettings settings = s;
  settings.heatmap = !opt.heatmap.empty();
  ImageComparison result;
  try {
    settings.materialNames = materialNamesOf(referenceMetadata);
    result = compareImagePair(std::move(candidate), std::move(reference), settings, candidateIsSrgb,
                              isSrgbEncoded(referencePath, referenceMetadata));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(pair + e.what());
  }
  nlohmann::ordered_json out;
  out["image"] = runs[0];
  if (runs.size() > 1) out["runs"] = runs;
  out["reference"] = referencePath;
  const nlohmann::ordered_json computed = nlohmann::ordered_json::parse(result.json);
  for (const auto& [key, value] : computed.items()) out[key] = value;
  if (!opt.heatmap.empty()) {
    writePng(result.heatmap, opt.heatmap);
    out["heatmap"] = opt.heatmap;
  }
  if (opt.json || !::isatty(STDOUT_FILENO)) std::cout << jsonText(out) << std::endl;
  else {
    // File names in the words may hold anything.
    std::cout << printableLines(result.words) << (result.words.ends_with('\n') ? "" : "\n") << std::flush;
  }
  return verdictExitStatus(result.verdict);
}

}  // namespace

void addCompareCommand(CLI::App& app, int& exitCode) {
  auto opt = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare an image against a reference");
  cmd->add_option("images", opt->images,
                  "The image to evaluate (or two or more independent runs of it, renders with other seeds, whose "
                  "spread is the noise of --test and --within), then the reference image")
      ->required();
  cmd->add_flag("--json", opt->json, "Print compare's JSON line (the default where stdout is not a terminal)");
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
