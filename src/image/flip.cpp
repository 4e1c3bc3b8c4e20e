// FLIP and HDR-FLIP. Section references are to the FLIP paper (HPG 2020) unless marked HDR.
#include "lucent/image/flip.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "lucent/core/memory.h"

namespace lucent {

namespace {

// A colour in one of the spaces below.
using Triple = std::array<float, 3>;

// Section 4.1: the three Gaussians' constants (a, b); a Gaussian's weight at x degrees is
// a sqrt(pi / b) exp(-pi^2 x^2 / b).
struct Gaussian {
  double a, b;
};
constexpr Gaussian kY{1, 0.0047}, kCx{1, 0.0053}, kCz1{34.1, 0.04}, kCz2{13.5, 0.025};
constexpr double kLargestB = 0.04;

// Section 4.2.
constexpr double kQc = 0.7, kPc = 0.4, kPt = 0.95;
// Section 4.3.
constexpr double kFeatureWidthDegrees = 0.082, kQf = 0.5;

// HDR Section 3: the tone-mapped value at which the start and stop exposures are placed.
constexpr double kExposureTarget = 0.85;
constexpr double kHdrMax = 65536;

}  // namespace

namespace flip {

namespace {

using Matrix = std::array<std::array<double, 3>, 3>;

constexpr double kWhiteX = 0.950428545, kWhiteZ = 1.088900371;  // D65, Y_n = 1

// Linear sRGB to CIE XYZ, from the sRGB primaries and D65 white as exact fractions.
constexpr Matrix kRgbToXyz = {{{10135552.0 / 24577794, 8788810.0 / 24577794, 4435075.0 / 24577794},
                               {2613072.0 / 12288897, 8788810.0 / 12288897, 887015.0 / 12288897},
                               {1425312.0 / 73733382, 8788810.0 / 73733382, 70074185.0 / 73733382}}};

constexpr Matrix inverse(const Matrix& m) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1], c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2],
               c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
  return {{{c00 / det, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det},
           {c01 / det, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det},
           {c02 / det, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det}}};
}
constexpr Matrix kXyzToRgb = inverse(kRgbToXyz);

Triple multiply(const Matrix& m, Triple v) {
  Triple out;
  for (int i = 0; i < 3; ++i) out[i] = float(m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2]);
  return out;
}

float luminance(Triple rgb) { return multiply(kRgbToXyz, rgb)[1]; }

}  // namespace

std::array<float, 3> linearRgbToYCxCz(std::array<float, 3> rgb) {
  const Triple xyz = multiply(kRgbToXyz, rgb);
  const double x = xyz[0] / kWhiteX, y = xyz[1], z = xyz[2] / kWhiteZ;
  return {float(116 * y - 16), float(500 * (x - y)), float(200 * (y - z))};
}

std::array<float, 3> yCxCzToLinearRgb(std::array<float, 3> ycxcz) {
  const double y = (ycxcz[0] + 16.0) / 116.0, x = y + ycxcz[1] / 500.0, z = y - ycxcz[2] / 200.0;
  return multiply(kXyzToRgb, {float(x * kWhiteX), float(y), float(z * kWhiteZ)});
}

std::array<float, 3> linearRgbToHuntLab(std::array<float, 3> rgb) {
  const Triple xyz = multiply(kRgbToXyz, rgb);
  constexpr double delta = 6.0 / 29.0;
  auto f = [](double t) { return t > delta * delta * delta ? std::cbrt(t) : t / (3 * delta * delta) + 4.0 / 29.0; };
  const double fx = f(xyz[0] / kWhiteX), fy = f(xyz[1]), fz = f(xyz[2] / kWhiteZ);
  const double l = 116 * fy - 16;
  // Hunt effect (Section 4.2): chroma appears stronger at higher luminance.
  return {float(l), float(0.01 * l * 500 * (fx - fy)), float(0.01 * l * 200 * (fy - fz))};
}

float hyab(std::array<float, 3> a, std::array<float, 3> b) {
  return std::abs(a[0] - b[0]) + std::hypot(a[1] - b[1], a[2] - b[2]);
}

float colourError(std::array<float, 3> huntLabA, std::array<float, 3> huntLabB) {
  static const double cMax = std::pow(hyab(linearRgbToHuntLab({0, 1, 0}), linearRgbToHuntLab({0, 0, 1})), kQc);
  const double e = std::pow(double(hyab(huntLabA, huntLabB)), kQc);
  const double knee = kPc * cMax;
  return float(e < knee ? e * kPt / knee : kPt + (e - knee) / (cMax - knee) * (1 - kPt));
}

