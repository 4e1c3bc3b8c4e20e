// The mappings Phi(x, y) = omega between micro-buffer pixels and gather directions (Ritschel et al.
// 2009, 2.2 and 2.3), in the gather point's local frame (normal on +z):
//
//   Nusselt  the projected hemisphere: (x, y) over [-1, 1]^2 is the direction (x, y, sqrt(1 - x^2 - y^2));
//            pixels outside the unit disc are unused. The convolution weighs each pixel by the BRDF,
//            the cosine and its solid angle.
//   Warped   BRDF importance warping: the slice f(wo, .) for the gather point's view direction,
//            tabulated over the same projected disc (omega_x, omega_y), is a 2-D density whose
//            inverse marginal and conditional CDFs map uniform pixels to directions distributed as
//            f cos (the cosine comes with the parameterization). The convolution is then a plain sum.
//
//   Paraboloid  the paraboloid projection (Heidrich and Seidel 1999; the environment-lighting PBGI
//            paper's micro-buffers): (x, y) over [-1, 1]^2 is the direction (2x, 2y, 1 - x^2 - y^2) /
//            (1 + x^2 + y^2); pixels outside the unit disc are unused. A pixel at the centre subtends
//            4 times the solid angle of one at the rim (the Nusselt mapping's rim pixels are the
//            largest). The convolution weighs each pixel as the Nusselt mapping does.
//
// All give every pixel a direction (at a sample point inside the pixel, jittered per gather point),
// the solid angle it subtends (the traversal's refinement threshold) and the weight of its radiance
// in the convolution. src/methods/microrender/README.md says where this departs from the paper.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/scene/bsdf.h"
#include "lucent/techniques/technique_kinds.h"

namespace lucent {

// The paraboloid projection's point (x, y) of a local direction with z > -1, and the direction of
// a point of the plane (below the horizon outside the unit disc).
inline Vec2 paraboloidPoint(Vec3 local) { return {local.x / (1.0f + local.z), local.y / (1.0f + local.z)}; }
inline Vec3 paraboloidDirection(Vec2 p) {
  const float r2 = p.x * p.x + p.y * p.y, s = 1.0f / (1.0f + r2);
  return {2.0f * p.x * s, 2.0f * p.y * s, (1.0f - r2) * s};
}

// A density over the projected disc, piecewise constant on T x T cells of [-1, 1]^2 in
// (omega_x, omega_y), with its marginal CDF over columns (omega_x) and per column the conditional
// CDF over rows (omega_y): M^-1 and C^-1 of 2.3.
struct WarpTable {
  int size = 0;                     // T
  float total = 0;                  // sum of the cell weights
  std::vector<float> cellWeight;    // T x T, column-major: cell (column j, row k) at j * T + k
  std::vector<float> columnCdf;     // T + 1, from 0 to 1
  std::vector<float> rowCdf;        // T x (T + 1): column j's conditional CDF at j * (T + 1)
  std::vector<float> scratch;       // tabulation's working space, reused
};

// Phi^-1 of 2.3 over inverse CDFs of n x n cells: the continuous pixel coordinates (u, v) in [0, 1)^2
// of a local direction's (omega_x, omega_y), M^-1 then C^-1. The n + 1 values of M^-1 start at
// columns[columnBase], column j's n + 1 values of C^-1 at rows[rowBase + j (n + 1)]. The Nusselt
// mapping is the table of one cell {0, 1}, whose inverse is the identity (0 + a (1 - 0) is a
// exactly). The traversal calls this in loops over a packet's lanes, with one array and each lane's
// bases: selects rather than std::clamp and std::min, and 32-bit indices from the same arrays, let
// GCC vectorize them (a pointer per lane does not: Cornell box micro at 128 x 128, 2 threads,
// final gathering 1.58-1.76 against 1.00-1.13 s with packets of 8).
inline Vec2 inverseCdfs(const float* columns, int32_t columnBase, const float* rows, int32_t rowBase, int32_t n,
                        float lx, float ly) {
  constexpr float kBelowOne = 0x1.fffffep-1f;
  const float a0 = (lx + 1.0f) * 0.5f, b0 = (ly + 1.0f) * 0.5f;  // clamped to [0, kBelowOne]
  const float a = a0 < 0.0f ? 0.0f : kBelowOne < a0 ? kBelowOne : a0;
  const float b = b0 < 0.0f ? 0.0f : kBelowOne < b0 ? kBelowOne : b0;
  const float an = a * float(n), bn = b * float(n);
  const int32_t j0 = int32_t(an), k0 = int32_t(bn);
  const int32_t j = n - 1 < j0 ? n - 1 : j0, k = n - 1 < k0 ? n - 1 : k0;
  const int32_t column = columnBase + j, row = rowBase + j * (n + 1) + k;
  const float u = columns[column] + (an - float(j)) * (columns[column + 1] - columns[column]);
  const float v = rows[row] + (bn - float(k)) * (rows[row + 1] - rows[row]);
  return {kBelowOne < u ? kBelowOne : u, kBelowOne < v ? kBelowOne : v};
}
inline constexpr float kIdentityCdf[2] = {0.0f, 1.0f};

// The pixel of continuous coordinates (u, v) in [0, 1)^2, in a width x height buffer.
struct PixelCoord {
  int32_t column, row;
};
inline PixelCoord pixelAt(Vec2 uv, int32_t width, int32_t height) {
  const int32_t x = int32_t(uv.x * float(width)), y = int32_t(uv.y * float(height));
  return {width - 1 < x ? width - 1 : x, height - 1 < y ? height - 1 : y};
}

// What does not change from one gather point to the next, computed once per render: the part of
// every table cell inside the unit disc and where the BRDF is evaluated for it, the Lambertian table
// (the same for every diffuse gather point), and the Nusselt pixels' solid angles.
struct MappingTables {
  int bufferSide = 0, tableSize = 0;
  std::vector<float> cellInside;      // T x T: fraction of the cell's area inside the disc
  std::vector<Vec2> cellCentroid;     // T x T: centroid of that part
  WarpTable lambertian;
  std::vector<float> nusseltSolidAngle;     // per pixel: the exact solid angle of the pixel's part of the disc
  std::vector<float> paraboloidSolidAngle;  // the same for the paraboloid projection
};
MappingTables makeMappingTables(int bufferSide, int tableSize);

// Tabulates the slice f(wo, omega) (its RGB average) over the cells that reach into the disc, each
// the mean of f at the centroid of its inside part and at its inside corners, so that a cell is
// positive wherever f is (the weights divide by the density). Diffuse slices: the shared table.
void tabulateBrdfSlice(const SurfaceBsdf& bsdf, Vec3 woLocal, const MappingTables& tables, WarpTable& table);

// A micro-buffer's mapping for one gather point.
struct HemisphereMapping {
  MappingKind kind = MappingKind::Nusselt;
  int width = 0, height = 0;
  Vec2 jitter{0.5f, 0.5f};        // sample position inside every pixel
  const WarpTable* table = nullptr;  // Warped only

