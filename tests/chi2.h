// Chi-square goodness-of-fit tests for samplers, after Mitsuba's: histogram the samples of a sampler,
// integrate the pdf it claims over each histogram cell, pool sparse cells and compare the two.
//
// Three domains: directions on the sphere (testSphere), points in [0,1)^2 (testSquare) and indices
// (testDiscrete). Each also checks, sample by sample, that the pdf the sampler returns equals the
// separate pdf callable, and that the pdf integrates to the claimed mass.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/core/rng.h"

namespace lucent::chi2 {

// What a sampler returns; a pdf <= 0 (or NaN) means the sampler produced no sample.
struct DirectionSample {
  Vec3 direction;
  float pdf = 0;  // solid-angle density
};
struct PointSample {
  Vec2 point;
  float pdf = 0;  // density on [0,1)^2
};
struct IndexSample {
  uint32_t index = 0;
  float pmf = 0;
};

struct Options {
  uint64_t samples = 1'000'000;
  uint64_t seed = 1;
  // Sphere: thetaBins cells uniform in cos(theta) over [zMin, 1] around `axis`, times phiBins in phi.
  // With zMin > -1 the rest of the sphere is one more cell; a cap close to 1 resolves narrow lobes.
  int thetaBins = 10, phiBins = 20;
  double zMin = -1;
  Vec3 axis{0, 0, 1};
  // Square: xBins x yBins cells over [0,1)^2.
  int xBins = 20, yBins = 20;
  // Probability that the sampler returns a sample, which the pdf must integrate to (within
  // integralTol); failures then form one more cell. nullopt: take it from the integral (samplers that
  // fail where their pdf is zero, as BSDFs do below the horizon).
  std::optional<double> mass = 1.0;
  double integralTol = 1e-3;
  double pdfRelTol = 1e-3;
  double maxPdfMismatchRate = 0;
  // With mass 1, failures are allowed at this rate: warps may hit a pdf-0 boundary with probability ~2^-24.
  double maxFailureRate = 1e-5;
  double minExpected = 5;  // cells expecting fewer samples are pooled
};

struct Result {
  double statistic = 0;
  int dof = 0;
  double pValue = 0;
  double integral = 0;  // of the pdf over the whole domain
  uint64_t samples = 0, failures = 0, invalid = 0, pdfMismatches = 0;
  std::string error;  // every check other than the p-value that failed, with an example