CsfFilters csfFilters(double pixelsPerDegree) {
  CsfFilters filters;
  filters.radius = int(std::ceil(3 * std::sqrt(kLargestB / (2 * std::numbers::pi * std::numbers::pi)) * pixelsPerDegree));
  const int r = filters.radius;
  // The separable factor of a Gaussian's two-dimensional weight a sqrt(pi / b) exp(-pi^2 (x^2 + y^2) / b).
  auto factor = [&](const Gaussian& g) {
    std::vector<double> w(size_t(2 * r + 1));
    for (int i = -r; i <= r; ++i) {
      const double x = i / pixelsPerDegree;
      w[size_t(i + r)] = std::sqrt(g.a * std::sqrt(std::numbers::pi / g.b)) *
                         std::exp(-std::numbers::pi * std::numbers::pi * x * x / g.b);
    }
    return w;
  };
  auto sum = [](const std::vector<double>& w) {
    double s = 0;
    for (const double v : w) s += v;
    return s;
  };
  auto scaled = [](const std::vector<double>& w, double scale) {
    std::vector<float> out(w.size());
    for (size_t i = 0; i < w.size(); ++i) out[i] = float(w[i] * scale);
    return out;
  };
  const std::vector<double> y = factor(kY), cx = factor(kCx), cz1 = factor(kCz1), cz2 = factor(kCz2);
  filters.y = scaled(y, 1 / sum(y));
  filters.cx = scaled(cx, 1 / sum(cx));
  // The two-dimensional Cz kernel sums to sum(cz1)^2 + sum(cz2)^2.
  const double czNorm = 1 / std::sqrt(sum(cz1) * sum(cz1) + sum(cz2) * sum(cz2));
  filters.cz1 = scaled(cz1, czNorm);
  filters.cz2 = scaled(cz2, czNorm);
  return filters;
}

FeatureFilters featureFilters(double pixelsPerDegree) {
  FeatureFilters filters;
  const double sd = 0.5 * kFeatureWidthDegrees * pixelsPerDegree;
  filters.radius = int(std::ceil(3 * sd));
  const int r = filters.radius;
  std::vector<double> g(size_t(2 * r + 1)), d1(g.size()), d2(g.size());
  double gSum = 0, d1Positive = 0, d1Negative = 0, d2Positive = 0, d2Negative = 0;
  for (int i = -r; i <= r; ++i) {
    const size_t k = size_t(i + r);
    g[k] = std::exp(-double(i) * i / (2 * sd * sd));
    d1[k] = -i * g[k];
    d2[k] = (double(i) * i / (sd * sd) - 1) * g[k];
    gSum += g[k];
    (d1[k] > 0 ? d1Positive : d1Negative) += std::abs(d1[k]);
    (d2[k] > 0 ? d2Positive : d2Negative) += std::abs(d2[k]);
  }
  // Normalising the one-dimensional factor's positive and negative parts normalises the
  // two-dimensional kernel's, the other factor being the normalised Gaussian.
  for (size_t k = 0; k < g.size(); ++k) {
    filters.gaussian.push_back(float(g[k] / gSum));
    filters.edge.push_back(float(d1[k] / (d1[k] > 0 ? d1Positive : d1Negative)));
    filters.point.push_back(float(d2[k] / (d2[k] > 0 ? d2Positive : d2Negative)));
  }
  return filters;
}

float acesToneMap(float value) {
  const double x = 0.6 * double(value);
  const double mapped = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
  return float(std::clamp(mapped, 0.0, 1.0));
}

namespace {

// The value x with ACES(x) = t: the root of (k0 - t k3) x^2 + (k1 - t k4) x - t k5 = 0.
double inverseAces(double t) {
  const double k0 = 0.36 * 2.51, k1 = 0.6 * 0.03, k3 = 0.36 * 2.43, k4 = 0.6 * 0.59, k5 = 0.14;
  const double c0 = (k1 - t * k4) / (k0 - t * k3), c1 = -t * k5 / (k0 - t * k3);
  return -0.5 * c0 + std::sqrt(0.25 * c0 * c0 - c1);
}

}  // namespace

