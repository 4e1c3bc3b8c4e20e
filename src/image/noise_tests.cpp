#include "lucent/image/noise_tests.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "image/channel_indices.h"
#include "lucent/core/memory.h"
#include "lucent/core/srgb.h"

namespace lucent {

const char* verdictName(Verdict verdict) {
  switch (verdict) {
    case Verdict::Pass: return "pass";
    case Verdict::Fail: return "fail";
    case Verdict::Inconclusive: return "inconclusive";
  }
  return "inconclusive";
}

int verdictExitStatus(Verdict verdict) {
  switch (verdict) {
    case Verdict::Pass: return 0;
    case Verdict::Fail: return 1;
    case Verdict::Inconclusive: return 3;
  }
  return 3;
}

Verdict combineVerdicts(Verdict a, Verdict b) {
  if (a == Verdict::Fail || b == Verdict::Fail) return Verdict::Fail;
  if (a == Verdict::Inconclusive || b == Verdict::Inconclusive) return Verdict::Inconclusive;
  return Verdict::Pass;
}

const char* noiseSourceName(NoiseSource source) {
  switch (source) {
    case NoiseSource::VarianceLayer: return "variance layer";
    case NoiseSource::Runs: return "runs";
    case NoiseSource::Unknown: return "unknown";
  }
  return "unknown";
}

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The regularized incomplete beta function I_x(a, b), by its continued fraction (DLMF 8.17.22)
// evaluated with Lentz's method, on the side of x where it converges fast.
double incompleteBeta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  if (x > (a + 1) / (a + b + 2)) return 1 - incompleteBeta(b, a, 1 - x);
  const double front = std::exp(a * std::log(x) + b * std::log1p(-x) - std::lgamma(a) - std::lgamma(b) + std::lgamma(a + b)) / a;
  constexpr double kTiny = 1e-300;
  double f = 1, c = 1, d = 0;
  for (int i = 0; i <= 1000; ++i) {
    const double m = double(i / 2);
    double numerator = 1;
    if (i > 0)
      numerator = i % 2 == 0 ? m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
                             : -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
    d = 1 + numerator * d;
    d = 1 / (std::abs(d) < kTiny ? kTiny : d);
    c = 1 + numerator / c;
    if (std::abs(c) < kTiny) c = kTiny;
    f *= c * d;
    if (std::abs(1 - c * d) < 1e-15) break;
  }
  return front * (f - 1);
}

}  // namespace

double studentTwoSidedP(double t, double dof) {
  if (!std::isfinite(t)) return 0;  // NaN or infinite: a difference no noise explains
  if (!(dof < 1e7)) return std::erfc(std::abs(t) / std::sqrt(2.0));
  return incompleteBeta(0.5 * dof, 0.5, dof / (dof + t * t));
}

