#include "lucent/image/comparison.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "core/json_text.h"
#include "lucent/image/metrics.h"

namespace lucent {

namespace {

nlohmann::ordered_json noiseJson(const CandidateNoise& noise) {
  nlohmann::ordered_json out;
  out["source"] = noiseSourceName(noise.source);
  out["runs"] = noise.runs;
  if (noise.ignoredVarianceLayers) out["variance_layers"] = "ignored: the runs' spread was used";
  if (noise.source == NoiseSource::Runs)
    for (const CandidateNoise::Scale& scale : noise.scales)
      out["correlation"][scale.name] = {{"factor", scale.correlation}, {"degrees_of_freedom", scale.degreesOfFreedom}};
  if (noise.neighboursMeasured)
    out["neighbour_correlation"] = {{"rho", noise.neighbourCorrelation}, {"z", noise.neighbourCorrelationZ},
                                    {"inflation", noise.neighbourInflation},
                                    {"squares_over_layers", noise.layerLevel}, {"squares_over_layers_z", noise.layerLevelZ}};
  if (noise.blockDispersionMeasured)
    out["block_dispersion"] = {{"factor", noise.blockDispersion}, {"z", noise.blockDispersionZ},
                               {"low", noise.blockDispersionLow}, {"high", noise.blockDispersionHigh}};
  if (!noise.undecided.empty()) out["undecided"] = noise.undecided;
  return out;
}

nlohmann::ordered_json testJson(const NoiseTest& t) {
  nlohmann::ordered_json out;
  out["alpha"] = t.alpha;
  out["verdict"] = verdictName(t.verdict);
  out["passed"] = t.verdict == Verdict::Pass;
  out["candidate_noise"] = noiseJson(t.noise);
  out["block"] = t.block;
  out["blocks"] = t.blocks;
  out["fraction_rejected_at_alpha"] = double(t.blocksRejectedAtAlpha) / double(t.blocks);
  out["blocks_rejected"] = t.blocksRejected;
  out["min_block_p_value"] = t.minBlockPValue;
  out["min_block_at"] = {t.minBlockX, t.minBlockY};
  out["regions"] = nlohmann::ordered_json::array();
  for (const RegionTest& r : t.regions)
    out["regions"].push_back({{"region", {r.x0, r.y0, r.x1, r.y1}},
                              {"relative_difference", r.relativeDifference},
                              {"channel", std::string(1, "RGB"[r.channel])},
                              {"channel_relative_difference", r.channelDifference},
                              {"z", r.z},
                              {"p_value", r.pValue},
                              {"rejected", r.rejected}});
  return out;
}

nlohmann::ordered_json equivalenceJson(const EquivalenceTest& t) {
  nlohmann::ordered_json out;
  out["within"] = t.within;
  out["alpha"] = t.alpha;
  out["verdict"] = verdictName(t.verdict);
  out["passed"] = t.verdict == Verdict::Pass;
  out["candidate_noise"] = noiseJson(t.noise);
  if (t.samplesToDecide > 0) out["samples_to_decide"] = t.samplesToDecide;
  out["regions"] = nlohmann::ordered_json::array();
  for (const EquivalenceRegion& r : t.regions)
    out["regions"].push_back({{"region", {r.x0, r.y0, r.x1, r.y1}},
                              {"channel", std::string(1, "RGB"[r.channel])},
                              {"relative_difference", r.relativeDifference},
                              {"interval", {r.low, r.high}},
                              {"verdict", verdictName(r.verdict)}});
  return out;
}

std::string percent(double value) {
  std::ostringstream s;
  s << std::showpos << std::setprecision(2) << std::fixed << 100 * value << "%";
  return s.str();
}

std::string regionName(int x0, int y0, int x1, int y1, int width, int height) {
  if (x0 == 0 && y0 == 0 && x1 == width && y1 == height) return "the whole image";
  return "pixels x " + std::to_string(x0) + "-" + std::to_string(x1 - 1) + ", y " + std::to_string(y0) + "-" +
         std::to_string(y1 - 1);
}

// The verdict in words: what was tested, what failed or is undecided, where and by how much.
std::string verdictWords(Verdict verdict, int width, int height, uint64_t nonFinite,
                         const ComparisonSettings& opt, double value, const std::optional<NoiseTest>& test,
                         const std::optional<EquivalenceTest>& equivalence,
                         const std::vector<SurfaceDifference>& surfaces) {
  std::ostringstream s;
  s << verdictName(verdict) << "\n";
  if (nonFinite > 0) s << "  the image has " << nonFinite << " NaN or infinite values\n";
  if (opt.maxError)
    s << "  " << opt.metric << " " << value << (value <= *opt.maxError ? " <= " : " > ") << *opt.maxError
      << " (--max-error)\n";
  const CandidateNoise* noise = test ? &test->noise : equivalence ? &equivalence->noise : nullptr;
  if (noise) {
    s << "  candidate noise: ";
    if (noise->source == NoiseSource::Runs) {
      s << "the spread of " << noise->runs << " runs";
      for (const CandidateNoise::Scale& scale : noise->scales)
        s << "; " << scale.name << ": sums vary " << std::setprecision(3) << scale.correlation
          << " x their pixels' variances";
      s << "\n";
    } else {
      s << noiseSourceName(noise->source) << "\n";
    }
  }
  if (test) {
    s << "  --test: " << verdictName(test->verdict) << ", " << test->blocksRejected << " of " << test->blocks
      << " blocks of " << test->block << " x " << test->block << " rejected (least p-value "
      << std::setprecision(3) << test->minBlockPValue << " at x " << test->minBlockX << ", y " << test->minBlockY
      << ")\n";
    for (const RegionTest& r : test->regions)
      if (r.rejected)
        s << "    " << regionName(r.x0, r.y0, r.x1, r.y1, width, height) << ": " << percent(r.relativeDifference)
          << ", " << "RGB"[r.channel] << " " << percent(r.channelDifference) << " (p-value " << std::setprecision(3)
          << r.pValue << ")\n";
  }
  if (equivalence) {
    s << "  --within " << equivalence->within << ": " << verdictName(equivalence->verdict) << "\n";
    for (const EquivalenceRegion& r : equivalence->regions)
      if (r.verdict != Verdict::Pass || &r == &equivalence->regions.front())
        s << "    " << regionName(r.x0, r.y0, r.x1, r.y1, width, height) << ", " << "RGB"[r.channel] << ": "
          << percent(r.relativeDifference) << " [" << percent(r.low) << ", " << percent(r.high) << "] "
          << verdictName(r.verdict) << "\n";
  }
  if (!surfaces.empty()) {
    s << "  by surface (what each pixel's centre shows in the reference; " << std::setprecision(3)
      << 100 * (1 - 2 * opt.alpha) << "% intervals):\n";
    for (const SurfaceDifference& d : surfaces) {
      s << "    " << d.name << ": " << percent(d.relativeDifference);
      if (std::isfinite(d.low) && std::isfinite(d.high)) s << " [" << percent(d.low) << ", " << percent(d.high) << "]";
      s << " (" << d.pixels << " pixels)\n";
    }
  }
  if (noise && !noise->undecided.empty() && verdict == Verdict::Inconclusive) s << "  undecided: " << noise->undecided << "\n";
  return s.str();
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

}  // namespace

std::string surfaceDifferencesJson(const std::vector<SurfaceDifference>& surfaces) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const SurfaceDifference& d : surfaces) {
    nlohmann::ordered_json entry = {{"kind", surfaceKindName(d.kind)}};
    if (d.kind == SurfaceDifference::Kind::Material) entry["material"] = d.material;
    entry["name"] = d.name;
    entry["pixels"] = d.pixels;
    entry["relative_difference"] = d.relativeDifference;
    entry["interval"] = {d.low, d.high};  // null bounds: the noise tests are undecided
    out.push_back(entry);
  }
  return jsonText(out);
}