std::array<double, 2> exposureRange(const Image& reference) {
  const int r = reference.channelIndex("R"), g = reference.channelIndex("G"), b = reference.channelIndex("B");
  std::vector<float> luminances;
  luminances.reserve(size_t(reference.width()) * size_t(reference.height()));
  for (int y = 0; y < reference.height(); ++y)
    for (int x = 0; x < reference.width(); ++x) {
      Triple rgb = {reference.at(x, y, r), reference.at(x, y, g), reference.at(x, y, b)};
      for (float& v : rgb) v = std::clamp(v, 0.0f, float(kHdrMax));
      luminances.push_back(std::max(luminance(rgb), 0.0f));
    }
  if (luminances.empty()) return {0, 0};
  const float largest = *std::max_element(luminances.begin(), luminances.end());
  if (!(largest > 0)) return {0, 0};
  auto middle = luminances.begin() + std::ptrdiff_t(luminances.size() / 2);
  std::nth_element(luminances.begin(), middle, luminances.end());
  float median = *middle;
  if (!(median > 0)) {
    // Most of the image is black (a sky-less render): the median of the lit pixels.
    std::erase_if(luminances, [](float v) { return !(v > 0); });
    middle = luminances.begin() + std::ptrdiff_t(luminances.size() / 2);
    std::nth_element(luminances.begin(), middle, luminances.end());
    median = *middle;
  }
  const double target = inverseAces(kExposureTarget);
  return {std::log2(target / largest), std::log2(target / median)};
}

}  // namespace flip

namespace {

// A float plane of width x height.
struct Plane {
  int width = 0, height = 0;
  std::vector<float> values;
  Plane(int w, int h) : width(w), height(h), values(size_t(w) * size_t(h)) {}
  float& at(int x, int y) { return values[size_t(y) * size_t(width) + size_t(x)]; }
  float at(int x, int y) const { return values[size_t(y) * size_t(width) + size_t(x)]; }
};

template <class Body>
void forRows(int height, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) body(y);
  });
}

// The correlation of a plane with horizontal then vertical weights at -r..r, the borders extended
// by their edge values; added to `out`. Loops run along rows, for the compiler's vector lanes.
void addSeparable(const Plane& in, const std::vector<float>& horizontal, const std::vector<float>& vertical,
                  Plane& out) {
  const int w = in.width, h = in.height, r = int(horizontal.size() / 2);
  Plane rows(w, h);
  forRows(h, [&](int y) {
    std::vector<float> padded(size_t(w + 2 * r));
    for (int i = 0; i < w + 2 * r; ++i) padded[size_t(i)] = in.at(std::clamp(i - r, 0, w - 1), y);
    float* dst = &rows.at(0, y);
    for (int i = 0; i <= 2 * r; ++i) {
      const float k = horizontal[size_t(i)];
      const float* src = padded.data() + i;
      for (int x = 0; x < w; ++x) dst[x] += k * src[x];
    }
  });
  forRows(h, [&](int y) {
    float* dst = &out.at(0, y);
    for (int i = -r; i <= r; ++i) {
      const float k = vertical[size_t(i + r)];
      const float* src = &rows.at(0, std::clamp(y + i, 0, h - 1));
      for (int x = 0; x < w; ++x) dst[x] += k * src[x];
    }
  });
}

// Section 4.3: each pixel's edge and point strength, the length of the gradient of the
// luminance's correlation with the two derivative kernels.
void featureStrengths(const Plane& lum, const flip::FeatureFilters& f, Plane& edges, Plane& points) {
  const int w = lum.width, h = lum.height;
  Plane edgeX(w, h), edgeY(w, h), pointX(w, h), pointY(w, h);
  addSeparable(lum, f.edge, f.gaussian, edgeX);
  addSeparable(lum, f.gaussian, f.edge, edgeY);
  addSeparable(lum, f.point, f.gaussian, pointX);
  addSeparable(lum, f.gaussian, f.point, pointY);
  for (size_t i = 0; i < edges.values.size(); ++i) {
    edges.values[i] = std::hypot(edgeX.values[i], edgeY.values[i]);
    points.values[i] = std::hypot(pointX.values[i], pointY.values[i]);
  }
}

struct Filters {
  flip::CsfFilters csf;
  flip::FeatureFilters features;
};

// What LDR-FLIP needs of one image: its colours filtered by the contrast sensitivity functions,
// Hunt-adjusted (Section 4.1-4.2), and its edge and point strengths (Section 4.3).
struct Prepared {
  std::vector<Triple> huntLab;
  Plane edges, points;
  Prepared(int w, int h) : huntLab(size_t(w) * size_t(h)), edges(w, h), points(w, h) {}
};

