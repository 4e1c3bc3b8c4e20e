// Sobol's low-discrepancy sequence in its first dimensions, with Owen scrambling by hashing
// (Laine and Karras 2011's nested uniform scramble, with Burley 2020's constants): a scrambled
// sequence keeps the stratification of every elementary interval of the unscrambled one in base 2,
// and is an unbiased estimator's samples for any seed.
#pragma once
#include <array>
#include <cstdint>

namespace lucent {

inline constexpr int kSobolDimensions = 3;

namespace sobol_detail {

constexpr uint32_t reverseBits(uint32_t v) {
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
  return (v >> 16) | (v << 16);
}

// Direction numbers v_k = m_k 2^(32 - k), k = 1 .. 32, of a dimension with primitive polynomial of
// degree s and coefficients a (Bratley and Fox 1988; the initial m of Joe and Kuo 2008); the first
// dimension is the van der Corput sequence (all m_k = 1).
constexpr std::array<uint32_t, 32> directions(int s, uint32_t a, std::array<uint32_t, 2> m0, bool first) {
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
    directions(0, 0, {0, 0}, true),     // x: van der Corput
    directions(1, 0, {1, 0}, false),    // x + 1
    directions(2, 1, {1, 3}, false)};   // x^2 + x + 1

}  // namespace sobol_detail

// The index-th point's coordinate in `dimension` (0 .. kSobolDimensions - 1) as 32 bits, unscrambled.
constexpr uint32_t sobolBits(uint32_t index, int dimension) {
  uint32_t x = 0;
  for (int k = 0; index != 0; index >>= 1, ++k)
    if (index & 1u) x ^= sobol_detail::kDirections[size_t(dimension)][size_t(k)];
  return x;
}

// Owen's nested uniform scramble of 32 bits keyed by `seed`: each bit flipped by a hash of the bits
// above it.
constexpr uint32_t owenScramble(uint32_t v, uint32_t seed) {
  v = sobol_detail::reverseBits(v);
  v ^= v * 0x3d20adeau;
  v += seed;
  v *= (seed >> 16) | 1u;
  v ^= v * 0x05526c56u;
  v ^= v * 0x53a22864u;
  return sobol_detail::reverseBits(v);
}

// The scrambled coordinate in [0, 1) (24 bits, so never 1).
constexpr float sobolSample(uint32_t index, int dimension, uint32_t seed) {
  return float(owenScramble(sobolBits(index, dimension), seed) >> 8) * 0x1p-24f;
}

}  // namespace lucent
