#include "photon_columns.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>

#include "knn_grid.h"
#include "lucent/core/parallel.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/octahedral.h"
#include "lucent/core/stop.h"

namespace lucent {

PhotonColumns photonColumns(std::span<const Photon> listed) {
  PhotonColumns c;
  // Every entry is written once: the photons by the parallel fill, the padding by resizeColumns.
  resizeColumns(c, uint32_t(listed.size()));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, listed.size(), kItemsPerTask), [&](const auto& range) {
    stopPoint();
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const Photon& p = listed[i];
      const Vec3 incoming = octahedralDirection(p.direction), facing = photonFacing(p);
      c.x[i] = p.position.x, c.y[i] = p.position.y, c.z[i] = p.position.z;
      c.incomingX[i] = incoming.x, c.incomingY[i] = incoming.y, c.incomingZ[i] = incoming.z;
      c.facingX[i] = facing.x, c.facingY[i] = facing.y, c.facingZ[i] = facing.z;
      c.r[i] = p.power.r, c.g[i] = p.power.g, c.b[i] = p.power.b;
    }
  });
  return c;
}

namespace {

// The helpers below pass eight-lane vectors by value. The default clone passes them differently
// from the AVX2 and AVX-512 ones, so every helper that takes or returns one is forced inline into
// the clone that calls it (a call from a clone to an out-of-line helper reads garbage lanes); GCC's
// note on the difference then concerns no interface.
#pragma GCC diagnostic ignored "-Wpsabi"
#define LUCENT_LANE_HELPER [[gnu::always_inline]] inline

// Eight lanes as GCC vector types: one AVX register in the AVX2 and AVX-512 clones (the latter with
// mask registers for the comparisons), two SSE registers otherwise.
typedef float Floats __attribute__((vector_size(32)));
typedef int32_t Ints __attribute__((vector_size(32)));

LUCENT_LANE_HELPER Floats loadLanes(const float* p) {
  Floats v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
LUCENT_LANE_HELPER Ints loadLanes(const int32_t* p) {
  Ints v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
LUCENT_LANE_HELPER void storeLanes(float* p, Floats v) { std::memcpy(p, &v, sizeof v); }
LUCENT_LANE_HELPER void storeLanes(int32_t* p, Ints v) { std::memcpy(p, &v, sizeof v); }
LUCENT_LANE_HELPER Floats broadcast(float f) { return Floats{} + f; }
LUCENT_LANE_HELPER Ints broadcast(int32_t i) { return Ints{} + i; }
// The lanes of v where mask is set (all ones), zero elsewhere.
LUCENT_LANE_HELPER Floats masked(Floats v, Ints mask) { return Floats(Ints(v) & mask); }
LUCENT_LANE_HELPER int32_t sum(Ints v) {
  int32_t n = 0;
  for (int j = 0; j < kPhotonLanes; ++j) n += v[j];
  return n;
}
// Lanes set in a mask.
LUCENT_LANE_HELPER int32_t count(Ints mask) { return -sum(mask); }

constexpr Ints kLane = {0, 1, 2, 3, 4, 5, 6, 7};

// Eight photons from `first` on: squared distance (as distance2) and whether each lights the
// query's side (as photonLights), lanes past the run's end invalid.
struct Block {
  Floats d2;
  Ints lights, valid;
};

struct ColumnQuery {
  Floats x, y, z, nx, ny, nz, fx, fy, fz;
  LUCENT_LANE_HELPER ColumnQuery(Vec3 q, const SurfaceSide& side)
      : x(broadcast(q.x)), y(broadcast(q.y)), z(broadcast(q.z)), nx(broadcast(side.shadingNormal.x)),
        ny(broadcast(side.shadingNormal.y)), nz(broadcast(side.shadingNormal.z)), fx(broadcast(side.facingNormal.x)),
        fy(broadcast(side.facingNormal.y)), fz(broadcast(side.facingNormal.z)) {}
};

// The list positions of a block's lanes, advanced block by block: a lane is valid while its position
// is before the run's end. (Broadcasting the remaining count anew for every block cost GCC eight
// instructions per block, a fifth of the loop.)
struct LanePositions {
  Ints position, end;
  LUCENT_LANE_HELPER LanePositions(uint32_t first, uint32_t runEnd)
      : position(kLane + broadcast(int32_t(first))), end(broadcast(int32_t(runEnd))) {}
  LUCENT_LANE_HELPER Ints valid() const { return position < end; }
  LUCENT_LANE_HELPER void next() { position += kPhotonLanes; }
};

LUCENT_LANE_HELPER Block block(const PhotonColumns& c, uint32_t first, Ints valid, const ColumnQuery& q) {
  const Floats dx = loadLanes(&c.x[first]) - q.x, dy = loadLanes(&c.y[first]) - q.y, dz = loadLanes(&c.z[first]) - q.z;
  Block b;
  b.d2 = dx * dx + dy * dy + dz * dz;
  const Floats cosine =
      loadLanes(&c.incomingX[first]) * q.nx + loadLanes(&c.incomingY[first]) * q.ny + loadLanes(&c.incomingZ[first]) * q.nz;
  const Floats facing =
      loadLanes(&c.facingX[first]) * q.fx + loadLanes(&c.facingY[first]) * q.fy + loadLanes(&c.facingZ[first]) * q.fz;
  const Floats h = dx * q.fx + dy * q.fy + dz * q.fz;
  b.lights = (cosine > 0) & (facing > kSameSurfaceCos) & (h * h <= b.d2 * (1 - facing * facing + kOffPlane * kOffPlane));
  b.valid = valid;
  return b;
}

}  // namespace

LUCENT_LANE_LOOP(void, sumPhotonRun, (const PhotonColumns& c, uint32_t begin, uint32_t end, const SurfaceSide& side, KnnGridSearch& s,
                  PhotonLaneSums& sums)) {
  const ColumnQuery q(s.position, side);
  const uint32_t examinedBefore = s.photonsExamined;
  uint32_t i = begin;

  // While fewer than k are accepted: whole blocks as long as the k-th photon is not among them.
  if (s.found < s.k) {
    const Floats maxRadius2 = broadcast(s.maxRadius2);
    Floats r = loadLanes(sums.r), g = loadLanes(sums.g), b = loadLanes(sums.b);
    Ints used = loadLanes(sums.used);
    Floats farD2 = loadLanes(sums.farthestD2), farR = loadLanes(sums.farthestR), farG = loadLanes(sums.farthestG),
           farB = loadLanes(sums.farthestB);
    Ints farOrder = loadLanes(reinterpret_cast<const int32_t*>(sums.farthestOrder));
    Floats radius2 = broadcast(s.radius2);
    LanePositions lanes(i, end);
    for (; i < end && s.found < s.k; i += kPhotonLanes, lanes.next()) {
      const Block blk = block(c, i, lanes.valid(), q);
      const Ints accepted = (blk.d2 <= maxRadius2) & blk.valid;
      const int32_t accepting = count(accepted);
      if (s.found + uint32_t(accepting) > s.k) break;  // the k-th photon is in this block
      s.found += uint32_t(accepting);
      const Ints lit = accepted & blk.lights;
      const Floats pr = masked(loadLanes(&c.r[i]), lit), pg = masked(loadLanes(&c.g[i]), lit),
                   pb = masked(loadLanes(&c.b[i]), lit);
      r += pr, g += pg, b += pb, used -= lit;
      radius2 = accepted ? (blk.d2 > radius2 ? blk.d2 : radius2) : radius2;
      const Ints farther = accepted & (blk.d2 > farD2);
      farD2 = farther ? blk.d2 : farD2;
      farR = farther ? pr : farR, farG = farther ? pg : farG, farB = farther ? pb : farB;
      farOrder = farther ? broadcast(int32_t(examinedBefore + (i - begin))) + kLane : farOrder;
    }
    storeLanes(sums.r, r), storeLanes(sums.g, g), storeLanes(sums.b, b), storeLanes(sums.used, used);
    storeLanes(sums.farthestD2, farD2), storeLanes(sums.farthestR, farR), storeLanes(sums.farthestG, farG),
        storeLanes(sums.farthestB, farB);
    storeLanes(reinterpret_cast<int32_t*>(sums.farthestOrder), farOrder);
    for (int j = 0; j < kPhotonLanes; ++j) s.radius2 = std::max(s.radius2, radius2[j]);

    // The block holding the k-th photon, one photon at a time.
    if (i < end && s.found < s.k) {
      const Block blk = block(c, i, lanes.valid(), q);
      const uint32_t blockEnd = std::min(end, i + kPhotonLanes);
      for (int j = 0; i < blockEnd; ++i, ++j) {
        const float d2 = blk.d2[j];
        const bool growing = s.found < s.k;
        if (!(d2 <= (growing ? s.maxRadius2 : s.radius2))) continue;
        ++s.found;
        const bool lit = blk.lights[j] != 0;
        const float pr = lit ? c.r[i] : 0.0f, pg = lit ? c.g[i] : 0.0f, pb = lit ? c.b[i] : 0.0f;
        sums.r[j] += pr, sums.g[j] += pg, sums.b[j] += pb, sums.used[j] += lit;
        if (!growing) continue;
        s.radius2 = std::max(s.radius2, d2);
        if (d2 > sums.farthestD2[j]) {
          sums.farthestD2[j] = d2;
          sums.farthestR[j] = pr, sums.farthestG[j] = pg, sums.farthestB[j] = pb;
          sums.farthestOrder[j] = examinedBefore + (i - begin);
        }
      }
    }
  }

  // Then the radius stays: every photon within it.
  if (i < end) {
    const Floats radius2 = broadcast(s.radius2);
    Floats r = loadLanes(sums.r), g = loadLanes(sums.g), b = loadLanes(sums.b);
    Ints used = loadLanes(sums.used), found = {};
    for (LanePositions lanes(i, end); i < end; i += kPhotonLanes, lanes.next()) {
      const Block blk = block(c, i, lanes.valid(), q);
      const Ints accepted = (blk.d2 <= radius2) & blk.valid;
      const Ints lit = accepted & blk.lights;
      r += masked(loadLanes(&c.r[i]), lit), g += masked(loadLanes(&c.g[i]), lit), b += masked(loadLanes(&c.b[i]), lit);
      used -= lit, found -= accepted;
    }
    storeLanes(sums.r, r), storeLanes(sums.g, g), storeLanes(sums.b, b), storeLanes(sums.used, used);
    s.found += uint32_t(sum(found));
  }
  s.photonsExamined += end - begin;
}
LUCENT_LANE_VERSIONS(void, sumPhotonRun, (const PhotonColumns& c, uint32_t begin, uint32_t end, const SurfaceSide& side, KnnGridSearch& s,
                  PhotonLaneSums& sums), (c, begin, end, side, s, sums))

void resizeColumns(PhotonColumns& columns, uint32_t count) {
  for (UninitializedVector<float>* column :
       {&columns.x, &columns.y, &columns.z, &columns.incomingX, &columns.incomingY, &columns.incomingZ, &columns.facingX,
        &columns.facingY, &columns.facingZ, &columns.r, &columns.g, &columns.b}) {
    column->resize(size_t(count) + PhotonColumns::kPad);
    std::fill(column->begin() + ptrdiff_t(count), column->end(), 0.0f);
  }
}

void copyColumns(const PhotonColumns& from, uint32_t first, uint32_t count, PhotonColumns& to, uint32_t at) {
  auto copy = [&](const UninitializedVector<float>& f, UninitializedVector<float>& t) {
    std::memcpy(t.data() + at, f.data() + first, size_t(count) * sizeof(float));
  };
  copy(from.x, to.x), copy(from.y, to.y), copy(from.z, to.z);
  copy(from.incomingX, to.incomingX), copy(from.incomingY, to.incomingY), copy(from.incomingZ, to.incomingZ);
  copy(from.facingX, to.facingX), copy(from.facingY, to.facingY), copy(from.facingZ, to.facingZ);
  copy(from.r, to.r), copy(from.g, to.g), copy(from.b, to.b);
}

LUCENT_LANE_LOOP(GrowingRadius, growingRadius, (const PhotonColumns& c, uint32_t offered, Vec3 q, const SurfaceSide& side, float maxRadius2,
                  uint32_t k)) {
  const ColumnQuery query(q, side);
  const Floats limit2 = broadcast(maxRadius2);
  GrowingRadius g;
  // Whole blocks while the k-th photon is not among them; each lane keeps its farthest photon,
  // the first at that distance (a lane meets its entries in order).
  Floats farthest = broadcast(-1.0f);
  Ints farthestAt = {};
  uint32_t i = 0;
  LanePositions lanes(0, offered);
  for (; i < offered; i += kPhotonLanes, lanes.next()) {
    const Block blk = block(c, i, lanes.valid(), query);
    const Ints accepted = (blk.d2 <= limit2) & blk.valid;
    const uint32_t accepting = uint32_t(count(accepted));
    if (g.found + accepting >= k) break;
    g.found += accepting;
    const Ints farther = accepted & (blk.d2 > farthest);
    farthest = farther ? blk.d2 : farthest;
    farthestAt = farther ? lanes.position : farthestAt;
  }
  // The first photon at the largest distance: the lanes' by their entries.
  for (int j = 0; j < kPhotonLanes; ++j)
    if (farthest[j] > g.d2 || (farthest[j] == g.d2 && farthest[j] >= 0 && uint32_t(farthestAt[j]) < g.farthest))
      g.d2 = farthest[j], g.farthest = uint32_t(farthestAt[j]);
  g.examined = std::min(i + kPhotonLanes, offered);
  // The block holding the k-th photon, one photon at a time: its entries come after the others.
  if (i < offered) {
    const Block blk = block(c, i, lanes.valid(), query);
    for (int j = 0; j < kPhotonLanes && g.found < k; ++j) {
      if (!blk.valid[j] || !(blk.d2[j] <= maxRadius2)) continue;
      ++g.found;
      if (blk.d2[j] > g.d2) g.d2 = blk.d2[j], g.farthest = i + uint32_t(j);
    }
  }
  if (g.found == 0) return g;
  // Whether it lights the side, by the block's arithmetic.
  const uint32_t at = g.farthest & ~uint32_t(kPhotonLanes - 1);
  const Block blk = block(c, at, Ints{} - 1, query);
  if (blk.lights[g.farthest - at]) g.share = Rgb(c.r[g.farthest], c.g[g.farthest], c.b[g.farthest]);
  return g;
}
LUCENT_LANE_VERSIONS(GrowingRadius, growingRadius, (const PhotonColumns& c, uint32_t offered, Vec3 q, const SurfaceSide& side, float maxRadius2,
                  uint32_t k), (c, offered, q, side, maxRadius2, k))

LUCENT_LANE_LOOP(SphereSum, sumWithinRadius, (const PhotonColumns& c, std::span<const ColumnRun> runs, Vec3 q, const SurfaceSide& side,
                  float radius2)) {
  const ColumnQuery query(q, side);
  const Floats r2 = broadcast(radius2);
  Floats r = {}, g = {}, b = {}, farthest = broadcast(-1.0f);
  Ints used = {}, found = {};
  for (const ColumnRun& run : runs) {
    // Blocks at multiples of eight: entry i always goes to lane i mod 8 (see the header).
    const uint32_t end = run.first + run.count;
    const Ints begin = broadcast(int32_t(run.first));
    LanePositions lanes(run.first & ~uint32_t(kPhotonLanes - 1), end);
    for (uint32_t i = run.first & ~uint32_t(kPhotonLanes - 1); i < end; i += kPhotonLanes, lanes.next()) {
      const Block blk = block(c, i, lanes.valid() & (lanes.position >= begin), query);
      const Ints accepted = (blk.d2 <= r2) & blk.valid;
      const Ints lit = accepted & blk.lights;
      r += masked(loadLanes(&c.r[i]), lit), g += masked(loadLanes(&c.g[i]), lit), b += masked(loadLanes(&c.b[i]), lit);
      used -= lit, found -= accepted;
      farthest = accepted ? (blk.d2 > farthest ? blk.d2 : farthest) : farthest;
    }
  }
  SphereSum s;
  for (int j = 0; j < kPhotonLanes; ++j) {
    s.sum += Rgb(r[j], g[j], b[j]);
    s.farthestD2 = std::max(s.farthestD2, farthest[j]);
  }
  s.found = uint32_t(sum(found)), s.used = uint32_t(sum(used));
  return s;
}
LUCENT_LANE_VERSIONS(SphereSum, sumWithinRadius, (const PhotonColumns& c, std::span<const ColumnRun> runs, Vec3 q, const SurfaceSide& side,
                  float radius2), (c, runs, q, side, radius2))
#undef LUCENT_LANE_HELPER

PhotonRunTotals photonRunTotals(const PhotonLaneSums& sums) {
  PhotonRunTotals t;
  int far = -1;
  for (int j = 0; j < kPhotonLanes; ++j) {
    t.sum += Rgb(sums.r[j], sums.g[j], sums.b[j]);
    t.used += uint32_t(sums.used[j]);
    if (sums.farthestD2[j] < 0) continue;
    if (far < 0 || sums.farthestD2[j] > sums.farthestD2[far] ||
        (sums.farthestD2[j] == sums.farthestD2[far] && sums.farthestOrder[j] < sums.farthestOrder[far]))
      far = j;
  }
  if (far >= 0) {
    t.farthestD2 = sums.farthestD2[far];
    t.farthest = Rgb(sums.farthestR[far], sums.farthestG[far], sums.farthestB[far]);
  }
  return t;
}

}  // namespace lucent