std::vector<std::string> materialNamesOf(const ImageMetadata& metadata) {
  for (const auto& [key, value] : metadata) {
    if (key != "lucent:materials") continue;
    const nlohmann::json names = nlohmann::json::parse(value, nullptr, false);
    std::vector<std::string> out;
    if (names.is_array())
      for (const nlohmann::json& name : names) {
        if (!name.is_string()) break;
        out.push_back(name.get<std::string>());
      }
    if (!names.is_array() || out.size() != names.size())
      throw std::invalid_argument("the reference's lucent:materials is not a JSON array of names");
    return out;
  }
  return {};
}

void checkPixelsPerDegree(double ppd) {
  if (!(ppd >= 1 && ppd <= 1000)) throw std::invalid_argument("--ppd must lie in [1, 1000]");
}

FlipOptions flipOptions(bool candidateIsSrgb, bool referenceIsSrgb, double ppd) {
  FlipOptions options;
  options.pixelsPerDegree = ppd;
  options.hdr = !(candidateIsSrgb && referenceIsSrgb);
  return options;
}

void checkComparisonSettings(const ComparisonSettings& opt) {
  // Ranges checked here (CLI11's range checks print their bounds with 309 digits and let NaN
  // through, which no error would ever exceed).
  if (opt.metric != "flip") parseErrorMetric(opt.metric);
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
}