Prepared prepare(const std::vector<Triple>& linear, int w, int h, const Filters& filters) {
  std::array<Plane, 3> opponent = {Plane(w, h), Plane(w, h), Plane(w, h)};
  Plane lum(w, h);
  forRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const Triple ycxcz = flip::linearRgbToYCxCz(linear[size_t(y) * size_t(w) + size_t(x)]);
      for (int c = 0; c < 3; ++c) opponent[size_t(c)].at(x, y) = ycxcz[size_t(c)];
      lum.at(x, y) = (ycxcz[0] + 16) / 116;  // Y / Y_n
    }
  });
  std::array<Plane, 3> filtered = {Plane(w, h), Plane(w, h), Plane(w, h)};
  addSeparable(opponent[0], filters.csf.y, filters.csf.y, filtered[0]);
  addSeparable(opponent[1], filters.csf.cx, filters.csf.cx, filtered[1]);
  addSeparable(opponent[2], filters.csf.cz1, filters.csf.cz1, filtered[2]);
  addSeparable(opponent[2], filters.csf.cz2, filters.csf.cz2, filtered[2]);
  Prepared out(w, h);
  forRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      Triple rgb = flip::yCxCzToLinearRgb({filtered[0].at(x, y), filtered[1].at(x, y), filtered[2].at(x, y)});
      for (float& v : rgb) v = std::clamp(v, 0.0f, 1.0f);
      out.huntLab[size_t(y) * size_t(w) + size_t(x)] = flip::linearRgbToHuntLab(rgb);
    }
  });
  featureStrengths(lum, filters.features, out.edges, out.points);
  return out;
}

// LDR-FLIP (Section 4) of two images of linear values in [0, 1], each pixel's error raised into
// `errors` (HDR-FLIP keeps the largest over its exposures).
void ldrFlip(const std::vector<Triple>& candidate, const std::vector<Triple>& reference, int w, int h,
             const Filters& filters, std::vector<float>& errors) {
  const Prepared c = prepare(candidate, w, h, filters), r = prepare(reference, w, h, filters);
  forRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      const double colour = flip::colourError(c.huntLab[i], r.huntLab[i]);
      const double featureDifference = std::max(std::abs(c.edges.values[i] - r.edges.values[i]),
                                                std::abs(c.points.values[i] - r.points.values[i]));
      const double feature = std::pow(featureDifference / std::numbers::sqrt2, kQf);
      errors[i] = std::max(errors[i], float(std::pow(colour, 1 - feature)));
    }
  });
}

// An image's R, G, B per pixel, black where a value is NaN or infinite; those pixels' indices are
// returned.
std::vector<size_t> readRgb(const Image& image, std::vector<Triple>& out) {
  const int r = image.channelIndex("R"), g = image.channelIndex("G"), b = image.channelIndex("B");
  std::vector<size_t> nonFinite;
  out.resize(size_t(image.width()) * size_t(image.height()));
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      const size_t i = size_t(y) * size_t(image.width()) + size_t(x);
      Triple rgb = {image.at(x, y, r), image.at(x, y, g), image.at(x, y, b)};
      if (!(std::isfinite(rgb[0]) && std::isfinite(rgb[1]) && std::isfinite(rgb[2]))) {
        nonFinite.push_back(i);
        rgb = {0, 0, 0};
      }
      out[i] = rgb;
    }
  return nonFinite;
}

std::vector<Triple> clamped(const std::vector<Triple>& linear, float scale, float top) {
  std::vector<Triple> out(linear.size());
  for (size_t i = 0; i < linear.size(); ++i)
    for (int c = 0; c < 3; ++c) out[i][size_t(c)] = std::clamp(scale * linear[i][size_t(c)], 0.0f, top);
  return out;
}

// The least error e with sum(errors <= e) >= p * sum(errors), errors sorted.
double weightedPercentile(const std::vector<float>& sorted, double total, double p) {
  double sum = 0;
  for (const float e : sorted) {
    sum += e;
    if (sum >= p * total && e > 0) return e;
  }
  return sorted.empty() ? 0 : sorted.back();
}

}  // namespace

Image flip::featureStrengths(const Image& linearRgb, double pixelsPerDegree) {
  std::vector<Triple> rgb;
  readRgb(linearRgb, rgb);
  const int w = linearRgb.width(), h = linearRgb.height();
  Plane lum(w, h), edges(w, h), points(w, h);
  for (size_t i = 0; i < rgb.size(); ++i) lum.values[i] = (flip::linearRgbToYCxCz(rgb[i])[0] + 16) / 116;
  featureStrengths(lum, flip::featureFilters(pixelsPerDegree), edges, points);
  Image out(w, h, {"edge", "point"});
  for (size_t i = 0; i < rgb.size(); ++i) {
    out.pixels()[2 * i] = edges.values[i];
    out.pixels()[2 * i + 1] = points.values[i];
  }
  return out;
}

