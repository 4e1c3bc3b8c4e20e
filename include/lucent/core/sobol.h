// Sobol's low-discrepancy sequence in its first dimensions, with Owen scrambling by hashing
// (Laine and Karras 2011's nested uniform scramble, with Burley 2020's constants): a scrambled
// sequence keeps the stratification of every elementary interval of the unscrambled one in base 2,
// and is an unbiased estimator's samples for any seed.
#pragma once
#include <array>
#include <cstdint>

namespace lucent {

inline constexpr int kSobolDimensions = 4;

namespace sobol_detail {

constexpr uint32_t reverseBits(uint32_t v) {
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  return __builtin_bswap32(v);
}

// Direction numbers v_k = m_k 2^(32 - k), k = 1 .. 32, of a dimension with primitive polynomial of
// degree s and coefficients a (Bratley and Fox 1988; the initial m of Joe and Kuo 2008); the first
// dimension is the van der Corput sequence (all m_k = 1).
constexpr std::array<uint32_t, 32> directions(int s, uint32_t a, std::array<uint32_t, 3> m0, bool first) {
  std::array<uint32_t, 32> v{};
  std::array<uint64_t, 33> m{};
  for (int k = 1; k <= 32; ++k) {
    if (first) {
      m[k] = 1;
    } else if (k <= s) {
      m[k] = m0[k - 1];
    } else {
      uint64_t mk = m[k - s] ^ (m[k - s] << s);
      for (int j = 1; j < s; ++j)
        if ((a >> (s - 1 - j)) & 1u) mk ^= m[k - j] << j;
      m[k] = mk;
    }
    v[k - 1] = uint32_t(m[k] << (32 - k));
  }
  return v;
}

inline constexpr std::array<std::array<uint32_t, 32>, kSobolDimensions> kDirections = {
    directions(0, 0, {0, 0, 0}, true),    // x: van der Corput
    directions(1, 0, {1, 0, 0}, false),   // x + 1
    directions(2, 1, {1, 3, 0}, false),   // x^2 + x + 1
    directions(3, 1, {1, 3, 1}, false)};  // x^3 + x + 1

}  // namespace sobol_detail

// The index-th point's coordinate in `dimension` (0 .. kSobolDimensions - 1) as 32 bits, unscrambled.
constexpr uint32_t sobolBits(uint32_t index, int dimension) {
  uint32_t x = 0;
  for (int k = 0; index != 0; index >>= 1, ++k)
    if (index & 1u) x ^= sobol_detail::kDirections[size_t(dimension)][size_t(k)];
  return x;
}

namespace sobol_detail {

// Laine and Karras's permutation of bit-reversed values: each bit flipped by a hash of the bits
// below it (the bits above it in the unreversed value).
constexpr uint32_t laineKarras(uint32_t v, uint32_t seed) {
  v ^= v * 0x3d20adeau;
  v += seed;
  v *= (seed >> 16) | 1u;
  v ^= v * 0x05526c56u;
  v ^= v * 0x53a22864u;
  return v;
}

// For dimensions 1 to 3, per byte of the index, the XOR of the bit-reversed direction numbers its
// set bits select, at ((dimension - 1) * 4 + byte) * 256 + value: reverseBits(sobolBits(i, d)) is
// four lookups. One flat table, so that lanes of different dimensions gather from it alike.
constexpr std::array<uint32_t, 3 * 4 * 256> reversedByteTables() {
  std::array<uint32_t, 3 * 4 * 256> t{};
  for (int d = 1; d <= 3; ++d)
    for (int b = 0; b < 4; ++b)
      for (uint32_t v = 0; v < 256; ++v) {
        uint32_t x = 0;
        for (int k = 0; k < 8; ++k)
          if ((v >> k) & 1u) x ^= reverseBits(kDirections[size_t(d)][size_t(8 * b + k)]);
        t[size_t(((d - 1) * 4 + b) * 256) + v] = x;
      }
  return t;
}
inline constexpr std::array<uint32_t, 3 * 4 * 256> kReversedByteTables = reversedByteTables();
[[gnu::always_inline]] constexpr uint32_t reversedCoordinate(uint32_t dimension, uint32_t index) {
  const uint32_t* t = kReversedByteTables.data();
  const int32_t base = int32_t(dimension - 1) * 1024;
  return t[base + int32_t(index & 0xffu)] ^ t[base + 256 + int32_t((index >> 8) & 0xffu)] ^
         t[base + 512 + int32_t((index >> 16) & 0xffu)] ^ t[base + 768 + int32_t(index >> 24)];
}

}  // namespace sobol_detail

// Owen's nested uniform scramble of 32 bits keyed by `seed`: each bit flipped by a hash of the bits
// above it.
constexpr uint32_t owenScramble(uint32_t v, uint32_t seed) {
  return sobol_detail::reverseBits(sobol_detail::laineKarras(sobol_detail::reverseBits(v), seed));
}

// Two dimensions' scrambled coordinates of the point whose index is shuffled by Owen's scramble
// keyed by `shuffleSeed` (Burley 2020), the first two or (`second`) the third and fourth:
// owenScramble(sobolBits(owenScramble(index, shuffleSeed), d), seed) for d = 0, 1 (seedX, seedY) or
// d = 2, 3, with half the bit reversals. The two pairs of one index and shuffle are one point of the
// four-dimensional sequence.
[[gnu::always_inline]] constexpr std::array<uint32_t, 2> shuffledSobolPair(uint32_t index, uint32_t shuffleSeed,
                                                                          uint32_t seedX, uint32_t seedY,
                                                                          bool second = false) {
  using namespace sobol_detail;
  const uint32_t shuffled = reverseBits(laineKarras(reverseBits(index), shuffleSeed));
  // The first dimension is the bit reversal of the index: reversed, the index itself.
  const uint32_t third = reversedCoordinate(2, shuffled);
  const uint32_t reversedX = second ? third : shuffled;
  const uint32_t reversedY = reversedCoordinate(second ? 3u : 1u, shuffled);
  return {reverseBits(laineKarras(reversedX, seedX)), reverseBits(laineKarras(reversedY, seedY))};
}

// The scrambled coordinate in [0, 1) (24 bits, so never 1).
constexpr float sobolSample(uint32_t index, int dimension, uint32_t seed) {
  return float(owenScramble(sobolBits(index, dimension), seed) >> 8) * 0x1p-24f;
}

}  // namespace lucent
