// The statistical verdicts of lucent compare and report: whether a candidate differs from a
// reference by more than their noise (--test), and whether it lies within +-D of it (--within).
//
// The candidate's noise is known in one of two ways. One image carries it in its variance layers
// (variance.R, .G, .B: the variance of each pixel's mean, as render --variance writes), which
// count pixels as independent. Two or more runs (independent renders of the same thing with other
// seeds) carry it in their spread, which holds for noise correlated between pixels (another
// renderer's shared random sequences, its pixel filter) and for biased methods. One image without
// variance layers, or with layers stored as half floats (whose small values become 0), leaves it
// unknown: the verdict is then inconclusive, never pass or fail.
//
// With runs, the variance of a sum over pixels (a block, a region, the image) is taken from the
// spread of the runs' sums. n runs give each sum's spread n - 1 degrees of freedom, too few to
// find a bias of a few percent, so the spread is pooled over the sums of one size: the
// correlation factor kappa = sum_k spread_k / sum_k v_k, v_k the sum of the pixels' own variances
// (from the runs' spread per pixel), is shared by the blocks (and by the 4 x 4 regions), with
// (n - 1) x (their count) degrees of freedom, and a sum's variance is max(kappa v_k, spread_k): the
// pooled model where it holds, the sum's own spread where it is larger (kappa not uniform over the
// image). The image as a whole is one sum: its own spread, n - 1 degrees of freedom, Student's t.
// Where the reference's variance adds in, the degrees of freedom are Welch-Satterthwaite's.
#pragma once
#include <cstdint>
#include <string>
#include <vector>
#include <utility>

#include "lucent/image/image.h"