uint64_t matchDisplayRange(bool candidateIsSrgb, bool referenceIsSrgb, Image& reference, bool ldr) {
  if (!candidateIsSrgb || referenceIsSrgb) return 0;
  uint64_t above = 0;
  for (const char* name : {"R", "G", "B"}) {
    const int c = reference.channelIndex(name);
    if (c < 0) continue;
    for (int y = 0; y < reference.height(); ++y)
      for (int x = 0; x < reference.width(); ++x)
        if (reference.at(x, y, c) > 1.0f) {
          ++above;
          if (ldr) reference.at(x, y, c) = 1.0f;
        }
  }
  if (above > 0 && !ldr)
    throw std::invalid_argument("the image is 8-bit (at most 1 once decoded) and the reference exceeds 1 in " +
                                std::to_string(above) + " values: compare an HDR image (EXR, PFM, HDR), or give --ldr "
                                "to compare it with the reference clipped to [0, 1]");
  return above;
}

ImageComparison compareImagePair(Candidate candidate, Image referenceFile, const ComparisonSettings& opt,
                                 bool candidateIsSrgb, bool referenceIsSrgb) {
  checkComparisonSettings(opt);
  if (candidate.runs.empty()) throw std::invalid_argument("no image to compare");
  // An image without pixels has no error to measure: "passed" would say nothing.
  for (const Image* image : {&candidate.runs[0], &referenceFile})
    if (image->width() < 1 || image->height() < 1)
      throw std::invalid_argument(std::string(image == &referenceFile ? "the reference" : "the image") +
                                  " has no pixels (" + std::to_string(image->width()) + " x " +
                                  std::to_string(image->height()) + ")");
  const bool statistical = opt.test || opt.within.has_value();
  const uint64_t clipped = matchDisplayRange(candidateIsSrgb, referenceIsSrgb, referenceFile, opt.ldr);
  const bool flip = opt.metric == "flip";
  const ErrorMetric metric = flip ? ErrorMetric::RelMse : parseErrorMetric(opt.metric);
  std::optional<LayerChoice> layer;
  if (!opt.layer.empty()) {
    const Image reference = std::move(referenceFile);
    for (Image& run : candidate.runs) {
      layer = chooseLayer(run, reference, opt.layer, opt.imageLayer);
      run = std::move(layer->candidate);
      referenceFile = std::move(layer->reference);
    }
  }
  // The tests read the variance layers or the runs; the metrics compare the colours (of the runs' mean).
  std::optional<NoiseTest> test;
  std::optional<EquivalenceTest> equivalence;
  std::optional<FlipResult> flipResult;
  if (opt.test) test = testWithinNoise(candidate, referenceFile, opt.alpha, 4, opt.block);
  if (opt.within) equivalence = testEquivalence(candidate, referenceFile, *opt.within, opt.alpha);
  // The breakdown by surface where the reference has the surface layers (and, as every interval
  // needs, its variance).
  std::vector<SurfaceDifference> surfaces;
  if (referenceFile.channelIndex("surface.material") >= 0 && referenceFile.channelIndex("variance.R") >= 0 &&
      referenceFile.channelIndex("variance.G") >= 0 && referenceFile.channelIndex("variance.B") >= 0)
    surfaces = differenceBySurface(candidate, referenceFile, opt.materialNames, opt.alpha);
  const Image candidateFile = candidateImage(candidate);
  if (flip) {
    FlipOptions options = flipOptions(candidateIsSrgb, referenceIsSrgb, opt.pixelsPerDegree);
    options.startExposure = opt.startExposure;
    options.stopExposure = opt.stopExposure;
    flipResult = computeFlip(candidateFile, referenceFile, options);
  }
  const Image image = statistical ? rgbChannels(candidateFile) : candidateFile;
  const Image reference = statistical ? rgbChannels(referenceFile) : referenceFile;
  const ImageError error = compareImages(image, reference);

  nlohmann::ordered_json out;
  out["width"] = image.width();
  out["height"] = image.height();
  out["metric"] = opt.metric;
  if (layer) out["layer"] = {{"image", layer->candidateLayer}, {"reference", layer->referenceLayer}};
  const double value = flipResult ? flipResult->mean : errorValue(error.overall, metric);
  out["value"] = value;
  out["overall"] = metricsJson(error.overall);
  out["channels"] = nlohmann::ordered_json::object();
  for (const ChannelError& c : error.perChannel) out["channels"][c.channel] = metricsJson(c);
  if (!error.notCompared.image.empty() || !error.notCompared.reference.empty())
    out["not_compared"] = {{"image", error.notCompared.image}, {"reference", error.notCompared.reference}};
  out["non_finite"] = error.nonFinite;
  if (opt.ldr) out["ldr"] = {{"reference_values_clipped", clipped}};
  ImageComparison result;
  // A NaN error must fail, hence "<=" rather than "not >".
  const bool measuredFail = error.nonFinite > 0 || (opt.maxError && !(value <= *opt.maxError));
  result.verdict = measuredFail ? Verdict::Fail : Verdict::Pass;
  if (test) result.verdict = combineVerdicts(result.verdict, test->verdict);
  if (equivalence) result.verdict = combineVerdicts(result.verdict, equivalence->verdict);
  if (opt.maxError) out["max_error"] = *opt.maxError;
  if (test) out["test"] = testJson(*test);
  if (equivalence) out["equivalence"] = equivalenceJson(*equivalence);
  // The rounding the tests allowed for, by each image's encoding (StoredRounding).
  const auto roundingJson = [](const StoredRounding& r) {
    nlohmann::ordered_json j = {{"encoding", colourEncodingName(r.encoding)}};
    if (r.encoding == ColourEncoding::Integer) j["largest_code"] = uint64_t(r.largestCode), j["srgb"] = r.srgb;
    return j;
  };
  if (statistical) {
    nlohmann::ordered_json image = nlohmann::ordered_json::array();  // the image's, or each run's
    for (const StoredRounding& r : candidate.rounding) image.push_back(roundingJson(r));
    out["stored_rounding"] = {{"image", image}, {"reference", roundingJson(candidate.referenceRounding)}};
  }
  if (flipResult) out["flip"] = flipJson(*flipResult, opt.pixelsPerDegree);
  if (!surfaces.empty())
    out["by_surface"] = {{"confidence", 1 - 2 * opt.alpha},
                         {"surfaces", nlohmann::ordered_json::parse(surfaceDifferencesJson(surfaces))}};
  out["verdict"] = verdictName(result.verdict);
  out["passed"] = result.verdict == Verdict::Pass;
  if (opt.heatmap)
    result.heatmap = flipResult ? valueHeatmap(flipResult->map, 1)
                     : test     ? valueHeatmap(test->statistic, 5)
                                : errorHeatmap(image, reference, metric);
  result.json = jsonText(out);
  result.words = verdictWords(result.verdict, image.width(), image.height(), error.nonFinite, opt, value, test,
                              equivalence, surfaces);
  return result;
}

}  // namespace lucent
