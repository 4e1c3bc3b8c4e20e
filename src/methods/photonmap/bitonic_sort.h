// Bitonic merge sort (Batcher 1968), the sort of Purcell et al. 2003, section 2.2.1 (Fig. 2, 3).
#pragma once
#include <cstdint>
#include <vector>

namespace lucent {

// A (key, photon index) pair packed so that sorting the 64-bit values sorts by key, then by index.
// Every packed value is distinct, so the sorted order is unique: it equals std::sort's and does not
// depend on the network or the thread count.
constexpr uint64_t packSortKey(uint32_t key, uint32_t index) { return uint64_t(key) << 32 | index; }
constexpr uint32_t sortKeyOf(uint64_t packed) { return uint32_t(packed >> 32); }
constexpr uint32_t sortIndexOf(uint64_t packed) { return uint32_t(packed); }

// Compare distances below this many elements are merged block by block in cache (see .cpp).
inline constexpr uint32_t kBitonicLocalBlock = 4096;

// Sorts ascending, any size: pads to a power of two with +inf (all bits set), runs the O(log^2 n)
// compare-exchange stages, drops the padding. `localBlock` (a power of two >= 2) is the block within
// which short-distance stages are fused into one pass; it never changes the result.
void bitonicSort(std::vector<uint64_t>& values, uint32_t localBlock = kBitonicLocalBlock);

}  // namespace lucent