  bool passed(double significance) const { return error.empty() && pValue > significance; }
  std::string summary() const {
    std::ostringstream s;
    s << "chi2 = " << statistic << ", dof = " << dof << ", p = " << pValue << ", integral = " << integral
      << ", samples = " << samples << ", failures = " << failures << ", invalid = " << invalid
      << ", pdf mismatches = " << pdfMismatches << (error.empty() ? "" : ", errors: ") << error;
    return s.str();
  }
};

// Per-test significance such that m independent tests at this level all pass with probability
// 1 - alpha when every sampler is correct (Sidak correction).
inline double sidak(double alpha, int m) { return 1.0 - std::pow(1.0 - alpha, 1.0 / m); }

// Regularized upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a): a power series for
// P = 1 - Q when x < a + 1, otherwise a continued fraction for Q by the modified Lentz method.
inline double gammaQ(double a, double x) {
  if (!(a > 0) || !(x >= 0)) return std::numeric_limits<double>::quiet_NaN();
  if (x == 0) return 1;
  const double prefix = std::exp(a * std::log(x) - x - std::lgamma(a));
  constexpr double kEps = 1e-15, kTiny = 1e-300;
  if (x < a + 1) {
    double term = 1 / a, sum = term;
    for (int n = 1; n < 100000 && std::abs(term) > std::abs(sum) * kEps; ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return std::clamp(1 - prefix * sum, 0.0, 1.0);
  }
  double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    h *= d * c;
    if (std::abs(d * c - 1) < kEps) break;
  }
  return std::clamp(prefix * h, 0.0, 1.0);
}

// Probability that a chi-square variable with `dof` degrees of freedom exceeds `statistic`.
inline double chi2PValue(double statistic, int dof) { return gammaQ(0.5 * dof, 0.5 * statistic); }

// Chi-square statistic over cells, pooling (in order of expected count) every cell that expects fewer
// than minExpected samples, plus further cells until the pool itself reaches minExpected. Adds to
// result.error when samples fall in a cell whose expected count is zero.
inline void pooledChi2(std::span<const double> observed, std::span<const double> expected, double minExpected,
                       Result& result) {
  std::vector<size_t> order(observed.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double stat = 0, poolObserved = 0, poolExpected = 0;
  int cells = 0;
  uint64_t strayCells = 0, strays = 0;
  for (size_t i : order) {
    if (!(expected[i] > 0)) {
      if (observed[i] > 0) ++strayCells, strays += uint64_t(observed[i]);
      continue;
    }
    if (expected[i] < minExpected || (poolExpected > 0 && poolExpected < minExpected)) {
      poolObserved += observed[i];
      poolExpected += expected[i];
    } else {
      stat += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
      ++cells;
    }
  }
  if (poolExpected > 0) {
    stat += (poolObserved - poolExpected) * (poolObserved - poolExpected) / poolExpected;
    ++cells;
  }
  if (strays > 0)
    result.error += std::to_string(strays) + " samples in " + std::to_string(strayCells) +
                    " cells where the pdf integrates to zero; ";
  result.statistic = stat;
  result.dof = cells - 1;
  result.pValue = result.dof > 0 ? chi2PValue(stat, result.dof) : 0;
  if (result.dof < 1) result.error += "fewer than two cells with samples expected; ";
}

namespace detail {

// Adaptive Simpson quadrature with an absolute tolerance per panel (not halved on subdivision, so that
// it also converges at jumps of piecewise-constant pdfs), a minimum depth that keeps it from stepping
// over narrow features, and a maximum depth for jumps that float rounding makes jitter. At 1e6 samples
// this puts expected counts within 1e-2 standard deviations (checked on lat-long maps, Phong lobes up
// to exponent 1000 and cones); tighter tolerances cost much more for no gain.
template <class F>
double simpson(F& f, double a, double b, double fa, double fm, double fb, double whole, int level) {
  constexpr double kTol = 1e-9;
  constexpr int kMinLevel = 4, kMaxLevel = 20;
  const double m = 0.5 * (a + b);
  const double flm = f(0.5 * (a + m)), frm = f(0.5 * (m + b));
  const double left = (m - a) / 6 * (fa + 4 * flm + fm), right = (b - m) / 6 * (fm + 4 * frm + fb);
  const double delta = left + right - whole;
  if (level >= kMaxLevel || (level >= kMinLevel && std::abs(delta) <= 15 * kTol)) return left + right + delta / 15;
  return simpson(f, a, m, fa, flm, fm, left, level + 1) + simpson(f, m, b, fm, frm, fb, right, level + 1);
}
template <class F>
double integrate(F&& f, double a, double b) {
  const double fa = f(a), fm = f(0.5 * (a + b)), fb = f(b);
  return simpson(f, a, b, fa, fm, fb, (b - a) / 6 * (fa + 4 * fm + fb), 0);
}
// Integral of f(x, y) over [x0,x1] x [y0,y1], x inner.
template <class F>
double integrate2D(F&& f, double x0, double x1, double y0, double y1) {
  return integrate([&](double y) { return integrate([&](double x) { return f(x, y); }, x0, x1); }, y0, y1);
}

// The bookkeeping that all three domains share.
class Tally {
 public:
  Tally(const Options& opt, size_t cells) : opt_(opt), observed_(cells, 0.0) { result_.samples = opt.samples; }

  void failure() { ++result_.failures; }
  void invalid(const std::string& what) {
    if (result_.invalid++ == 0) firstInvalid_ = what;
  }
  // Counts the sample in `cell` after checking the sampler's pdf against the pdf callable's;
  // where() names the sample for the report.
  template <class Where>
  void add(size_t cell, double claimedPdf, double pdf, Where&& where) {
    if (!(std::abs(claimedPdf - pdf) <= opt_.pdfRelTol * std::max(claimedPdf, pdf)) &&
        result_.pdfMismatches++ == 0) {
      std::ostringstream s;
      s << "sampler's pdf " << claimedPdf << " but pdf() " << pdf << " at " << where();
      firstMismatch_ = s.str();
    }
    observed_[cell] += 1;
  }

  Result finish(std::vector<double> expectedMass, double integral) {
    Result& r = result_;
    r.integral = integral;
    const double n = double(opt_.samples);
    if (r.invalid > 0) r.error += std::to_string(r.invalid) + " invalid samples, e.g. " + firstInvalid_ + "; ";
    if (r.pdfMismatches > opt_.maxPdfMismatchRate * n)
      r.error += std::to_string(r.pdfMismatches) + " pdf mismatches, e.g. " + firstMismatch_ + "; ";
    if (opt_.mass && std::abs(integral - *opt_.mass) > opt_.integralTol)
      r.error += "pdf integrates to " + std::to_string(integral) + ", not " + std::to_string(*opt_.mass) + "; ";
    const double mass = opt_.mass.value_or(integral);
    if (mass < 1) {
      observed_.push_back(double(r.failures));
      expectedMass.push_back(std::max(0.0, 1 - mass));
    } else if (r.failures > opt_.maxFailureRate * n) {
      r.error += std::to_string(r.failures) + " failed samples but the pdf integrates to 1; ";
    }
    for (double& e : expectedMass) e *= n;
    pooledChi2(observed_, expectedMass, opt_.minExpected, r);
    return r;
  }

 private:
  const Options& opt_;
  std::vector<double> observed_;
  Result result_;
  std::string firstInvalid_, firstMismatch_;
};

inline std::string str(Vec3 v) {
  std::ostringstream s;
  s << '(' << v.x << ", " << v.y << ", " << v.z << ')';
  return s.str();
}
inline std::string str(Vec2 v) {
  std::ostringstream s;
  s << '(' << v.x << ", " << v.y << ')';
  return s.str();
}

}  // namespace detail

// sampler: Rng& -> DirectionSample; pdf: Vec3 -> float (solid-angle density of unit directions).
// A pdf with a pole (1/sin(theta) for lat-long maps) must have it on +-axis, where the integration's
// Jacobian cancels it.
template <class Sampler, class Pdf>
Result testSphere(Sampler&& sampler, Pdf&& pdf, const Options& opt = {}) {
  const Frame frame(normalize(opt.axis));
  const int nt = opt.thetaBins, np = opt.phiBins;
  const bool cap = opt.zMin > -1;
  const double zSpan = 1 - opt.zMin, twoPi = 2 * std::acos(-1.0);
  detail::Tally tally(opt, size_t(nt) * np + cap);
  Rng rng(opt.seed);
  for (uint64_t i = 0; i < opt.samples; ++i) {
    const DirectionSample s = sampler(rng);
    if (!(s.pdf > 0)) {
      tally.failure();
      continue;
    }
    const Vec3 d = s.direction;
    if (!isFinite(d) || !std::isfinite(s.pdf) || std::abs(length(d) - 1) > 1e-4f) {
      tally.invalid("direction " + detail::str(d) + " with pdf " + std::to_string(s.pdf));
      continue;
    }
    const Vec3 l = frame.toLocal(d);
    double phi = std::atan2(double(l.y), double(l.x));
    if (phi < 0) phi += twoPi;
    const int it = std::clamp(int((l.z - opt.zMin) / zSpan * nt), 0, nt - 1);
    const int ip = std::clamp(int(phi / twoPi * np), 0, np - 1);
    const size_t cell = l.z < opt.zMin ? size_t(nt) * np : size_t(it) * np + ip;
    tally.add(cell, s.pdf, pdf(d), [&] { return detail::str(d); });
  }

  // Integrating over (theta, phi) with the sin(theta) Jacobian, rather than over (cos theta, phi), keeps
  // the integrand bounded for pdfs with a 1/sin(theta) pole at the axis (latitude-longitude maps).
  auto density = [&](double theta, double phi) {
    const double st = std::sin(theta);
    if (st == 0) return 0.0;
    const Vec3 local(float(st * std::cos(phi)), float(st * std::sin(phi)), float(std::cos(theta)));
    return double(pdf(frame.toWorld(local))) * st;
  };
  std::vector<double> expected(size_t(nt) * np + cap);
  double integral = 0;
  for (int it = 0; it < nt; ++it) {
    const double theta0 = std::acos(std::min(1.0, opt.zMin + zSpan * (it + 1) / nt));
    const double theta1 = std::acos(opt.zMin + zSpan * it / nt);
    for (int ip = 0; ip < np; ++ip) {
      const double e = detail::integrate2D(density, theta0, theta1, twoPi * ip / np, twoPi * (ip + 1) / np);
      expected[size_t(it) * np + ip] = e;
      integral += e;
    }
  }
  if (cap) {
    double rest = 0;
    for (int ip = 0; ip < np; ++ip)
      rest += detail::integrate2D(density, std::acos(opt.zMin), twoPi / 2, twoPi * ip / np, twoPi * (ip + 1) / np);
    expected.back() = rest;
    integral += rest;
  }
  return tally.finish(std::move(expected), integral);
}

// sampler: Rng& -> PointSample; pdf: Vec2 -> float, a density on [0,1]^2 (evaluated on cell edges too).
template <class Sampler, class Pdf>
Result testSquare(Sampler&& sampler, Pdf&& pdf, const Options& opt = {}) {
  const int nx = opt.xBins, ny = opt.yBins;
  detail::Tally tally(opt, size_t(nx) * ny);
  Rng rng(opt.seed);
  for (uint64_t i = 0; i < opt.samples; ++i) {
    const PointSample s = sampler(rng);
    if (!(s.pdf > 0)) {
      tally.failure();
      continue;
    }
    const Vec2 p = s.point;
    auto where = [&] { return detail::str(p); };
    if (!(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1) || !std::isfinite(s.pdf)) {
      tally.invalid("point " + where() + " with pdf " + std::to_string(s.pdf));
      continue;
    }
    const int ix = std::min(int(p.x * nx), nx - 1), iy = std::min(int(p.y * ny), ny - 1);
    tally.add(size_t(iy) * nx + ix, s.pdf, pdf(p), where);
  }
  auto density = [&](double x, double y) { return double(pdf(Vec2{float(x), float(y)})); };
  std::vector<double> expected(size_t(nx) * ny);
  double integral = 0;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) {
      const double e = detail::integrate2D(density, double(ix) / nx, double(ix + 1) / nx, double(iy) / ny,
                                           double(iy + 1) / ny);
      expected[size_t(iy) * nx + ix] = e;
      integral += e;
    }
  return tally.finish(std::move(expected), integral);
}

// sampler: Rng& -> IndexSample; pmf: uint32_t -> float over indices [0, n).
template <class Sampler, class Pmf>
Result testDiscrete(Sampler&& sampler, Pmf&& pmf, uint32_t n, const Options& opt = {}) {
  detail::Tally tally(opt, n);
  Rng rng(opt.seed);
  for (uint64_t i = 0; i < opt.samples; ++i) {
    const IndexSample s = sampler(rng);
    if (!(s.pmf > 0)) {
      tally.failure();
      continue;
    }
    if (s.index >= n || !std::isfinite(s.pmf)) {
      tally.invalid("index " + std::to_string(s.index) + " with pmf " + std::to_string(s.pmf));
      continue;
    }
    tally.add(s.index, s.pmf, pmf(s.index), [&] { return "index " + std::to_string(s.index); });
  }
  std::vector<double> expected(n);
  for (uint32_t i = 0; i < n; ++i) expected[i] = pmf(i);
  const double total = std::accumulate(expected.begin(), expected.end(), 0.0);
  return tally.finish(std::move(expected), total);
}

}  // namespace lucent::chi2

// Catch2 checks for test files, which declare `kAlpha`: the Sidak-corrected level for the number of
// passing tests in the file. A negative control must be rejected by the histogram itself (its p-value),
// not only by a consistency check.
#define CHECK_CHI2_PASS(result)                 \
  do {                                          \
    const ::lucent::chi2::Result r_ = (result); \
    INFO(r_.summary());                         \
    CHECK(r_.passed(kAlpha));                   \
  } while (0)
#define CHECK_CHI2_REJECT(result)               \
  do {                                          \
    const ::lucent::chi2::Result r_ = (result); \
    INFO(r_.summary());                         \
    CHECK(r_.pValue < kAlpha);                  \
  } while (0)
