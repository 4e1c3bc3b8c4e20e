// What `lucent compare` computes of a candidate image against a reference, for any caller (the CLI
// reads files; the Python module passes arrays): the metrics, FLIP, the within-noise test and the
// equivalence verdict, as compare's JSON, so that every caller reports the same numbers.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "lucent/image/flip.h"
#include "lucent/image/image.h"
#include "lucent/image/noise_tests.h"

namespace lucent {

struct ComparisonSettings {
  std::string metric = "relmse";  // rmse, relmse, smape, mae or flip
  std::optional<double> maxError;  // fail when the metric exceeds it
  bool test = false;               // the within-noise test (the reference needs variance layers)
  int block = 8;
  std::optional<double> within;    // the equivalence verdict: within +-D of the reference
  double alpha = 0.01;
  std::string layer, imageLayer;   // compare the reference's layer (and the candidate's, by its name)
  double pixelsPerDegree = kFlipPixelsPerDegree;
  std::optional<double> startExposure, stopExposure;  // HDR-FLIP's range (default: from the reference)
  bool heatmap = false;            // also make the heatmap compare --heatmap writes
  bool ldr = false;                // an 8-bit candidate against the reference clipped to [0, 1]
  // The reference's material names by index (its lucent:materials), which name the breakdown of
  // the difference by the surfaces its surface.material layer shows.
  std::vector<std::string> materialNames;
};

// An 8-bit (display) image holds at most 1 once decoded: against a reference brighter than that
// (its lights), the clipped light would read as a bias (-51% on a lamp). Where the candidate is
// 8-bit sRGB, the reference is not and some of its R, G, B values exceed 1, throws
// std::invalid_argument saying so, unless `ldr`: then those values of `reference` are clipped to 1,
// and their count is returned (0 where nothing applies).
uint64_t matchDisplayRange(bool candidateIsSrgb, bool referenceIsSrgb, Image& reference, bool ldr);

// The material names an image's metadata holds (lucent:materials, a JSON array of strings, which
// render --layers writes); empty where it has none. Throws std::invalid_argument where it is not
// such an array.
std::vector<std::string> materialNamesOf(const ImageMetadata& metadata);

// The breakdown by surface as compare's JSON holds it (by_surface.surfaces), an array, for every
// front end that reports it.
std::string surfaceDifferencesJson(const std::vector<SurfaceDifference>& surfaces);

// Throws std::invalid_argument, naming the option as the command line spells it, for a setting out
// of its range.
void checkComparisonSettings(const ComparisonSettings& settings);
// FLIP's observer, in [1, 1000] pixels per degree; throws std::invalid_argument naming --ppd.
void checkPixelsPerDegree(double ppd);
// LDR-FLIP between two 8-bit sRGB images (display images), HDR-FLIP otherwise.
FlipOptions flipOptions(bool candidateIsSrgb, bool referenceIsSrgb, double ppd);

struct ImageComparison {
  // Fail where --max-error is exceeded, the image has NaN or infinite values, or a statistical test
  // fails; else inconclusive where a statistical test is (the candidate's noise unknown, or an
  // interval across the margin); else pass.
  Verdict verdict = Verdict::Inconclusive;
  std::string json;   // compare's JSON from "width" on (the caller names the files before it)
  std::string words;  // the verdict for a person: what failed or is undecided, where, by how much
  Image heatmap;      // with settings.heatmap
};

// Compares the candidate (one image, or two or more runs: the metrics and FLIP of their mean) with
// the reference (linear images; *IsSrgb: decoded from 8-bit sRGB files, which makes FLIP LDR-FLIP).
// Throws std::invalid_argument for images that cannot be compared.
ImageComparison compareImagePair(Candidate candidate, Image reference, const ComparisonSettings& settings,
                                 bool candidateIsSrgb = false, bool referenceIsSrgb = false);

}  // namespace lucent
