// Stable parallel LSD radix sort of (key, value) pairs by the low `keyBits` bits of the key. Blocks
// of fixed size count their digits, one exclusive scan over (digit, block) places them, and each
// block scatters its elements in order: stable, and the same result for any thread count. Equal keys
// keep their input order, so sorting (key, index) pairs by key alone orders them by (key, index).
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "lucent/core/stop.h"


namespace lucent::points {

template <class Value>
void radixSortByKey(std::vector<uint64_t>& keys, std::vector<Value>& values, uint32_t keyBits,
                    std::vector<uint64_t>& keyScratch, std::vector<Value>& valueScratch) {
  constexpr uint32_t kDigitBits = 11, kBuckets = 1u << kDigitBits;
  constexpr size_t kBlock = size_t(1) << 16;
  const size_t n = keys.size();
  if (n < 2 || keyBits == 0) return;
  keyScratch.resize(n);
  valueScratch.resize(n);
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<uint32_t> offsets(blocks * kBuckets);
  for (uint32_t shift = 0; shift < keyBits; shift += kDigitBits) {
    // Per block, the count of each digit.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& r) {
      stopPoint();
      for (size_t b = r.begin(); b != r.end(); ++b) {
        uint32_t* count = &offsets[b * kBuckets];
        std::fill(count, count + kBuckets, 0u);
        for (size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i) ++count[(keys[i] >> shift) & (kBuckets - 1)];
      }
    });
    // Where each block's run of each digit starts: digits in order, blocks in order within a digit.
    uint32_t sum = 0;
    for (uint32_t d = 0; d < kBuckets; ++d)
      for (size_t b = 0; b < blocks; ++b) {
        const uint32_t c = offsets[b * kBuckets + d];
        offsets[b * kBuckets + d] = sum;
        sum += c;
      }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& r) {
      stopPoint();
      for (size_t b = r.begin(); b != r.end(); ++b) {
        uint32_t* next = &offsets[b * kBuckets];
        for (size_t i = b * kBlock, e = std::min(n, i + kBlock); i < e; ++i) {
          const uint32_t at = next[(keys[i] >> shift) & (kBuckets - 1)]++;
          keyScratch[at] = keys[i];
          valueScratch[at] = values[i];
        }
      }
    });
    keys.swap(keyScratch);
    values.swap(valueScratch);
  }
}

}  // namespace lucent::points
