// The radiance estimate of a Lambertian surface on the sorted and stencil grids, eight photons at a
// time. The kNN-grid reads a map's photons in runs (a row of cells whose photons are consecutive in
// the photon list); a run's photons are taken from the map's columns (a structure of arrays in list
// order) and accepted by the rule of examinePhotons (knn_grid.h): while fewer than k are accepted,
// any photon within the maximum radius, the radius growing to include it; afterwards those within
// the radius. The accepted photons' power is summed over those that light the viewer's side
// (photonLights), in
// eight lanes (lane j takes the run's photons j, j + 8, ...). Which photons are accepted, the radius
// and the counts are exactly examinePhotons'; only the order of the power sums differs.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/uninitialized.h"
#include "lucent/techniques/photons/photon.h"

namespace lucent {

struct KnnGridSearch;

// A map's listed photons as columns, padded with kPad zero entries so that eight photons can be
// loaded from any position of the list (the lanes past the end are masked out).
struct PhotonColumns {
  static constexpr uint32_t kPad = 8;
  UninitializedVector<float> x, y, z;                          // position
  UninitializedVector<float> incomingX, incomingY, incomingZ;  // octahedralDirection: the side it came from
  UninitializedVector<float> facingX, facingY, facingZ;        // photonFacing
  UninitializedVector<float> r, g, b;                          // power
};

PhotonColumns photonColumns(std::span<const Photon> listed);

inline constexpr int kPhotonLanes = 8;

// One estimate's running sums, per lane.
struct alignas(32) PhotonLaneSums {
  float r[kPhotonLanes] = {}, g[kPhotonLanes] = {}, b[kPhotonLanes] = {};
  int32_t used[kPhotonLanes] = {};  // accepted and lighting the viewer's side
  // The lane's farthest photon accepted while the radius grew: the first in search order at the
  // largest distance, its share of the sum, and its place in the search (to break ties between lanes).
  float farthestD2[kPhotonLanes] = {-1, -1, -1, -1, -1, -1, -1, -1};
  float farthestR[kPhotonLanes] = {}, farthestG[kPhotonLanes] = {}, farthestB[kPhotonLanes] = {};
  uint32_t farthestOrder[kPhotonLanes] = {};
};

// Entries [begin, end) of the list offered to the search s at a point whose side is `side`:
// s.found, s.radius2 and s.photonsExamined are updated as examinePhotons (knn_grid.h) updates them;
// keep the two rules in step.
void sumPhotonRun(const PhotonColumns& columns, uint32_t begin, uint32_t end, const SurfaceSide& side,
                  KnnGridSearch& s, PhotonLaneSums& sums);

// The lanes' totals: the power sum, the photons in it, and the farthest photon (the first met at
// the largest distance; d2 -1 when none was accepted) with its share.
struct PhotonRunTotals {
  Rgb sum, farthest;
  float farthestD2 = -1;
  uint32_t used = 0;
};
PhotonRunTotals photonRunTotals(const PhotonLaneSums& sums);

// Entries [first, first + count) of `from` appended to `to`'s first `at` entries (`to` holds at
// least at + count + kPad entries).
void copyColumns(const PhotonColumns& from, uint32_t first, uint32_t count, PhotonColumns& to, uint32_t at);
// Sizes every column for `count` photons (entries kept or left unwritten) and the padding (zeros).
void resizeColumns(PhotonColumns& columns, uint32_t count);

// The growing radius of a search (examinePhotons in knn_grid.h) offered the first `offered` photons
// of `c` in order: the first k of them within the maximum radius (found of them, if fewer), their
// farthest squared distance (-1: none), the first of them at it, and its share of the estimate at
// a point whose side is `side` (its power if it lights that side, else nothing).
struct GrowingRadius {
  uint32_t found = 0;
  float d2 = -1;
  uint32_t farthest = 0;
  Rgb share;
  uint32_t examined = 0;  // entries read
};
GrowingRadius growingRadius(const PhotonColumns& c, uint32_t offered, Vec3 q, const SurfaceSide& side, float maxRadius2,
                            uint32_t k);

// Entries [first, first + count) of a map's columns.
struct ColumnRun {
  uint32_t first = 0, count = 0;
};

// Of the photons of `c` in `runs`, those within squared radius radius2 of q: how many, the farthest
// one's squared distance (-1: none), and the power of those that light `side` (used of them).
// Entry i is summed in lane i mod 8, and the lanes' sums are added in order, so that the sum
// depends only on the photons accepted, not on the runs that hold them, as long as the runs are
// in list order: a sphere read from a box of cells or from its own rows gives the same bits.
struct SphereSum {
  Rgb sum;
  uint32_t found = 0, used = 0;
  float farthestD2 = -1;
};
SphereSum sumWithinRadius(const PhotonColumns& c, std::span<const ColumnRun> runs, Vec3 q, const SurfaceSide& side,
                          float radius2);

}  // namespace lucent