double studentTwoSidedQuantile(double p, double dof) {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("a quantile's probability must be in (0, 1)");
  double lo = 0, hi = 1;
  while (studentTwoSidedP(hi, dof) > p && hi < 1e300) hi *= 2;
  // Bisection on the p-value, decreasing in t: to double precision.
  for (int i = 0; i < 2000 && hi - lo > 1e-14 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (studentTwoSidedP(mid, dof) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double normalUpperQuantile(double alpha) {
  if (!(alpha > 0 && alpha < 1)) throw std::invalid_argument("a quantile's probability must be in (0, 1)");
  // Bisection on the upper tail 0.5 erfc(z / sqrt 2), decreasing in z: to double precision.
  double lo = -40, hi = 40;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * std::max(1.0, std::abs(lo)); ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

StoredRounding storedRoundingOf(const ImageHeader& header, bool srgb) {
  return {header.colourEncoding, header.colourEncoding == ColourEncoding::Integer && srgb,
          header.colourEncoding == ColourEncoding::Integer ? header.largestCode : 0};
}

namespace {

// R, G, B and their sum (the equivalence test's quantity).
constexpr int kSum = 3;
using Quad = std::array<double, 4>;

// The variance of R + G + B from the channels' as if they were fully correlated, (the sum of their
// standard deviations)^2: a bound whatever their correlation.
double sumVarianceBound(const Quad& variance) {
  const double deviations = std::sqrt(variance[0]) + std::sqrt(variance[1]) + std::sqrt(variance[2]);
  return deviations * deviations;
}

// The region (1-based, row by row) of a grid of tiles x tiles that pixel (x, y) of a w x h image lies in.
size_t tileOf(int x, int y, int tiles, int w, int h) {
  return size_t(1 + int64_t(y) * tiles / h * tiles + int64_t(x) * tiles / w);
}

// The ratio sum a / sum w of terms (a_k, w_k), and its standard error from the terms' spread about
// it: sqrt(sum (a_k - q w_k)^2) / sum w.
// Disjoint pairs of units k apart on a w x h grid, row by row: in each cell of 2k x 2k units the
// units k apart along x or, in every other cell, along y, so that no unit is in two pairs.
// `pair(xa, ya, xb, yb)` is called for each pair whose second unit lies on the grid.
template <class Pair>
void forDisjointPairs(int w, int h, int k, const Pair& pair) {
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool alongX = (x / (2 * k) + y / (2 * k)) % 2 == 0;
      if (alongX && x % (2 * k) < k && x + k < w) pair(x, y, x + k, y);
      if (!alongX && y % (2 * k) < k && y + k < h) pair(x, y, x, y + k);
    }
}

struct RatioOfSums {
  double numerator = 0, denominator = 0, numerator2 = 0, cross = 0, denominator2 = 0;
  void add(double a, double w) {
    numerator += a, denominator += w, numerator2 += a * a, cross += a * w, denominator2 += w * w;
  }
  double ratio() const { return numerator / denominator; }
  double spread() const {
    const double q = ratio();
    return std::sqrt(std::max(0.0, numerator2 - 2 * q * cross + q * q * denominator2)) / denominator;
  }
};

// Whether the variance layers' neighbours are shown correlated (or anticorrelated): rho and its z
// beyond kNeighbourCorrelation and kNeighbourCorrelationZ.
bool neighbourCorrelationShown(const CandidateNoise& noise) {
  return noise.source == NoiseSource::VarianceLayer && noise.neighboursMeasured &&
         std::abs(noise.neighbourCorrelation) >= kNeighbourCorrelation &&
         std::abs(noise.neighbourCorrelationZ) >= kNeighbourCorrelationZ;
}

// The candidate and the reference as the tests read them, pixel by pixel.
class TestPixels {
 public:
  // `tiles`: the grid over whose tiles the variance floor takes its median (floorPixelVariances).
  TestPixels(const Candidate& candidate, const Image& reference, int tiles)
      : candidate_(candidate), reference_(reference), tiles_(std::max(1, tiles)) {
    if (candidate.runs.empty()) throw std::invalid_argument("no image to compare");
    for (const Image& run : candidate.runs) requireSameSize(run, reference);
    referenceValue_ = rgbIndices(reference, "", "the reference");
    referenceVariance_ = rgbIndices(reference, "variance.", "the reference", " (render it with --variance)");
    const bool runs = candidate.runs.size() > 1;
    for (size_t i = 0; i < candidate.runs.size(); ++i) {
      const std::string role = runs ? "run " + std::to_string(i + 1) : "the image";
      runs_.push_back({rgbIndices(candidate.runs[i], "", role), rgbIndices(candidate.runs[i], "variance.", "")});
    }
    const auto hasVariance = [](const Channels& c) { return c.variance[0] >= 0 && c.variance[1] >= 0 && c.variance[2] >= 0; };
    noise_.runs = int(candidate.runs.size());
    if (runs) {
      noise_.source = NoiseSource::Runs;
      noise_.ignoredVarianceLayers = std::any_of(runs_.begin(), runs_.end(), hasVariance);
    } else if (hasVariance(runs_[0])) {
      noise_.source = NoiseSource::VarianceLayer;
      if (candidate.halfVariance)
        noise_.undecided = "the image's variance layers are stored as half floats, which turn variances below 6e-8 "
                           "into 0: write them as 32-bit floats, or give two or more runs (renders with other seeds)";
    } else {
      noise_.undecided = "the image has no variance layers, so its noise is unknown: give two or more runs (renders "
                         "with other seeds), or an image with variance layers (render --variance)";
    }
    const auto lossy = [](const StoredRounding& r) { return r.encoding == ColourEncoding::Lossy; };
    const bool candidateLossy = std::any_of(candidate.rounding.begin(), candidate.rounding.end(), lossy);
    if ((candidateLossy || lossy(candidate.referenceRounding)) && noise_.undecided.empty())
      noise_.undecided = std::string(candidateLossy ? runs ? "a run" : "the image" : "the reference") +
                         " is stored lossily (JPEG), whose compression changes values by more than their noise: "
                         "compare a lossless file (EXR, PFM, PNG)";
    // Each way the runs were stored once, with its share of them: readRounded weighs their allowances.
    for (const StoredRounding& r : candidate.rounding) {
      const auto same = [&](const RoundingShare& s) {
        return s.rounding.encoding == r.encoding && s.rounding.srgb == r.srgb && s.rounding.largestCode == r.largestCode;
      };
      const auto found = std::find_if(roundings_.begin(), roundings_.end(), same);
      (found != roundings_.end() ? *found : roundings_.emplace_back(RoundingShare{r, 0.0})).share +=
          1.0 / double(candidate.rounding.size());
    }
    values_.resize(candidate.runs.size());
    checkVariances();
    // Before the floor, which raises the variances (w below) of pixels whose layers are low by chance.
    if (noise_.source == NoiseSource::VarianceLayer && noise_.undecided.empty()) {
      measureNeighbourCorrelation();
      measureBlockDispersion();
    }
    if (noise_.source != NoiseSource::Unknown) floorPixelVariances();
  }

  const CandidateNoise& noise() const { return noise_; }
  CandidateNoise& noise() { return noise_; }
  int width() const { return reference_.width(); }
  int height() const { return reference_.height(); }

  // Pixel (x, y): the candidate's mean and the variance of that mean (0 where unknown), the
  // reference's value and variance, and each run's values (values()).
  void read(int x, int y, Quad& mean, Quad& variance, Quad& reference, Quad& referenceVariance) {
    for (int c = 0; c < 3; ++c) {
      reference[size_t(c)] = reference_.at(x, y, referenceValue_[size_t(c)]);
      referenceVariance[size_t(c)] = knownVariance(reference_.at(x, y, referenceVariance_[size_t(c)]));
    }
    reference[kSum] = reference[0] + reference[1] + reference[2];
    referenceVariance[kSum] = sumVarianceBound(referenceVariance);
    const size_t n = candidate_.runs.size();
    for (size_t i = 0; i < n; ++i) {
      const Image& run = candidate_.runs[i];
      for (int c = 0; c < 3; ++c) values_[i][size_t(c)] = run.at(x, y, runs_[i].value[size_t(c)]);
      values_[i][kSum] = values_[i][0] + values_[i][1] + values_[i][2];
    }
    if (n == 1) {
      mean = values_[0];
      variance = {};
      if (noise_.source == NoiseSource::VarianceLayer) {
        for (int c = 0; c < 3; ++c)
          variance[size_t(c)] = knownVariance(candidate_.runs[0].at(x, y, runs_[0].variance[size_t(c)]));
        variance[kSum] = sumVarianceBound(variance);
      }
    } else {
      spreadOfRuns(mean, variance);
    }
    if (floors_.empty()) return;
    const Quad& floor = floors_[tileOf(x, y, tiles_, width(), height()) - 1];
    for (size_t c = 0; c < 4; ++c) variance[c] = std::max(variance[c], floor[c] * referenceVariance[c]);
  }
  // The same with the two values' rounding (Candidate::rounding) allowed for. Rounding to the
  // nearest (floats), per pixel, so that bright exact pixels (an emitter) lend no allowance to the
  // difference of others: where neither value has noise the candidate's mean is moved towards the
  // reference by as much as the two may differ by; elsewhere the rounding counts as noise, a
  // uniform error of variance m^2 / 3 added to the reference's (known) variance. Integer codes and
  // RGBE, which may be truncated (a value stored up to a step low, or half a step high where the
  // writer rounds or the reader adds half a step), are a bias of one sign that sums over pixels:
  // `low` and `high` are how far below and above the true difference the stored one may lie, for
  // the tests to allow over each sum (UnitSums::low, high).
  void readRounded(int x, int y, Quad& mean, Quad& variance, Quad& reference, Quad& referenceVariance, Quad& low,
                   Quad& high) {
    read(x, y, mean, variance, reference, referenceVariance);
    const double candidateLargest = std::max({mean[0], mean[1], mean[2]});
    const double referenceLargest = std::max({reference[0], reference[1], reference[2]});
    low = {}, high = {};
    for (size_t c = 0; c < 3; ++c) {
      const double d = mean[c] - reference[c];
      if (!std::isfinite(d)) continue;  // a non-finite candidate stays as it is: no noise explains it
      Allowance a;
      for (const auto& [rounding, share] : roundings_) {
        const Allowance each = allowanceOf(rounding, mean[c], candidateLargest);
        a.nearest += share * each.nearest, a.step += share * each.step;
      }
      const Allowance b = allowanceOf(candidate_.referenceRounding, reference[c], referenceLargest);
      const double nearest = a.nearest + b.nearest;
      if (variance[c] == 0 && referenceVariance[c] == 0)
        mean[c] = reference[c] + std::copysign(std::max(0.0, std::abs(d) - nearest), d);
      else
        referenceVariance[c] += nearest * nearest / 3;
      // The candidate's value low by up to a step, high by up to half; the reference's likewise.
      low[c] = a.step + 0.5 * b.step, high[c] = 0.5 * a.step + b.step;
    }
    mean[kSum] = mean[0] + mean[1] + mean[2];
    referenceVariance[kSum] = sumVarianceBound(referenceVariance);
    low[kSum] = low[0] + low[1] + low[2], high[kSum] = high[0] + high[1] + high[2];
  }
  const std::vector<Quad>& values() const { return values_; }

 private:
  // How a value v, of a pixel whose largest channel is `largest`, may differ from the value
  // written, by its file's encoding: by up to `nearest` either way (a float), or within its code's
  // `step` (an integer code, RGBE).
  struct Allowance {
    double nearest = 0, step = 0;
  };
  static Allowance allowanceOf(const StoredRounding& r, double v, double largest) {
    switch (r.encoding) {
      case ColourEncoding::Float: return {kFloatRounding * std::abs(v), 0};
      // Below 2^-14 a half float's spacing stops shrinking: at least half its smallest subnormal.
      case ColourEncoding::Half: return {std::max(kHalfRounding * std::abs(v), 0x1p-25), 0};
      // Read as code / largest in float arithmetic (which counts beside 32-bit codes' steps).
      case ColourEncoding::Integer: return {kFloatRounding * std::abs(v), codeStep(r.largestCode, r.srgb, v)};
      case ColourEncoding::SharedExponent: {
        // 8-bit mantissas under the exponent of the largest channel, m 2^e with m in [0.5, 1).
        int exponent = 0;
        std::frexp(std::abs(largest), &exponent);
        return {0, largest != 0 && std::isfinite(largest) ? std::ldexp(1.0, exponent - 8) : 0.0};
      }
      case ColourEncoding::Lossy: return {};  // undecided (see the constructor)
    }
    return {};
  }
  // One step of an integer code of `levels` steps at the value v, in linear terms: through the
  // sRGB curve the step above v's code, the larger of the two about it (the curve is convex).
  static double codeStep(double levels, bool srgb, double v) {
    if (!srgb) return 1 / levels;
    const double code = std::min(double(linearToSrgb(float(std::clamp(v, 0.0, 1.0)))), 1 - 1 / levels);
    return double(srgbToLinear(float(code + 1 / levels))) - double(srgbToLinear(float(code)));
  }

  // A variance layer's value where it is one: finite and not negative. Infinity (a pixel of fewer
  // than 2 samples), NaN (another renderer's M2 / (n - 1) at n = 1) or a negative value make the
  // verdict inconclusive (checkVariances); read as 0, they keep the sums finite.
  static double knownVariance(float v) { return v >= 0 && v <= std::numeric_limits<float>::max() ? v : 0.0; }

  // Every pixel's variance known, in the reference and (where the candidate's noise is its variance
  // layers) in the candidate: otherwise a block holding one would be tested against a variance that
  // is infinite (passing whatever its difference) or taken as nought (failing at any).
  void checkVariances() {
    const bool candidateLayers = noise_.source == NoiseSource::VarianceLayer;
    struct Unknown {
      uint64_t count = 0;
      int x = 0, y = 0;
    } reference, candidate;
    const auto note = [](Unknown& u, int x, int y) {
      if (u.count++ == 0) u.x = x, u.y = y;
    };
    for (int y = 0; y < height(); ++y)
      for (int x = 0; x < width(); ++x)
        for (size_t c = 0; c < 3; ++c) {
          const float r = reference_.at(x, y, referenceVariance_[c]);
          if (!(r == knownVariance(r))) note(reference, x, y);
          if (!candidateLayers) continue;
          const float v = candidate_.runs[0].at(x, y, runs_[0].variance[c]);
          if (!(v == knownVariance(v))) note(candidate, x, y);
        }
    for (const auto& [u, whose] : {std::pair{&reference, "the reference"}, std::pair{&candidate, "the image"}})
      if (u->count > 0 && noise_.undecided.empty())
        noise_.undecided = std::string(whose) + "'s variance is infinite, NaN or negative at " +
                           std::to_string(u->count) + (u->count == 1 ? " value" : " values") + " (the first at x " +
                           std::to_string(u->x) + ", y " + std::to_string(u->y) + "): such a pixel's noise is unknown (a "
                           "pixel of fewer than 2 samples has none); render it with more samples";
  }

  // CandidateNoise::neighbourCorrelation. Differences of neighbours leave a smooth bias out, and
  // a bias that changes between them only lowers rho. Over disjoint pairs (in each 2 x 2 cell the
  // two rows or, in every other cell, the two columns), d the difference of the pair's residuals
  // (candidate - reference) and w the sum of their variances (the layers', the reference's, rounding), R,
  // G and B summed: rho = 1 - sum d^2 / sum w, its standard error from the pairs' spread about
  // that ratio.
  void measureNeighbourCorrelation() {
    RatioOfSums pairs, pixels;  // the pairs' d^2 over w; each pixel's r^2 over its variance
    Quad meanA, varianceA, referenceA, referenceVarianceA, meanB, varianceB, referenceB, referenceVarianceB, low, high;
    const auto pair = [&](int x0, int y0, int x1, int y1) {
      if (x1 >= width() || y1 >= height()) return;
      readRounded(x0, y0, meanA, varianceA, referenceA, referenceVarianceA, low, high);
      readRounded(x1, y1, meanB, varianceB, referenceB, referenceVarianceB, low, high);
      double d2 = 0, w = 0, r2[2] = {0, 0}, v[2] = {0, 0};
      for (size_t c = 0; c < 3; ++c) {
        const double ra = meanA[c] - referenceA[c], rb = meanB[c] - referenceB[c], d = ra - rb;
        d2 += d * d, w += varianceA[c] + referenceVarianceA[c] + varianceB[c] + referenceVarianceB[c];
        r2[0] += ra * ra, r2[1] += rb * rb;
        v[0] += varianceA[c] + referenceVarianceA[c], v[1] += varianceB[c] + referenceVarianceB[c];
      }
      if (!(w > 0) || !std::isfinite(d2)) return;
      pairs.add(d2, w);
      for (int i = 0; i < 2; ++i) pixels.add(r2[i], v[i]);
    };
    for (int y = 0; y < height(); y += 2)
      for (int x = 0; x < width(); x += 2)
        if ((x / 2 + y / 2) % 2 == 0) pair(x, y, x + 1, y), pair(x, y + 1, x + 1, y + 1);
        else pair(x, y, x, y + 1), pair(x + 1, y, x + 1, y + 1);
    if (!(pairs.denominator > 0)) return;
    const double q = pairs.ratio(), spread = pairs.spread();
    noise_.neighbourCorrelation = 1 - q;
    noise_.neighbourCorrelationZ = spread > 0 ? (1 - q) / spread : 0.0;
    noise_.neighboursMeasured = true;
    const double rho = noise_.neighbourCorrelation;
    if (neighbourCorrelationShown(noise_) && rho > 0)
      noise_.neighbourInflation = 1 + 24 * rho + fartherNeighbourCorrelation();
    // The pixels' terms as if independent; where neighbours share noise their squares do too, by at
    // most 1 + 24 rho over the 24 pixels within 2 of each. (Not the inflation: layers too large
    // make every lag's rho positive, and its sum would hide them.)
    const double l = pixels.ratio(), levelSpread = pixels.spread() * std::sqrt(1 + 24 * std::max(0.0, rho));
    noise_.layerLevel = l;
    noise_.layerLevelZ = levelSpread > 0 ? (l - 1) / levelSpread : 0.0;
  }

  // CandidateNoise::blockDispersion. Blocks of kDispersionBlock pixels a side (whole ones only),
  // paired two apart (forDisjointPairs: no block is in two pairs). The
  // differences are from the reference times the candidate's scale over the image (per channel, the
  // sum of the candidate over the reference's): a candidate too bright or too dark everywhere (a
  // light's power, an exposure) would otherwise raise the dispersion wherever the image has
  // contrast, and pass for noise shared by its pixels.
  void measureBlockDispersion() {
    constexpr int side = kDispersionBlock;
    const int blocksX = width() / side, blocksY = height() / side;
    // Per block and channel: the candidate's and the reference's sums, and their variances' sum.
    requireMemory(uint64_t(blocksX) * uint64_t(blocksY) * 9 * sizeof(double), "the blocks' dispersion",
                  "compare crops of the images");
    std::vector<std::array<double, 9>> sums(size_t(blocksX) * size_t(blocksY));
    std::array<double, 3> candidateTotal{}, referenceTotal{}, varianceTotal{};
    Quad mean, variance, reference, referenceVariance, low, high;
    for (int y = 0; y < blocksY * side; ++y)
      for (int x = 0; x < blocksX * side; ++x) {
        readRounded(x, y, mean, variance, reference, referenceVariance, low, high);
        auto& b = sums[size_t(y / side) * size_t(blocksX) + size_t(x / side)];
        for (size_t c = 0; c < 3; ++c) {
          b[c] += mean[c], b[3 + c] += reference[c], b[6 + c] += variance[c] + referenceVariance[c];
          candidateTotal[c] += mean[c], referenceTotal[c] += reference[c];
          varianceTotal[c] += variance[c] + referenceVariance[c];
        }
      }
    // The scale where the reference's total stands well above the noise of the two totals (a channel
    // near black, or a pixel filter's negative lobes cancelling, would give it at random).
    std::array<double, 3> scale{1, 1, 1};
    for (size_t c = 0; c < 3; ++c) {
      const double s = candidateTotal[c] / referenceTotal[c];
      if (std::isfinite(s) && candidateTotal[c] > 0 && referenceTotal[c] > 10 * std::sqrt(varianceTotal[c])) scale[c] = s;
    }
    std::vector<double> ratios;
    size_t pairs = 0;
    forDisjointPairs(blocksX, blocksY, 2, [&](int xa, int ya, int xb, int yb) {
      const auto& a = sums[size_t(ya) * size_t(blocksX) + size_t(xa)];
      const auto& b = sums[size_t(yb) * size_t(blocksX) + size_t(xb)];
      bool any = false;
      for (size_t c = 0; c < 3; ++c) {
        const double d = (a[c] - scale[c] * a[3 + c]) - (b[c] - scale[c] * b[3 + c]), w = a[6 + c] + b[6 + c];
        if (!(w > 0) || !std::isfinite(d) || !std::isfinite(w)) continue;
        ratios.push_back(d * d / w);
        any = true;
      }
      pairs += any;
    });
    if (pairs < size_t(kDispersionPairs)) return;  // fewer stray too far (docs/validation.md)
    const auto middle = ratios.begin() + std::ptrdiff_t(ratios.size() / 2);
    std::nth_element(ratios.begin(), middle, ratios.end());
    // chi-square with 1 degree of freedom: median 0.454936, density there 0.471136; the sample
    // median's standard error 1 / (2 f sqrt(n)), n the pairs.
    constexpr double kChiSquareMedian = 0.454936, kDensityAtMedian = 0.471136;
    noise_.blockDispersion = *middle / kChiSquareMedian;
    const double se = 1 / (2 * kDensityAtMedian * std::sqrt(double(pairs))) / kChiSquareMedian;
    noise_.blockDispersionZ = (noise_.blockDispersion - 1) / se;
    // The median's relative standard error is the same whatever the factor k: the estimate lies
    // within k (1 +- 2 se), so k within estimate / (1 +- 2 se).
    noise_.blockDispersionLow = noise_.blockDispersion / (1 + 2 * se);
    noise_.blockDispersionHigh = 2 * se < 1 ? noise_.blockDispersion / (1 - 2 * se) : kInfinity;
    noise_.blockDispersionMeasured = true;
  }

  // CandidateNoise::neighbourInflation beyond 2 pixels: for each lag k from 3 to 8, the correlation
  // rho_k of pixels k apart along a row or a column (as rho, over forDisjointPairs), 8 k rho_k for
  // the 8 k pixels at that distance, while rho_k is shown at z 2. A separable filter of no negative
  // lobes correlates pixels most along the axes at a given distance, so the sum bounds theirs.
  double fartherNeighbourCorrelation() {
    constexpr int kFarthest = 8;
    const int w = width(), h = height();
    // R, G, B and the variances' sum, in floats: as large as a colour image, not twice.
    requireMemory(uint64_t(w) * uint64_t(h) * 4 * sizeof(float), "the neighbours' correlation",
                  "compare crops of the images");
    std::vector<std::array<float, 4>> residuals(size_t(w) * size_t(h));
    Quad mean, variance, reference, referenceVariance, low, high;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        readRounded(x, y, mean, variance, reference, referenceVariance, low, high);
        auto& r = residuals[size_t(y) * size_t(w) + size_t(x)];
        r = {float(mean[0] - reference[0]), float(mean[1] - reference[1]), float(mean[2] - reference[2]),
             float(variance[0] + referenceVariance[0] + variance[1] + referenceVariance[1] + variance[2] +
                   referenceVariance[2])};
      }
    double added = 0;
    for (int k = 3; k <= kFarthest; ++k) {
      RatioOfSums pairs;
      forDisjointPairs(w, h, k, [&](int xa, int ya, int xb, int yb) {
        const auto& a = residuals[size_t(ya) * size_t(w) + size_t(xa)];
        const auto& b = residuals[size_t(yb) * size_t(w) + size_t(xb)];
        double d2 = 0;
        for (size_t c = 0; c < 3; ++c) {
          const double d = double(a[c]) - double(b[c]);
          d2 += d * d;
        }
        const double v = double(a[3]) + double(b[3]);  // infinite where a float overflowed: left out
        if (v > 0 && std::isfinite(v) && std::isfinite(d2)) pairs.add(d2, v);
      });
      if (!(pairs.denominator > 0)) break;
      const double rho = 1 - pairs.ratio(), se = pairs.spread();
      if (!(rho >= 2 * se) || !(rho > 0)) break;
      added += 8 * k * rho;
    }
    return added;
  }

  // The runs' mean at the pixel last read, and the variance of that mean from their spread.
  void spreadOfRuns(Quad& mean, Quad& variance) const {
    const size_t n = values_.size();
    for (size_t c = 0; c < 4; ++c) {
      double m = 0;
      for (size_t i = 0; i < n; ++i) m += values_[i][c];
      m /= double(n);
      double squares = 0;
      for (size_t i = 0; i < n; ++i) squares += (values_[i][c] - m) * (values_[i][c] - m);
      mean[c] = m;
      variance[c] = squares / double(n - 1) / double(n);
    }
  }

  // A pixel's variance from a few samples or runs of a heavy-tailed estimator is mostly too small
  // (they missed its rare large values) and now and then far too large: a block whose pixels all
  // missed them looks both dark and quiet, and would be rejected (2 to 8 runs of a Pareto-tailed
  // estimator: 12-16% false rejections at alpha 0.05; one image with its 4 samples' variance as
  // layers: 77%). So each pixel's variance is at least the reference's (whose many samples see the
  // tail) times the ratio of the two over the image (the sum of the candidate's pixel variances over
  // the reference's, where the reference has noise); but that ratio counts at most kFloorOverMedian
  // times its median over the grid's tiles, so that one firefly (one pixel far brighter than the
  // rest) cannot raise every pixel's variance and hide a bias anywhere, and at most kFloorOverTile
  // times the pixel's own tile's, so that where a candidate is legitimately quieter than elsewhere
  // (adaptive sampling, another renderer's better strategy there) a bias is not hidden either.
  void floorPixelVariances() {
    constexpr double kFloorOverMedian = 4, kFloorOverTile = 4;
    Quad mean, variance, reference, referenceVariance, spreads{}, references{};
    std::vector<Quad> tileSpreads(size_t(tiles_) * size_t(tiles_)), tileReferences = tileSpreads;
    for (int y = 0; y < height(); ++y)
      for (int x = 0; x < width(); ++x) {
        read(x, y, mean, variance, reference, referenceVariance);
        const size_t tile = tileOf(x, y, tiles_, width(), height()) - 1;
        for (size_t c = 0; c < 4; ++c) {
          if (!(referenceVariance[c] > 0) || !std::isfinite(variance[c])) continue;  // no floor to set there
          spreads[c] += variance[c], references[c] += referenceVariance[c];
          tileSpreads[tile][c] += variance[c], tileReferences[tile][c] += referenceVariance[c];
        }
      }
    floors_.assign(tileSpreads.size(), Quad{});
    for (size_t c = 0; c < 4; ++c) {
      std::vector<double> ratios;
      for (size_t k = 0; k < tileSpreads.size(); ++k)
        if (tileReferences[k][c] > 0) ratios.push_back(tileSpreads[k][c] / tileReferences[k][c]);
      if (ratios.empty()) continue;
      std::sort(ratios.begin(), ratios.end());
      const size_t middle = ratios.size() / 2;
      const double median = ratios.size() % 2 ? ratios[middle] : 0.5 * (ratios[middle - 1] + ratios[middle]);
      const double image = std::min(spreads[c] / references[c], kFloorOverMedian * median);
      for (size_t k = 0; k < tileSpreads.size(); ++k)
        if (tileReferences[k][c] > 0)
          floors_[k][c] = std::min(image, kFloorOverTile * tileSpreads[k][c] / tileReferences[k][c]);
    }
    if (noise_.source == NoiseSource::Runs && spreads[kSum] == 0 && references[kSum] > 0 && noise_.undecided.empty())
      noise_.undecided = "the runs are the same image, pixel for pixel, so their spread says nothing of their noise "
                         "(rendered with one seed?): give runs rendered with different seeds";
  }

  struct Channels {
    std::array<int, 3> value, variance;
  };
  struct RoundingShare {
    StoredRounding rounding;
    double share = 0;  // of the runs
  };
  const Candidate& candidate_;
  std::vector<RoundingShare> roundings_;
  const Image& reference_;
  std::array<int, 3> referenceValue_{}, referenceVariance_{};
  std::vector<Channels> runs_;
  std::vector<Quad> values_;
  int tiles_;
  std::vector<Quad> floors_;  // per tile: the least ratio of a pixel's variance to the reference's
  CandidateNoise noise_;
};

// The sums over a set of pixels (a block, a region, the image) that the tests need.
struct UnitSums {
  Quad difference{}, reference{}, candidate{}, pixelVariance{}, referenceVariance{};
  Quad low{}, high{};  // how far below and above the true difference truncation may put it
  std::vector<Quad> runs;  // each run's sum, where there are runs

  void add(const Quad& mean, const Quad& variance, const Quad& ref, const Quad& refVariance, const std::vector<Quad>& values,
           const Quad& lowBy = {}, const Quad& highBy = {}) {
    for (size_t c = 0; c < 4; ++c) {
      low[c] += lowBy[c], high[c] += highBy[c];
      difference[c] += mean[c] - ref[c];
      reference[c] += ref[c];
      candidate[c] += mean[c];
      pixelVariance[c] += variance[c];
      referenceVariance[c] += refVariance[c];
    }
    if (values.size() < 2) return;
    runs.resize(values.size());
    for (size_t i = 0; i < values.size(); ++i)
      for (size_t c = 0; c < 4; ++c) runs[i][c] += values[i][c];
  }
  // The variance of the runs' mean sum from the runs' spread (0 without runs).
  double spread(size_t c) const {
    const size_t n = runs.size();
    if (n < 2) return 0;
    double m = 0;
    for (const Quad& r : runs) m += r[c];
    m /= double(n);
    double squares = 0;
    for (const Quad& r : runs) squares += (r[c] - m) * (r[c] - m);
    return squares / double(n - 1) / double(n);
  }
};

// What a block keeps for the test once its pixels are summed.
struct BlockSums {
  std::array<double, 3> difference{}, pixelVariance{}, referenceVariance{}, spread{};
};

// A sum's difference nearest 0 that truncation (UnitSums::low, high) allows: the stored difference
// may lie up to `low` below the true one and `high` above it.
double allowedDifference(double difference, double low, double high) {
  return difference - std::clamp(difference, -low, high);
}

// The region a tile index stands for: 0 the whole image, k > 0 the grid's tile k - 1, row by row.
void regionBounds(size_t k, int tiles, int w, int h, int& x0, int& y0, int& x1, int& y1) {
  if (k == 0) {
    x0 = 0, y0 = 0, x1 = w, y1 = h;
    return;
  }
  // tileOf puts pixel x in tile floor(x tiles / w): tile t holds x from ceil(t w / tiles) on.
  const int tx = int(k - 1) % tiles, ty = int(k - 1) / tiles;
  const auto start = [tiles](int t, int size) { return int((int64_t(t) * size + tiles - 1) / tiles); };
  x0 = start(tx, w), y0 = start(ty, h), x1 = start(tx + 1, w), y1 = start(ty + 1, h);
}

// Sums every pixel into the regions (the whole image, then the tiles) and, with block > 0, into
// blocks of block x block pixels (row by row).
void sumImage(TestPixels& pixels, int tiles, int block, std::vector<UnitSums>& regions, std::vector<BlockSums>& blocks) {
  const int w = pixels.width(), h = pixels.height();
  regions.assign(size_t(1 + tiles * tiles), UnitSums{});
  const int side = block > 0 ? block : std::max(w, h);
  const int blocksX = (w + side - 1) / side, blocksY = (h + side - 1) / side;
  if (block > 0) {
    requireMemory(uint64_t(blocksX) * uint64_t(blocksY) * sizeof(BlockSums), "the test's blocks",
                  "use larger blocks (--block) or raise --memory-limit");
    blocks.assign(size_t(blocksX) * size_t(blocksY), BlockSums{});
  }
  Quad mean, variance, reference, referenceVariance, low, high;
  for (int by = 0; by < blocksY; ++by)
    for (int bx = 0; bx < blocksX; ++bx) {
      UnitSums sums;
      const int x0 = bx * side, y0 = by * side, x1 = std::min(w, x0 + side), y1 = std::min(h, y0 + side);
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          pixels.readRounded(x, y, mean, variance, reference, referenceVariance, low, high);
          for (UnitSums* s : {&regions[0], &regions[tileOf(x, y, tiles, w, h)], &sums})
            s->add(mean, variance, reference, referenceVariance, pixels.values(), low, high);
        }
      if (block <= 0) continue;
      BlockSums& b = blocks[size_t(by) * size_t(blocksX) + size_t(bx)];
      for (size_t c = 0; c < 3; ++c) {
        b.difference[c] = allowedDifference(sums.difference[c], sums.low[c], sums.high[c]);
        b.pixelVariance[c] = sums.pixelVariance[c];
        b.referenceVariance[c] = sums.referenceVariance[c], b.spread[c] = sums.spread(c);
      }
    }
}

// A scale's correlation factor, pooled over its units and the given channels, and its degrees of
// freedom (see noise_tests.h). Without runs: 1, and infinite degrees of freedom.
CandidateNoise::Scale poolScale(const std::string& name, double spread, double pixelVariance, size_t units, int runs) {
  CandidateNoise::Scale scale{name, 1.0, kInfinity};
  if (runs < 2) return scale;
  scale.correlation = pixelVariance > 0 ? spread / pixelVariance : 1.0;
  scale.degreesOfFreedom = double(runs - 1) * double(units);
  return scale;
}

double candidateVariance(NoiseSource source, const CandidateNoise::Scale& scale, double pixelVariance, double spread) {
  switch (source) {
    case NoiseSource::Runs: return std::max(scale.correlation * pixelVariance, spread);
    case NoiseSource::VarianceLayer: return pixelVariance;
    case NoiseSource::Unknown: return 0;
  }
  return 0;
}

// The degrees of freedom of a variance `total` of which `candidate` was estimated with `dof`
// (Welch-Satterthwaite; the reference's share counts as known).
double welchDegreesOfFreedom(double candidate, double total, double dof) {
  if (!(candidate > 0) || !std::isfinite(dof)) return kInfinity;
  return dof * (total / candidate) * (total / candidate);
}

// A set of pixels' relative difference d = C / R - 1 in channel `channel` (kSum: over R + G + B),
// and its (1 - 2 alpha) interval d +- q se, var(d) = var(C) / R^2 + C^2 var(R) / R^4 (the delta
// method), both variances `inflation` times as large; R > 0.
struct RelativeInterval {
  double difference = 0, low = 0, high = 0;
  double candidateHalfWidth = 0;  // the candidate's noise's share of the half width
};
RelativeInterval relativeInterval(const UnitSums& s, size_t channel, NoiseSource source, const CandidateNoise::Scale& scale,
                                  double alpha, double inflation) {
  const double c = s.candidate[channel], r = s.reference[channel];
  const double ratio = c / r;
  const double cv = inflation * candidateVariance(source, scale, s.pixelVariance[channel], s.spread(channel));
  const double total = cv + inflation * ratio * ratio * s.referenceVariance[channel];
  const double se = std::sqrt(total) / r;
  const double q = studentTwoSidedQuantile(2 * alpha, welchDegreesOfFreedom(cv, total, scale.degreesOfFreedom));
  // The true difference lies up to `high` below the stored one and `low` above it (truncation).
  return {ratio - 1, ratio - 1 - q * se - s.high[channel] / r, ratio - 1 + q * se + s.low[channel] / r,
          q * std::sqrt(cv) / r};
}

// The correlation of the noise of sums of regions' size over their pixels' own (see noise_tests.h),
// pooled over a grid x grid of tiles, and of the image.
std::array<CandidateNoise::Scale, 2> regionScales(const std::vector<UnitSums>& regions, int runs) {
  double tileSpread = 0, tilePixels = 0, imageSpread = 0, imagePixels = 0;
  for (size_t c = 0; c < 3; ++c) {
    for (size_t k = 1; k < regions.size(); ++k) tileSpread += regions[k].spread(c), tilePixels += regions[k].pixelVariance[c];
    imageSpread += regions[0].spread(c), imagePixels += regions[0].pixelVariance[c];
  }
  return {poolScale("regions", tileSpread, tilePixels, regions.size() - 1, runs),
          poolScale("image", imageSpread, imagePixels, 1, runs)};
}

double statistic(double difference, double variance) {
  if (!std::isfinite(difference)) return difference;  // a candidate's NaN or infinity: no noise explains it
  if (variance > 0) return difference / std::sqrt(variance);
  return difference == 0 ? 0.0 : std::copysign(kInfinity, difference);
}

// Whether blocks' sums are shown to vary more than the layers and the neighbours' correlation say
// (CandidateNoise::blockDispersion): noise shared farther than neighbours.
bool sharedFartherShown(const CandidateNoise& noise) {
  return noise.source == NoiseSource::VarianceLayer && noise.blockDispersionMeasured &&
         !neighbourCorrelationShown(noise) && noise.blockDispersion >= kBlockDispersion && noise.blockDispersionLow > 1;
}

// A verdict from variance layers, where the differences from the reference say the layers do not
// describe the noise (CandidateNoise: neighbours correlated, noise shared farther, or the layers
// above the differences' spread): what the layers cannot support becomes inconclusive, saying why.
// `intervals`: --within's, which positive correlation narrows. `failsInflated(k, blocksOnly)`:
// whether --test still fails with every variance k times as large (counting only the blocks);
// correlated neighbours raise a sum's variance at most CandidateNoise::neighbourInflation times, so
// a failure beyond that stands; where noise is shared farther, a block's failure beyond the blocks'
// dispersion.
Verdict throughNeighbours(CandidateNoise& noise, Verdict verdict, bool intervals,
                          const std::function<bool(double, bool)>& failsInflated = {}) {
  if (noise.source != NoiseSource::VarianceLayer || !noise.neighboursMeasured || verdict == Verdict::Inconclusive)
    return verdict;
  if (sharedFartherShown(noise) && (intervals || verdict == Verdict::Fail) &&
      !(!intervals && failsInflated && failsInflated(noise.blockDispersionHigh, true))) {
    std::ostringstream why;
    why << std::setprecision(2) << "blocks of " << kDispersionBlock << " x " << kDispersionBlock
        << " pixels differ from the reference by more than their variance layers tell, beyond what neighbouring "
           "pixels' correlation explains (their sums vary "
        << noise.blockDispersion << " times as much, z " << std::setprecision(3) << noise.blockDispersionZ
        << "): noise is shared over more than a few pixels (random numbers shared by tiles of pixels), which "
           "variance layers cannot say, so "
        << (intervals ? "the intervals are too narrow" : "the failure may be noise")
        << ": give two or more runs (renders with other seeds)";
    noise.undecided = why.str();
    return Verdict::Inconclusive;
  }
  const double rho = noise.neighbourCorrelation;
  const bool shown = neighbourCorrelationShown(noise);
  // Squared differences below the layers' sum (a bias only raises them): the layers are too large,
  // which also shows as rho > 0.
  const bool overstated = noise.layerLevel <= 1 - kNeighbourCorrelation && noise.layerLevelZ <= -kNeighbourCorrelationZ;
  const bool more = shown && rho > 0 && !overstated, less = (shown && rho < 0) || overstated;
  std::ostringstream why;
  why << std::setprecision(2);
  if (intervals ? more : verdict == Verdict::Fail ? more && !(failsInflated && failsInflated(noise.neighbourInflation, false))
                                                  : less) {
    if (overstated)
      why << "the variance layers are larger than the differences from the reference say (their squares sum to "
          << noise.layerLevel << " of the layers', z " << std::setprecision(3) << noise.layerLevelZ
          << "), so a bias may hide in noise the image does not have";
    else
      why << "neighbouring pixels' differences from the reference are " << (more ? "correlated" : "anticorrelated")
          << " (rho " << rho << ", z " << std::setprecision(3) << noise.neighbourCorrelationZ
          << "), which variance layers cannot say: sums of pixels vary "
          << (more ? "more than the layers tell (a pixel filter that splats samples into several pixels, random "
                     "numbers shared by pixels), so "
                   : "less than the layers tell (blue-noise sampling), so ")
          << (intervals ? "the intervals are too narrow" : more ? "the failure may be noise" : "a bias may hide in the noise they claim");
    noise.undecided = why.str() + ": give two or more runs (renders with other seeds)";
    return Verdict::Inconclusive;
  }
  return verdict;
}

}  // namespace

Image candidateImage(const Candidate& candidate) {
  if (candidate.runs.empty()) throw std::invalid_argument("no image to compare");
  if (candidate.runs.size() == 1) return candidate.runs[0];
  const Image& first = candidate.runs[0];
  Image mean(first.width(), first.height(), {"R", "G", "B"});
  for (size_t i = 0; i < candidate.runs.size(); ++i) {
    const Image& run = candidate.runs[i];
    requireSameSize(run, first);
    const std::array<int, 3> at = rgbIndices(run, "", "run " + std::to_string(i + 1));
    for (int y = 0; y < run.height(); ++y)
      for (int x = 0; x < run.width(); ++x)
        for (int c = 0; c < 3; ++c) mean.at(x, y, c) += run.at(x, y, at[size_t(c)]) / float(candidate.runs.size());
  }
  return mean;
}

NoiseTest testWithinNoise(const Candidate& candidate, const Image& reference, double alpha, int grid, int block) {
  if (!(alpha > 0 && alpha < 1)) throw std::invalid_argument("the significance must be in (0, 1)");
  if (block < 1) throw std::invalid_argument("the block side must be at least 1 pixel");
  const int tiles = std::max(1, grid);
  TestPixels pixels(candidate, reference, tiles);
  NoiseTest t;
  t.alpha = alpha;
  t.block = block;
  const int w = pixels.width(), h = pixels.height();
  const int blocksX = (w + block - 1) / block;
  std::vector<UnitSums> regions;
  std::vector<BlockSums> blocks;
  sumImage(pixels, tiles, block, regions, blocks);
  t.pixels = uint64_t(w) * uint64_t(h);
  t.blocks = blocks.size();
  CandidateNoise& noise = pixels.noise();
  const int runs = noise.runs;
  double blockSpread = 0, blockPixels = 0;
  for (const BlockSums& b : blocks)
    for (size_t c = 0; c < 3; ++c) blockSpread += b.spread[c], blockPixels += b.pixelVariance[c];
  const auto scales = regionScales(regions, runs);
  noise.scales = {poolScale("blocks", blockSpread, blockPixels, blocks.size(), runs), scales[0], scales[1]};

  t.statistic = Image(w, h, {"z"});
  double largestBlockZ = 0, largestRegionZ = 0;  // |z|, for failures with inflated variances
  bool nonFinite = false;  // a NaN z (a candidate's NaN): a failure no inflation undoes
  const double blockThreshold = alpha / (2.0 * 3.0 * double(t.blocks));
  for (size_t k = 0; k < blocks.size(); ++k) {
    const BlockSums& b = blocks[k];
    double largest = 0, minP = 1;
    for (size_t c = 0; c < 3; ++c) {
      const double cv = candidateVariance(noise.source, noise.scales[0], b.pixelVariance[c], b.spread[c]);
      const double total = cv + b.referenceVariance[c];
      const double z = statistic(b.difference[c], total);
      largest = std::max(largest, std::abs(z));
      nonFinite = nonFinite || std::isnan(z);
      minP = std::min(minP, studentTwoSidedP(z, welchDegreesOfFreedom(cv, total, noise.scales[0].degreesOfFreedom)));
    }
    const int x0 = int(k % size_t(blocksX)) * block, y0 = int(k / size_t(blocksX)) * block;
    for (int y = y0; y < std::min(h, y0 + block); ++y)
      for (int x = x0; x < std::min(w, x0 + block); ++x) t.statistic.at(x, y, 0) = float(largest);
    if (minP < t.minBlockPValue) t.minBlockPValue = minP, t.minBlockX = x0, t.minBlockY = y0;
    largestBlockZ = std::max(largestBlockZ, largest);
    t.blocksRejectedAtAlpha += std::min(1.0, 3.0 * minP) < alpha;
    t.blocksRejected += minP < blockThreshold;
  }
  const double regionThreshold = alpha / (2.0 * 3.0 * double(regions.size()));
  bool rejected = t.blocksRejected > 0;
  for (size_t k = 0; k < regions.size(); ++k) {
    const CandidateNoise::Scale& scale = noise.scales[k == 0 ? 2 : 1];
    RegionTest r;
    regionBounds(k, tiles, w, h, r.x0, r.y0, r.x1, r.y1);
    const UnitSums& s = regions[k];
    for (size_t c = 0; c < 3; ++c) {
      const double cv = candidateVariance(noise.source, scale, s.pixelVariance[c], s.spread(c));
      const double total = cv + s.referenceVariance[c];
      const double z = statistic(allowedDifference(s.difference[c], s.low[c], s.high[c]), total);
      const double p = studentTwoSidedP(z, welchDegreesOfFreedom(cv, total, scale.degreesOfFreedom));
      // The channel of the least p-value; of those with equal ones (0 beyond |z| 38), the largest |z|.
      if (p < r.pValue || (p == r.pValue && std::abs(z) > std::abs(r.z))) r.pValue = p, r.z = z, r.channel = int(c);
    }
    r.relativeDifference = s.reference[kSum] != 0 ? s.difference[kSum] / s.reference[kSum] : 0;
    const size_t tested = size_t(r.channel);
    r.channelDifference = s.reference[tested] != 0 ? s.difference[tested] / s.reference[tested] : 0;
    r.rejected = r.pValue < regionThreshold;
    largestRegionZ = std::max(largestRegionZ, std::abs(r.z));
    nonFinite = nonFinite || std::isnan(r.z);
    rejected = rejected || r.rejected;
    t.regions.push_back(r);
  }
  t.verdict = !noise.undecided.empty() ? Verdict::Inconclusive : rejected ? Verdict::Fail : Verdict::Pass;
  // With variance layers p-values are normal: a failure stands with variances k times as large
  // where a |z| / sqrt(k) is still rejected.
  // The blocks' dispersion is measured over blocks of kDispersionBlock pixels: larger ones may vary more.
  const auto failsInflated = [&](double k, bool blocksOnly) {
    if (nonFinite) return true;
    if (blocksOnly && block > kDispersionBlock) return false;
    return studentTwoSidedP(largestBlockZ / std::sqrt(k), kInfinity) < blockThreshold ||
           (!blocksOnly && studentTwoSidedP(largestRegionZ / std::sqrt(k), kInfinity) < regionThreshold);
  };
  t.verdict = throughNeighbours(noise, t.verdict, false, failsInflated);
  t.noise = noise;
  return t;
}

EquivalenceTest testEquivalence(const Candidate& candidate, const Image& reference, double within, double alpha, int grid) {
  if (!(alpha > 0 && alpha < 0.5)) throw std::invalid_argument("the significance must be in (0, 0.5)");
  if (!(within > 0) || !std::isfinite(within)) throw std::invalid_argument("the equivalence margin must be positive");
  const int tiles = std::max(1, grid);
  TestPixels pixels(candidate, reference, tiles);
  EquivalenceTest t;
  t.within = within;
  t.alpha = alpha;
  const int w = pixels.width(), h = pixels.height();
  std::vector<UnitSums> regions;
  std::vector<BlockSums> noBlocks;
  sumImage(pixels, tiles, 0, regions, noBlocks);
  CandidateNoise& noise = pixels.noise();
  const auto scales = regionScales(regions, noise.runs);
  noise.scales = {scales[0], scales[1]};
  t.verdict = Verdict::Pass;
  // A pass needs every interval inside the margin, so each at level alpha keeps the pass's at
  // alpha; a failure needs only one outside it, on either side, so each side of each is tested at
  // alpha over their number.
  const double failAlpha = alpha / (2.0 * 3.0 * double(regions.size()));
  bool negativeReference = false;  // a region's reference sum is negative in a channel
  for (size_t k = 0; k < regions.size(); ++k) {
    const CandidateNoise::Scale& scale = noise.scales[k == 0 ? 1 : 0];
    const UnitSums& s = regions[k];
    // Each channel within the margin: a shift of colour (red up, blue down) is a difference even
    // where R + G + B keeps its sum. The region is reported by its deciding channel: the one of the
    // worst verdict, of those the one whose interval reaches farthest from 0.
    EquivalenceRegion e;
    for (size_t c = 0; c < 3; ++c) {
      EquivalenceRegion channel;
      channel.channel = int(c);
      const double r = s.reference[c];
      if (r > 0) {
        const RelativeInterval interval = relativeInterval(s, c, noise.source, scale, alpha, 1.0);
        const RelativeInterval failing = relativeInterval(s, c, noise.source, scale, failAlpha, 1.0);
        channel.relativeDifference = interval.difference;
        channel.low = interval.low, channel.high = interval.high;
        if (!std::isfinite(channel.high - channel.low)) channel.verdict = Verdict::Inconclusive;
        else if (channel.low > -within && channel.high < within) channel.verdict = Verdict::Pass;
        else if (failing.low >= within || failing.high <= -within) channel.verdict = Verdict::Fail;
        else {
          channel.verdict = Verdict::Inconclusive;
          // The candidate's share of the interval must narrow to the margin between d and +-D (the
          // failing interval's where d lies beyond it).
          const double margin = std::abs(std::abs(channel.relativeDifference) - within);
          const double halfWidth = std::abs(channel.relativeDifference) > within ? failing.candidateHalfWidth
                                                                                   : interval.candidateHalfWidth;
          t.samplesToDecide = std::max(t.samplesToDecide, margin > 0 ? std::pow(halfWidth / margin, 2) : kInfinity);
        }
      } else if (r == 0) {
        // A black reference region: equivalent only to a black candidate.
        channel.verdict = s.candidate[c] == 0 ? Verdict::Pass : Verdict::Fail;
      } else {
        // Negative (a pixel filter's negative lobes over a dark region): no relative difference.
        channel.verdict = Verdict::Inconclusive;
        negativeReference = true;
      }
      const auto rank = [](Verdict v) { return v == Verdict::Fail ? 2 : v == Verdict::Inconclusive ? 1 : 0; };
      const auto reach = [](const EquivalenceRegion& x) { return std::max(std::abs(x.low), std::abs(x.high)); };
      if (c == 0 || rank(channel.verdict) > rank(e.verdict) ||
          (rank(channel.verdict) == rank(e.verdict) && reach(channel) > reach(e)))
        e = channel;
    }
    regionBounds(k, tiles, w, h, e.x0, e.y0, e.x1, e.y1);
    t.verdict = combineVerdicts(t.verdict, e.verdict);
    t.regions.push_back(e);
  }
  if (!noise.undecided.empty()) t.verdict = Verdict::Inconclusive;
  else if (t.verdict != Verdict::Inconclusive) t.verdict = throughNeighbours(noise, t.verdict, true);
  else if (negativeReference)
    noise.undecided = "a region's reference sum is negative in a channel (a pixel filter's negative lobes over a dark "
                      "region), so it has no relative difference there: compare with a pixel filter of no negative lobes";
  else if (CandidateNoise correlated = noise; throughNeighbours(correlated, Verdict::Pass, true) == Verdict::Inconclusive) {
    noise.undecided = correlated.undecided;  // more samples would not widen the intervals: runs decide
    t.samplesToDecide = 0;
  }
  else {
    std::ostringstream why;
    why << "an interval reaches across +-" << within << ": ";
    if (std::isfinite(t.samplesToDecide) && t.samplesToDecide < 1e9)
      why << "about " << std::ceil(t.samplesToDecide) << " times the candidate's samples (or runs) would decide it";
    else
      why << "its difference lies on the margin itself; no number of samples would decide it";
    noise.undecided = why.str();
  }
  t.noise = noise;
  return t;
}

const char* surfaceKindName(SurfaceDifference::Kind kind) {
  switch (kind) {
    case SurfaceDifference::Kind::Material: return "material";
    case SurfaceDifference::Kind::Background: return "background";
    case SurfaceDifference::Kind::Emitters: return "emitters";
    case SurfaceDifference::Kind::NonEmitters: return "non_emitters";
  }
  return "";
}

std::vector<SurfaceDifference> differenceBySurface(const Candidate& candidate, const Image& reference,
                                                   const std::vector<std::string>& materialNames, double alpha) {
  if (!(alpha > 0 && alpha < 0.5)) throw std::invalid_argument("the significance must be in (0, 0.5)");
  const int materialAt = reference.channelIndex("surface.material"), emitterAt = reference.channelIndex("surface.emitter");
  if (materialAt < 0 || emitterAt < 0) return {};
  TestPixels pixels(candidate, reference, kRegionGrid);
  const int w = pixels.width(), h = pixels.height();
  const CandidateNoise& noise = pixels.noise();
  // With runs, each surface's sum by its own spread (Student's t, n - 1 degrees of freedom): its
  // pixels lie all over the image, and noise shared over long ranges (a per-run offset, a random
  // sequence shared by every pixel) makes their sums vary more than a pool over tiles would say.
  // With variance layers whose neighbours' differences are shown correlated, by variances (the
  // candidate's and the reference's) CandidateNoise::neighbourInflation times as large, as a
  // failure of --test must survive: intervals wide enough to locate a gross error.
  const double inflation = noise.neighbourInflation;
  const CandidateNoise::Scale scale = noise.source == NoiseSource::Runs
                                          ? CandidateNoise::Scale{"surfaces", 0.0, double(noise.runs - 1)}
                                          : CandidateNoise::Scale{"surfaces", 1.0, kInfinity};
  // Units: the materials present by index (those the names do not reach named by their index),
  // then the background, the emitters, all but the emitters: keys past any material index.
  constexpr uint64_t kBackground = uint64_t(1) << 32, kEmitters = kBackground + 1, kNonEmitters = kBackground + 2;
  std::map<uint64_t, std::pair<UnitSums, uint64_t>> units;  // and each one's pixels
  Quad mean, variance, value, referenceVariance, low, high;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float material = reference.at(x, y, materialAt);
      const bool emits = reference.at(x, y, emitterAt) != 0;
      pixels.readRounded(x, y, mean, variance, value, referenceVariance, low, high);
      auto add = [&](uint64_t unit) {
        auto& [sums, count] = units[unit];
        sums.add(mean, variance, value, referenceVariance, pixels.values(), low, high);
        ++count;
      };
      // A value that is no material index (another renderer's IDs, a pixel not traced) counts
      // only as an emitter or not.
      if (material >= 0 && material < 4294967296.0f && material == std::floor(material)) add(uint64_t(material));
      if (material == -1) add(kBackground);
      add(emits ? kEmitters : kNonEmitters);
    }
  std::vector<SurfaceDifference> out;
  for (const auto& [unit, entry] : units) {
    const auto& [s, count] = entry;
    SurfaceDifference d;
    d.pixels = count;
    if (unit < kBackground) {
      d.kind = SurfaceDifference::Kind::Material, d.material = int64_t(unit);
      d.name = unit < materialNames.size() ? materialNames[unit] : "material " + std::to_string(unit);
    } else if (unit == kBackground) {
      d.kind = SurfaceDifference::Kind::Background, d.name = "background";
    } else if (unit == kEmitters) {
      d.kind = SurfaceDifference::Kind::Emitters, d.name = "emitters";
    } else {
      d.kind = SurfaceDifference::Kind::NonEmitters, d.name = "all but emitters";
    }
    if (s.reference[kSum] > 0) {
      const RelativeInterval interval = relativeInterval(s, kSum, noise.source, scale, alpha, inflation);
      d.relativeDifference = interval.difference, d.low = interval.low, d.high = interval.high;
    } else {
      // A black reference: no relative difference, only none or some light.
      d.relativeDifference = s.candidate[kSum] == 0 ? 0.0 : kInfinity, d.low = d.high = d.relativeDifference;
    }
    // No interval where the noise tests are undecided (no noise known, a lossy file, a variance
    // unknown somewhere).
    if (!noise.undecided.empty()) d.low = d.high = std::numeric_limits<double>::quiet_NaN();
    out.push_back(d);
  }
  return out;
}

}  // namespace lucent
