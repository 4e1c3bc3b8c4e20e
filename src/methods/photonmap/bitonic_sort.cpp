// Bitonic merge sort as data-parallel stages (Purcell et al. 2003, section 2.2.1).
//
// Stage (k, j) of the network compares element a with a + j for every a whose bit j is clear, in
// ascending order where bit k of a is clear and descending otherwise (Fig. 2; the `csign`/`cdir`
// of Fig. 3). Pairs with consecutive a form runs of length j, compare-exchanged by one branch-free
// loop that the compiler vectorizes. Stages with j < localBlock only touch elements within aligned
// blocks of localBlock elements, so one work item runs all of them for its block while it is in
// cache, like a GPU thread block in shared memory; the network, and so the result, is unchanged.
#include "bitonic_sort.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>

#include "lucent/core/stop.h"

namespace lucent {
namespace {

// x[t] <-> y[t], the smaller to x when ascending. Masks instead of branches, and the 64-bit compare
// split into two 32-bit ones because SSE2 has no 64-bit compare: GCC vectorizes this loop
// (-fopt-info-vec reports "loop vectorized using 16 byte vectors").
template <bool Ascending>
void compareExchangeRuns(uint64_t* __restrict x, uint64_t* __restrict y, uint64_t len) {
  for (uint64_t t = 0; t < len; ++t) {
    const uint64_t a = x[t], b = y[t];
    const uint32_t ah = uint32_t(a >> 32), bh = uint32_t(b >> 32), al = uint32_t(a), bl = uint32_t(b);
    const uint64_t swap = 0 - uint64_t((ah > bh) | ((ah == bh) & (al > bl)));
    const uint64_t lo = (a & ~swap) | (b & swap), hi = (b & ~swap) | (a & swap);
    x[t] = Ascending ? lo : hi;
    y[t] = Ascending ? hi : lo;
  }
}

// Pairs [p0, p1) of stage (k, j): pair p starts at a = 2p - (p mod j).
void compareExchangePairs(uint64_t* v, uint64_t k, uint64_t j, uint64_t p0, uint64_t p1) {
  if (j == 1) {  // runs of one: a plain loop beats a vector loop per pair
    for (uint64_t p = p0; p < p1; ++p) {
      const uint64_t a = 2 * p;
      if (a & k) compareExchangeRuns<false>(v + a, v + a + 1, 1);
      else compareExchangeRuns<true>(v + a, v + a + 1, 1);
    }
    return;
  }
  for (uint64_t p = p0; p < p1;) {
    const uint64_t t = p & (j - 1), a = 2 * p - t, len = std::min(j - t, p1 - p);
    if (a & k) compareExchangeRuns<false>(v + a, v + a + j, len);
    else compareExchangeRuns<true>(v + a, v + a + j, len);
    p += len;
  }
}

// One work item per block of `block` elements runs, for k = kFirst .. kLast, the stages (k, j) with
// j < block.
void localStages(uint64_t* v, uint64_t n, uint64_t block, uint64_t kFirst, uint64_t kLast) {
  tbb::parallel_for(uint64_t(0), n / block, [&](uint64_t b) {
    stopPoint();
    const uint64_t p0 = b * block / 2, p1 = p0 + block / 2;
    for (uint64_t k = kFirst; k <= kLast; k *= 2)
      for (uint64_t j = std::min(k, block) / 2; j >= 1; j /= 2) compareExchangePairs(v, k, j, p0, p1);
  });
}

}  // namespace

void bitonicSort(std::vector<uint64_t>& values, uint32_t localBlock) {
  const size_t n = values.size();
  if (n < 2) return;
  const uint64_t padded = std::bit_ceil(uint64_t(n));
  values.resize(padded, ~uint64_t(0));
  uint64_t* v = values.data();
  const uint64_t block = std::min<uint64_t>(padded, std::bit_ceil(std::max<uint64_t>(localBlock, 2)));
  constexpr uint64_t kPairsPerItem = 1 << 14;

  // Merges of size k <= block never leave a block.
  localStages(v, padded, block, 2, block);
  for (uint64_t k = 2 * block; k <= padded; k *= 2) {
    for (uint64_t j = k / 2; j >= block; j /= 2)  // one pass over all pairs per stage
      tbb::parallel_for(tbb::blocked_range<uint64_t>(0, padded / 2, kPairsPerItem),
                        [&](const auto& r) {
                          stopPoint();
                          compareExchangePairs(v, k, j, r.begin(), r.end());
                        });
    localStages(v, padded, block, k, k);
  }
  values.resize(n);
}

}  // namespace lucent