namespace lucent {

enum class Verdict { Pass, Fail, Inconclusive };
// "pass", "fail", "inconclusive".
const char* verdictName(Verdict verdict);
// The exit status of compare for a verdict: 0 pass, 1 fail, 3 inconclusive (2 is bad input).
int verdictExitStatus(Verdict verdict);
// The verdict of two verdicts together: fail over inconclusive over pass.
Verdict combineVerdicts(Verdict a, Verdict b);

// How much the noise tests allow for the rounding of stored R, G, B values, by the file's encoding.
// Floats round to the nearest: a half float's unit roundoff (and half its smallest subnormal,
// 2^-25, below 2^-14), and for 32-bit floats sixteen units, room for the rounding of the few dozen
// operations by which two renderers may compute one value (an emitter's radiance seen directly,
// which has no noise). Where neither image has noise a difference within the two values'
// allowances counts as none; elsewhere it counts as noise, uniform over +-m (variance m^2 / 3).
// Integer codes and RGBE may be truncated (stb_image_write's RGBE and many renderers' 8-bit
// writers truncate; stb's and OpenImageIO's RGBE readers add no half step): a value stored up to
// one step of its code low (for RGBE, 2^(e-8) under the largest channel's exponent e), or half a
// step high where it was rounded. That is a bias of one sign that sums over pixels, so each sum
// the tests take (a block, a region) may lie below the true one by its pixels' steps and above it
// by their half steps. A lossy encoding (JPEG; EXR's DWA and B44 compressions) changes values by
// more than any noise: the verdict is then inconclusive.
constexpr double kHalfRounding = 0x1p-11, kFloatRounding = 0x1p-20;
struct StoredRounding {
  ColourEncoding encoding = ColourEncoding::Float;
  bool srgb = false;       // integer codes of sRGB-encoded values
  double largestCode = 0;  // integer codes: the largest, which reads as 1 (ImageHeader::largestCode)
};
// How a file's R, G, B were stored, from its header; `srgb` as the caller decodes it.
StoredRounding storedRoundingOf(const ImageHeader& header, bool srgb);

// What is compared with the reference: one image, or two or more runs (same size; their R, G, B).
struct Candidate {
  Candidate(Image image, bool halfVariance = false) : runs{std::move(image)}, halfVariance(halfVariance) {}
  explicit Candidate(std::vector<Image> runs) : runs(std::move(runs)) {}
  std::vector<Image> runs;
  bool halfVariance = false;  // the one image's variance layers were stored as half floats
  // How the runs' R, G, B were stored, run by run (or one for all), and the reference's. The runs'
  // mean is allowed the mean of their allowances: runs stored in different ways (an RGBE run and
  // an 8-bit one) are each rounded in their own.
  std::vector<StoredRounding> rounding{StoredRounding{}};
  StoredRounding referenceRounding;
};

// The regions' grid by default: the whole image, then 4 x 4 tiles.
constexpr int kRegionGrid = 4;

enum class NoiseSource { VarianceLayer, Runs, Unknown };
// "variance layer", "runs", "unknown".
const char* noiseSourceName(NoiseSource source);

// How a candidate's noise was measured, and at each scale how much the sums' spread exceeds their
// pixels' own variances (kappa; 1 where pixels are independent) with its degrees of freedom
// (infinite where the noise comes from variance layers).
struct CandidateNoise {
  NoiseSource source = NoiseSource::Unknown;
  int runs = 1;
  bool ignoredVarianceLayers = false;  // runs that also had variance layers: their spread was used
  struct Scale {
    std::string name;  // "blocks", "regions", "image"
    double correlation = 1, degreesOfFreedom = 0;
  };
  std::vector<Scale> scales;
  // With variance layers, which count pixels as independent: the correlation of neighbouring
  // pixels' differences from the reference, and its z. A renderer that splats each sample into
  // several pixels correlates them (sums of pixels then vary more than the layers say), blue-noise
  // sampling anticorrelates them (less). Where it is at least kNeighbourCorrelation and z at least
  // kNeighbourCorrelationZ, the verdicts the layers cannot support are inconclusive: a failure of
  // --test (unless it stands with every variance neighbourInflation times as large) and any
  // verdict of --within where rho > 0, a pass of --test where rho < 0.
  double neighbourCorrelation = 0, neighbourCorrelationZ = 0;
  // Where rho is shown and positive, how many times a sum's variance may exceed the layers' sum: 1 +
  // 24 rho (the 24 pixels within 2 of each, at rho), plus 8 k rho_k for each lag k from 3 to 8 while
  // the correlation of pixels k apart along a row or a column is shown at z 2 (a pixel filter that
  // splats into pixels up to 8 apart); 1 elsewhere.
  double neighbourInflation = 1;
  // And the sum of the pixels' squared differences over that of their variances, and its z: about
  // 1 where the layers are right, above it with a bias, below it where the layers overstate the
  // noise (which also makes rho positive): then a pass of --test is inconclusive instead.
  double layerLevel = 1, layerLevelZ = 0;
  bool neighboursMeasured = false;  // false where the verdict was undecided first, or no pair has noise
  // Noise shared farther than neighbours reach (random numbers shared by a tile of pixels) can be
  // too weak between any two pixels for rho to show it, yet make a block's sum vary several times
  // what its layers say (pixels of 16 x 16 tiles sharing 3% of their variance: 8 x 8 blocks' sums
  // 2.9 times, the tiles' 8.7 times). Hence the dispersion of blocks of kDispersionBlock pixels a
  // side, two blocks apart: for disjoint pairs (A, B) and each channel, (A's difference from the
  // reference minus B's)^2 over their variances' sum (the layers' and the reference's), whose median
  // over the pairs and channels, divided by chi-square's with 1 degree of freedom, is the factor by
  // which the layers understate a block's variance (about 1 where they are right; the median keeps a
  // bias in a few blocks from raising it, differences leave a smooth bias out, and the reference is
  // first scaled by the candidate's brightness over it, channel by channel, so that a candidate too
  // bright everywhere does not raise it where the image has contrast); its z against 1 and its
  // bounds (Low, High: the factor over 1 +- 2 standard errors of the median, counting a pair's three
  // channels as one). Where rho does not show, the factor is at least kBlockDispersion and its lower
  // bound above 1, the noise is shared farther than the layers tell, and no one image bounds how much
  // a region's sum then varies: a failure of --test stands only where a block (of at most
  // kDispersionBlock pixels a side) fails with variances the upper bound times as large, and
  // --within is inconclusive. Measured (blockDispersionMeasured) where the image holds at least
  // kDispersionPairs pairs (96 x 96 pixels hold 72): with 32 pairs (64 x 64) 3 of 200 images of
  // independent noise with a 2% bias in one region had a lower bound above 1. Tiles of 32 pixels or
  // more that hold both blocks of most pairs escape it: runs find them.
  double blockDispersion = 1, blockDispersionZ = 0, blockDispersionLow = 1, blockDispersionHigh = 1;
  bool blockDispersionMeasured = false;
  std::string undecided;  // why the verdict cannot be pass or fail, and what would decide it
};
constexpr double kNeighbourCorrelation = 0.05, kNeighbourCorrelationZ = 4;
constexpr int kDispersionBlock = 8, kDispersionPairs = 64;
constexpr double kBlockDispersion = 1.2;

// The mean of the runs' R, G, B (the one image's R, G, B and variance layers where there is one run).
Image candidateImage(const Candidate& candidate);

// A candidate against a reference within both images' noise (lucent compare --test): per block of
// block x block pixels (smaller at the right and bottom edges) and channel the statistic
// t = (c - r) / sqrt(var_c + var_r) of the block's sums, its two-sided p-value (normal with
// variance layers, Student's t with runs); and per region (the whole image, then a grid x grid of
// tiles) the same statistic of the region's sums, which finds a bias far below one pixel's noise.
// The reference must have variance layers. Blocks, not pixels: a pixel's few samples of a
// heavy-tailed integrand (rare paths at low sample counts) give a variance far below the true one
// when they miss the rare paths, and single pixels are rejected by chance; a block's sums draw on
// block^2 times the samples. The Cornell box at 128 x 128 against 1,024 samples per pixel, path
// traced with independent samples, two seeds each: at 64 samples, blocks of 1 reject 50 and 60
// pixels of 16,384 (4.5 times alpha's share below alpha), of 4 x 4 0 and 1 (1.6 times), of 8 x 8
// none (0.8 times); at 16 samples 8 x 8 rejects none (2 times alpha's share below alpha), 4 x 4
// 2 and 4; at 256 samples both none. Hence 8 x 8 by default. A block or region is rejected when its
// p-value is below alpha / (2 * 3 * blocks) or alpha / (2 * 3 * regions) (Bonferroni over the
// channels, the blocks and the regions, alpha split between the two families), the values' rounding
// allowed for pixel by pixel (StoredRounding). Verdict: fail when one is rejected, pass when none
// is, inconclusive when the candidate's noise is unknown, a variance in either image is infinite,
// NaN or negative, the runs are one image, or either image is a JPEG.
struct RegionTest {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double relativeDifference = 0;  // sum(c - r) / sum(r) over the region's R, G, B: its bias
  int channel = 0;                // the channel with the least p-value (0 R, 1 G, 2 B), and its
  double channelDifference = 0;   // sum(c - r) / sum(r), z and p-value
  double z = 0, pValue = 1;
  bool rejected = false;
};
struct NoiseTest {
  double alpha = 0.01;
  int block = 8;
  CandidateNoise noise;
  uint64_t pixels = 0, blocks = 0;
  uint64_t blocksRejectedAtAlpha = 0;  // p-value (Bonferroni over the channels) below alpha: about alpha of them by chance
  uint64_t blocksRejected = 0;         // below the corrected threshold
  double minBlockPValue = 1;
  int minBlockX = 0, minBlockY = 0;    // the top left pixel of the block with the least p-value
  std::vector<RegionTest> regions;     // the whole image, then the grid row by row
  Verdict verdict = Verdict::Inconclusive;
  Image statistic;                     // one channel "z": per pixel its block's largest |t| of the channels
};
NoiseTest testWithinNoise(const Candidate& candidate, const Image& reference, double alpha, int grid = kRegionGrid,
                          int block = 8);

// An equivalence verdict for a biased candidate (lucent compare --within D): per region (the whole
// image, then a grid x grid of tiles) and channel its relative difference from the reference,
// d = sum(c) / sum(r) - 1 over the region's R, G or B, and the (1 - 2 alpha) confidence interval
// d +- q se (q the normal quantile with variance layers, Student's t with runs), se by the delta
// method from both images' noise (runs give the sum's spread itself). Per channel, so that a shift
// of colour that keeps R + G + B is a difference. Verdict: pass when every interval lies inside
// (-D, D) (two one-sided tests per region and channel at level alpha, intersection-union over
// them), fail when an interval lies wholly outside it at level alpha / (2 x 3 x regions) (a bias
// beyond D shown at level alpha over both sides of all the intervals, Bonferroni), else
// inconclusive, with the factor of samples that would decide it; inconclusive too when the
// candidate's noise is unknown, or a region's reference sum is negative in a channel (a pixel
// filter's negative lobes).
struct EquivalenceRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int channel = 0;  // the deciding channel (0 R, 1 G, 2 B): its difference and interval
  double relativeDifference = 0, low = 0, high = 0;
  Verdict verdict = Verdict::Inconclusive;  // pass: inside +-D; fail: wholly outside
};
struct EquivalenceTest {
  double within = 0, alpha = 0.01;
  CandidateNoise noise;
  std::vector<EquivalenceRegion> regions;  // the whole image, then the grid row by row
  // Where the verdict is inconclusive for want of samples: about this many times the candidate's
  // samples (or runs) would narrow every undecided interval enough to decide it.
  double samplesToDecide = 0;
  Verdict verdict = Verdict::Inconclusive;
};
EquivalenceTest testEquivalence(const Candidate& candidate, const Image& reference, double within, double alpha,
                                int grid = kRegionGrid);