FlipResult computeFlip(const Image& candidate, const Image& reference, const FlipOptions& options) {
  if (candidate.width() != reference.width() || candidate.height() != reference.height())
    throw std::invalid_argument("FLIP needs images of one size: " + std::to_string(candidate.width()) + " x " +
                                std::to_string(candidate.height()) + " against " + std::to_string(reference.width()) +
                                " x " + std::to_string(reference.height()));
  for (const Image* image : {&candidate, &reference})
    for (const char* c : {"R", "G", "B"})
      if (image->channelIndex(c) < 0)
        throw std::invalid_argument(std::string("FLIP needs R, G and B channels; the ") +
                                    (image == &candidate ? "image" : "reference") + " has no " + c);
  if (!(options.pixelsPerDegree >= 1 && options.pixelsPerDegree <= 1000))
    throw std::invalid_argument("FLIP's pixels per degree must lie in [1, 1000]");
  const int w = reference.width(), h = reference.height();
  // At the peak: both images' inputs and tone-mapped copies, one image's stages being prepared
  // (17 planes) and the other's results (5), the errors and their sorted copy: 40 floats a pixel.
  requireMemory(uint64_t(w) * uint64_t(h) * 40 * sizeof(float), "FLIP", "compare crops of the images");
  std::vector<Triple> candidateRgb, referenceRgb;
  FlipResult result;
  result.hdr = options.hdr;
  const std::vector<size_t> nonFinite = readRgb(candidate, candidateRgb);
  result.nonFinite = nonFinite.size();
  if (!readRgb(reference, referenceRgb).empty())
    throw std::invalid_argument("the reference has NaN or infinite values");
  const Filters filters{flip::csfFilters(options.pixelsPerDegree), flip::featureFilters(options.pixelsPerDegree)};
  std::vector<float> errors(referenceRgb.size(), 0.0f);
  if (!options.hdr) {
    ldrFlip(clamped(candidateRgb, 1, 1), clamped(referenceRgb, 1, 1), w, h, filters, errors);
  } else {
    // HDR Section 3: LDR-FLIP at exposures spaced at most one stop apart, the largest error kept.
    const std::array<double, 2> range = flip::exposureRange(reference);
    result.startExposure = options.startExposure.value_or(range[0]);
    result.stopExposure = options.stopExposure.value_or(range[1]);
    for (const double e : {result.startExposure, result.stopExposure})
      if (!(std::isfinite(e) && std::abs(e) <= 100))
        throw std::invalid_argument("FLIP's exposures must lie in [-100, 100] stops");
    if (result.startExposure > result.stopExposure)
      throw std::invalid_argument("FLIP's start exposure must not exceed its stop exposure");
    result.exposures = int(std::max(2.0, std::ceil(result.stopExposure - result.startExposure)));
    const double step = (result.stopExposure - result.startExposure) / (result.exposures - 1);
    const std::vector<Triple> hdrCandidate = clamped(candidateRgb, 1, float(kHdrMax));
    const std::vector<Triple> hdrReference = clamped(referenceRgb, 1, float(kHdrMax));
    for (int k = 0; k < result.exposures; ++k) {
      const float scale = float(std::exp2(result.startExposure + k * step));
      auto toneMapped = [scale](std::vector<Triple> linear) {
        for (Triple& rgb : linear)
          for (float& v : rgb) v = flip::acesToneMap(scale * v);
        return linear;
      };
      ldrFlip(toneMapped(hdrCandidate), toneMapped(hdrReference), w, h, filters, errors);
    }
  }
  for (const size_t i : nonFinite) errors[i] = 1;
  result.map = Image(w, h, {"flip"});
  result.map.pixels() = errors;
  // Pooling (FLIP Section 5): the mean and percentiles weighted by the errors themselves.
  std::vector<float> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  double total = 0;
  for (const float e : sorted) total += e;
  result.mean = sorted.empty() ? 0 : total / double(sorted.size());
  result.weightedQuartile1 = weightedPercentile(sorted, total, 0.25);
  result.weightedMedian = weightedPercentile(sorted, total, 0.5);
  result.weightedQuartile3 = weightedPercentile(sorted, total, 0.75);
  return result;
}

}  // namespace lucent