  // Per pixel, row-major (row y, column x), filled by evaluatePixels.
  std::vector<Vec3> direction;    // local frame; (0, 0, 0) for unused pixels
  std::vector<float> solidAngle;  // Omega(x, y)
  std::vector<Rgb> weight;        // radiance weight in the convolution; 0 for unused pixels
  // Sine of the smallest angle from the pixel's direction to a used neighbour's: nodes splat into a
  // pixel and the neighbours their sphere covers, so a node no wider than this reaches no further.
  // Where pixels are anisotropic (the Nusselt rim: radially stretched by 1 / cos) this, not the
  // solid angle, limits the node size.
  std::vector<float> spacing;
  std::vector<Vec3> probe;        // the direction, or for unused pixels the nearest one at the rim
  std::vector<uint16_t> used;     // the pixels with a direction, in order
  uint32_t pixelCount() const { return uint32_t(width * height); }

  // Continuous pixel coordinates (u, v) in [0, 1)^2 of a local direction with z > 0 (Phi^-1), and the
  // direction of (u, v) (Phi); `inside` is false where (u, v) maps outside the disc.
  Vec2 inverse(Vec3 local) const {
    if (kind == MappingKind::Nusselt) return inverseCdfs(kIdentityCdf, 0, kIdentityCdf, 0, 1, local.x, local.y);
    if (kind == MappingKind::Paraboloid) {
      const Vec2 p = paraboloidPoint(local);
      return inverseCdfs(kIdentityCdf, 0, kIdentityCdf, 0, 1, p.x, p.y);
    }
    return inverseCdfs(table->columnCdf.data(), 0, table->rowCdf.data(), 0, table->size, local.x, local.y);
  }
  Vec3 forward(Vec2 uv, bool& inside) const;
  // The point of the mapping's square [-1, 1]^2 at (u, v), possibly outside the disc: M^-1(u)
  // (`column`: the table column and a = (x + 1) / 2), then C^-1(v | column). For the Nusselt and
  // warped mappings the point is (omega_x, omega_y), for the paraboloid paraboloidPoint(omega).
  struct Column {
    int index;
    float a;
  };
  Column column(float u) const;
  Vec2 forwardDisc(Column c, float v) const;
  Vec2 forwardDisc(Vec2 uv) const { return forwardDisc(column(uv.x), uv.y); }
  int pixelOf(Vec3 local) const {
    const PixelCoord p = pixelAt(inverse(local), width, height);
    return p.row * width + p.column;
  }
  // Density of the mapping's directions over solid angle (for uniform (u, v)).
  float pdf(Vec3 local) const;
};

// Sets up the mapping (the table must outlive it) and evaluates every pixel: direction at the
// jittered sample, solid angle, and weight f cos Omega (Nusselt, Paraboloid: the pixel's solid angle
// at its sample, its area times the mapping's Jacobian there) or f / (N p) (Warped, p the table's
// density over the projected disc; with an exact table this is rho / N, the paper's sum scaled by
// rho). Averaged over uniform jitters, the weights of every mapping sum to the directional albedo.
void evaluatePixels(HemisphereMapping& mapping, MappingKind kind, int side, Vec2 jitter, const WarpTable* table,
                    const SurfaceBsdf& bsdf, Vec3 woLocal, const MappingTables& tables);

}  // namespace lucent
