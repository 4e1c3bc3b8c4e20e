// Nusselt and BRDF importance-warped micro-buffer mappings (Ritschel et al. 2009, 2.2, 2.3).
#include "lucent/techniques/microbuffers/hemisphere_mapping.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lucent/techniques/microbuffers/micro_buffer.h"

namespace lucent {

namespace {

// Index of the CDF interval [cdf[i], cdf[i + 1]) holding u, skipping empty intervals.
int findInterval(const float* cdf, int n, float u) {
  const int i = int(std::upper_bound(cdf + 1, cdf + n, u) - cdf) - 1;
  return std::clamp(i, 0, n - 1);
}

// Solid angle of {(x, y) in [x0, x1] x [y0, y1] : x^2 + y^2 < 1} on the projected hemisphere,
// dOmega = dx dy / sqrt(1 - x^2 - y^2): in y the integral is asin(y / s), s = sqrt(1 - x^2), then
// midpoint quadrature in x. The same x nodes for every cell of a column make a column's cells sum to
// exactly pi times its width, so all pixels sum to 2 pi.
float projectedCellSolidAngle(double x0, double x1, double y0, double y1) {
  constexpr int kNodes = 256;
  double sum = 0;
  for (int i = 0; i < kNodes; ++i) {
    const double x = x0 + (x1 - x0) * (i + 0.5) / kNodes;
    const double s = std::sqrt(std::max(0.0, 1.0 - x * x));
    if (!(s > 0)) continue;
    sum += std::asin(std::clamp(y1 / s, -1.0, 1.0)) - std::asin(std::clamp(y0 / s, -1.0, 1.0));
  }
  return float(sum * (x1 - x0) / kNodes);
}

// The same for the paraboloid projection, dOmega = 4 dx dy / (1 + x^2 + y^2)^2: in y, with a = 1 + x^2,
// the integral of 4 / (a + y^2)^2 is 2 (y / (a (a + y^2)) + atan(y / sqrt a) / a^1.5), over the
// column's part of the disc.
float paraboloidCellSolidAngle(double x0, double x1, double y0, double y1) {
  constexpr int kNodes = 256;
  auto primitive = [](double a, double y) { return 2.0 * (y / (a * (a + y * y)) + std::atan(y / std::sqrt(a)) / (a * std::sqrt(a))); };
  double sum = 0;
  for (int i = 0; i < kNodes; ++i) {
    const double x = x0 + (x1 - x0) * (i + 0.5) / kNodes;
    const double s = std::sqrt(std::max(0.0, 1.0 - x * x));
    const double lo = std::max(y0, -s), hi = std::min(y1, s);
    if (!(hi > lo)) continue;
    const double a = 1.0 + x * x;
    sum += primitive(a, hi) - primitive(a, lo);
  }
  return float(sum * (x1 - x0) / kNodes);
}

void buildCdfs(WarpTable& t) {
  const int n = t.size;
  t.columnCdf.assign(size_t(n) + 1, 0.0f);
  t.rowCdf.assign(size_t(n) * (n + 1), 0.0f);
  double total = 0;
  std::vector<double> column(n, 0.0);
  for (int j = 0; j < n; ++j) {
    double c = 0;
    float* cdf = &t.rowCdf[size_t(j) * (n + 1)];
    for (int k = 0; k < n; ++k) {
      c += t.cellWeight[size_t(j) * n + k];
      cdf[k + 1] = float(c);
    }
    for (int k = 1; k <= n; ++k) cdf[k] = c > 0 ? float(cdf[k] / c) : float(k) / float(n);
    cdf[n] = 1.0f;
    column[j] = c;
    total += c;
  }
  if (!(total > 0)) throw std::logic_error("warp table without mass");
  double c = 0;
  for (int j = 0; j < n; ++j) {
    c += column[j];
    t.columnCdf[j + 1] = float(c / total);
  }
  t.columnCdf[n] = 1.0f;
  t.total = float(total);
}

// Table density at cell (j, k) over the projected disc (area of [-1, 1]^2 is 4).
float cellDensity(const WarpTable& t, int j, int k) {
  return t.cellWeight[size_t(j) * t.size + k] / t.total * float(t.size * t.size) * 0.25f;
}

}  // namespace

MappingTables makeMappingTables(int bufferSide, int tableSize) {
  if (bufferSide < 1 || tableSize < 1) throw std::invalid_argument("mapping sizes must be positive");
  MappingTables m;
  m.bufferSide = bufferSide;
  m.tableSize = tableSize;
  const int T = tableSize;
  constexpr int kSub = 16;  // sub-samples per cell side for the part inside the disc
  m.cellInside.resize(size_t(T) * T);
  m.cellCentroid.resize(size_t(T) * T);
  for (int j = 0; j < T; ++j)
    for (int k = 0; k < T; ++k) {
      int inside = 0;
      double cx = 0, cy = 0;
      for (int a = 0; a < kSub; ++a)
        for (int b = 0; b < kSub; ++b) {
          const double x = -1.0 + 2.0 * (j + (a + 0.5) / kSub) / T, y = -1.0 + 2.0 * (k + (b + 0.5) / kSub) / T;
          if (x * x + y * y >= 1.0) continue;
          ++inside;
          cx += x;
          cy += y;
        }
      const size_t c = size_t(j) * T + k;
      m.cellInside[c] = float(inside) / float(kSub * kSub);
      m.cellCentroid[c] = inside > 0 ? Vec2{float(cx / inside), float(cy / inside)} : Vec2{};
    }
  m.lambertian.size = T;
  m.lambertian.cellWeight.resize(m.cellInside.size());
  for (size_t c = 0; c < m.cellInside.size(); ++c) m.lambertian.cellWeight[c] = m.cellInside[c] > 0 ? 1.0f : 0.0f;
  buildCdfs(m.lambertian);

  const int N = bufferSide;
  m.nusseltSolidAngle.resize(size_t(N) * N);
  m.paraboloidSolidAngle.resize(size_t(N) * N);
  for (int y = 0; y < N; ++y)
    for (int x = 0; x < N; ++x) {
      const double x0 = -1.0 + 2.0 * x / N, x1 = -1.0 + 2.0 * (x + 1) / N;
      const double y0 = -1.0 + 2.0 * y / N, y1 = -1.0 + 2.0 * (y + 1) / N;
      m.nusseltSolidAngle[size_t(y) * N + x] = projectedCellSolidAngle(x0, x1, y0, y1);
      m.paraboloidSolidAngle[size_t(y) * N + x] = paraboloidCellSolidAngle(x0, x1, y0, y1);
    }
  return m;
}

void tabulateBrdfSlice(const SurfaceBsdf& bsdf, Vec3 woLocal, const MappingTables& tables, WarpTable& table) {
  const int T = tables.tableSize;
  table.size = T;
  table.cellWeight.resize(size_t(T) * T);
  auto slice = [&](float x, float y) {
    const float z2 = 1.0f - x * x - y * y;
    return z2 > 0 ? evalBsdf(bsdf, woLocal, {x, y, std::sqrt(z2)}).average() : -1.0f;
  };
  // The slice at the cells' corners (T + 1 per side, shared by neighbouring cells).
  std::vector<float>& corners = table.scratch;
  corners.resize(size_t(T + 1) * (T + 1));
  for (int j = 0; j <= T; ++j)
    for (int k = 0; k <= T; ++k) corners[size_t(j) * (T + 1) + k] = slice(-1.0f + 2.0f * j / T, -1.0f + 2.0f * k / T);
  // Each cell's value: the mean of the slice at the centroid of its part inside the disc and at its
  // corners inside the disc. Where the slice is positive anywhere near a cell, so is the cell, and
  // the table follows f at second order. Cells cut by the rim keep their full value (not scaled by
  // the part inside): the density inside the disc is then f's, and samples falling outside are
  // unused pixels.
  double sum = 0;
  for (int j = 0; j < T; ++j)
    for (int k = 0; k < T; ++k) {
      const size_t c = size_t(j) * T + k;
      float w = 0;
      if (tables.cellInside[c] > 0) {
        const Vec2 q = tables.cellCentroid[c];
        float total = std::max(0.0f, slice(q.x, q.y));
        int count = 1;
        for (int corner = 0; corner < 4; ++corner) {
          const float v = corners[size_t(j + (corner & 1)) * (T + 1) + k + (corner >> 1)];
          if (v >= 0) total += v, ++count;
        }
        w = total / float(count);
      }
      table.cellWeight[c] = w;
      sum += w;
    }
  if (!(sum > 0))  // a black slice: any density will do, the weights are zero
    for (size_t c = 0; c < table.cellWeight.size(); ++c) table.cellWeight[c] = tables.cellInside[c] > 0 ? 1.0f : 0.0f;
  buildCdfs(table);
}

HemisphereMapping::Column HemisphereMapping::column(float u) const {
  if (kind != MappingKind::Warped) return {0, u};
  const WarpTable& t = *table;
  const int n = t.size;
  const int j = findInterval(t.columnCdf.data(), n, u);
  const float du = t.columnCdf[j + 1] - t.columnCdf[j];
  return {j, (float(j) + std::clamp(du > 0 ? (u - t.columnCdf[j]) / du : 0.5f, 0.0f, 1.0f)) / float(n)};
}

Vec2 HemisphereMapping::forwardDisc(Column c, float v) const {
  float b = v;
  if (kind == MappingKind::Warped) {
    const WarpTable& t = *table;
    const int n = t.size;
    const float* rows = &t.rowCdf[size_t(c.index) * (n + 1)];
    const int k = findInterval(rows, n, v);
    const float dv = rows[k + 1] - rows[k];
    b = (float(k) + std::clamp(dv > 0 ? (v - rows[k]) / dv : 0.5f, 0.0f, 1.0f)) / float(n);
  }
  return {2.0f * c.a - 1.0f, 2.0f * b - 1.0f};
}

Vec3 HemisphereMapping::forward(Vec2 uv, bool& inside) const {
  const Vec2 q = forwardDisc(uv);
  if (kind == MappingKind::Paraboloid) {
    inside = q.x * q.x + q.y * q.y < 1.0f;
    return inside ? paraboloidDirection(q) : Vec3{};
  }
  const float z2 = 1.0f - q.x * q.x - q.y * q.y;
  inside = z2 > 0;
  return inside ? Vec3{q.x, q.y, std::sqrt(z2)} : Vec3{};
}

float HemisphereMapping::pdf(Vec3 local) const {
  if (!(local.z > 0)) return 0.0f;
  // Uniform (u, v) over [0, 1]^2: a quarter over the square [-1, 1]^2, whose paraboloid points
  // have the density (1 + x^2 + y^2)^2 / 4 = 1 / (1 + z)^2 over solid angle.
  if (kind == MappingKind::Paraboloid) return 0.25f / ((1.0f + local.z) * (1.0f + local.z));
  float density = 0.25f;  // Nusselt: uniform over [-1, 1]^2
  if (kind == MappingKind::Warped) {
    const int n = table->size;
    const float a = std::clamp((local.x + 1.0f) * 0.5f, 0.0f, 0x1.fffffep-1f);
    const float b = std::clamp((local.y + 1.0f) * 0.5f, 0.0f, 0x1.fffffep-1f);
    density = cellDensity(*table, std::min(int(a * float(n)), n - 1), std::min(int(b * float(n)), n - 1));
  }
  return density * local.z;  // dA_projected = cos dOmega
}

void evaluatePixels(HemisphereMapping& m, MappingKind kind, int side, Vec2 jitter, const WarpTable* table,
                    const SurfaceBsdf& bsdf, Vec3 woLocal, const MappingTables& tables) {
  if (side < 1 || side > kMaxMicroBufferSide)
    throw std::invalid_argument("micro-buffer side " + std::to_string(side) + " outside 1 to " +
                                std::to_string(kMaxMicroBufferSide));
  m.kind = kind;
  m.width = m.height = side;
  m.jitter = jitter;
  m.table = table;
  const size_t n = size_t(side) * side;
  m.direction.resize(n);
  m.solidAngle.resize(n);
  m.weight.resize(n);
  m.spacing.resize(n);
  m.probe.resize(n);
  m.used.clear();
  const float invN = 1.0f / float(n);
  // M^-1 once per column of pixels, C^-1 per pixel.
  HemisphereMapping::Column columns[kMaxMicroBufferSide];
  for (int x = 0; x < side; ++x) columns[x] = m.column((float(x) + jitter.x) / float(side));
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const size_t i = size_t(y) * side + x;
      const Vec2 q = m.forwardDisc(columns[x], (float(y) + jitter.y) / float(side));
      const float r2 = q.x * q.x + q.y * q.y;
      const bool inside = r2 < 1.0f;
      // Pixels whose sample falls outside the disc gather nothing, but nodes can still map to them
      // (at the rim): they get the solid angle and spacing of the direction at the rim.
      const float shrink = inside ? 1.0f : 0.9999f / std::sqrt(r2);
      const Vec2 c{q.x * shrink, q.y * shrink};
      const Vec3 w = kind == MappingKind::Paraboloid ? paraboloidDirection(c)
                                                     : Vec3{c.x, c.y, std::sqrt(std::max(0.0f, 1.0f - c.x * c.x - c.y * c.y))};
      m.probe[i] = w;
      m.direction[i] = inside ? w : Vec3{};
      m.weight[i] = Rgb();
      if (kind == MappingKind::Paraboloid) {
        m.solidAngle[i] = tables.paraboloidSolidAngle[i];
        const float jacobian = 4.0f / ((1.0f + r2) * (1.0f + r2));  // dOmega / dx dy at the sample
        if (inside) m.weight[i] = evalBsdf(bsdf, woLocal, w) * (w.z * jacobian * 4.0f * invN);
      } else if (kind == MappingKind::Nusselt) {
        m.solidAngle[i] = tables.nusseltSolidAngle[i];
        if (inside) m.weight[i] = evalBsdf(bsdf, woLocal, w) * (4.0f * invN);  // f cos dOmega = f dA, dA = 4 / N
      } else {
        const float p = m.pdf(w) / w.z;  // density over the projected disc
        m.solidAngle[i] = invN / (p * w.z);
        if (inside) m.weight[i] = evalBsdf(bsdf, woLocal, w) * (invN / p);
      }
      if (inside) m.used.push_back(uint16_t(i));
    }
  for (size_t i = 0; i < n; ++i) {
    const int x = int(i) % side, y = int(i) / side;
    float maxCos = -1;
    if (x > 0) maxCos = std::max(maxCos, dot(m.probe[i], m.probe[i - 1]));
    if (x + 1 < side) maxCos = std::max(maxCos, dot(m.probe[i], m.probe[i + 1]));
    if (y > 0) maxCos = std::max(maxCos, dot(m.probe[i], m.probe[i - side]));
    if (y + 1 < side) maxCos = std::max(maxCos, dot(m.probe[i], m.probe[i + side]));
    m.spacing[i] = std::sqrt(std::max(0.0f, 1.0f - maxCos * maxCos));
  }
}

}  // namespace lucent