// Where a difference lies: the candidate's relative difference from the reference over the pixels
// of each surface the reference's surface layers tell apart (render --layers: surface.material,
// surface.emitter, what each pixel's centre shows), each material (named by `materialNames`, the
// reference's lucent:materials; by its index beyond them), the background, the emitters, and all
// but the emitters; each with its (1 - 2 alpha) confidence interval as testEquivalence's regions
// have it, except that with runs a surface's variance is its own sum's spread, with n - 1 degrees
// of freedom (a surface's pixels lie all over the image, where noise shared over long ranges, such
// as a per-run offset, adds more than a pool over tiles would say), and with variance layers whose
// neighbours are shown correlated both variances are neighbourInflation times as large (see
// CandidateNoise). The interval is absent (NaN) where the noise tests are undecided (the candidate's
// noise unknown, a lossy file). Empty where the reference has no surface layers. The reference
// needs variance layers.
struct SurfaceDifference {
  enum class Kind { Material, Background, Emitters, NonEmitters };
  Kind kind = Kind::Material;
  int64_t material = -1;  // Kind::Material: the reference's material index
  std::string name;   // the material's name, "background", "emitters", "all but emitters"
  uint64_t pixels = 0;
  double relativeDifference = 0, low = 0, high = 0;
};
std::vector<SurfaceDifference> differenceBySurface(const Candidate& candidate, const Image& reference,
                                                   const std::vector<std::string>& materialNames, double alpha);
// "material", "background", "emitters", "non_emitters".
const char* surfaceKindName(SurfaceDifference::Kind kind);

// The z with probability alpha above it under the standard normal distribution, alpha in (0, 1).
double normalUpperQuantile(double alpha);
// The two-sided p-value of t under Student's t with `dof` degrees of freedom (the normal
// distribution where dof is infinite), and the t with two-sided p-value p.
double studentTwoSidedP(double t, double dof);
double studentTwoSidedQuantile(double p, double dof);

}  // namespace lucent
