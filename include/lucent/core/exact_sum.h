// A sum of floats whose value does not depend on the order of its terms, nor on how they were
// grouped into partial sums: the film's pixel sums, so that a render split into sample ranges or
// resumed from a checkpoint, then merged, gives the single render's image bit for bit. Fixed point
// with 96 integer and 96 fractional bits, two's complement in three 64-bit words: terms are exact
// to 2^-96 (smaller bits are dropped, toward zero), and up to 2^24 terms of magnitude at most
// kMaxTerm cannot overflow.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>

namespace lucent {

class ExactSum {
 public:
  static constexpr float kMaxTerm = 0x1p70f;  // 1.2e21
  static constexpr bool accepts(float x) { return std::abs(x) <= kMaxTerm; }  // false for NaN

  // x must satisfy accepts(x).
  void add(float x) {
    uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const uint32_t biased = (bits >> 23) & 0xffu;
    const uint64_t mantissa = (bits & 0x7fffffu) | (biased != 0 ? 0x800000u : 0u);
    // x = mantissa * 2^(max(biased, 1) - 150); in units of 2^-96 the mantissa's lowest bit is at
    // bit max(biased, 1) - 54. Up to bit 104 the term fits the low 128 bits (|x| < 2^32: nearly
    // every term); below bit 0 its lowest bits are dropped (|x| < 2^-73).
    const int shift = int(biased == 0 ? 1 : biased) - 54;
    Words term;
    if (shift >= 0 && shift <= 104) [[likely]] {
      term.low = Wide(mantissa) << shift;
    } else if (shift < 0) {
      if (shift <= -24) return;
      term.low = mantissa >> -shift;
    } else if (shift < 128) {
      term.low = Wide(mantissa) << shift;  // the bits that fit; the rest go to the high word
      term.high = mantissa >> (128 - shift);
    } else {
      term.high = mantissa << (shift - 128);
    }
    if (bits >> 31) term = term.negated();
    add(term);
  }
  void add(const ExactSum& other) { add(other.words()); }

  // The sum, rounded to a double (the same double for the same terms in any order).
  double value() const {
    const bool negative = w_[2] >> 63;
    const Words w = negative ? words().negated() : words();
    const double magnitude = double(w.high) * 0x1p128 + double(uint64_t(w.low >> 64)) * 0x1p64 + double(uint64_t(w.low));
    return (negative ? -magnitude : magnitude) * 0x1p-96;
  }
  bool operator==(const ExactSum& other) const = default;

 private:
  using Wide = unsigned __int128;
  // Bits 0-127 and 128-191 of the two's complement value.
  struct Words {
    Wide low = 0;
    uint64_t high = 0;
    Words negated() const {
      Words n;
      n.low = ~low + 1;
      n.high = ~high + (n.low == 0 ? 1 : 0);
      return n;
    }
  };
  Words words() const { return {Wide(w_[1]) << 64 | w_[0], w_[2]}; }
  void add(const Words& term) {
    const Wide before = Wide(w_[1]) << 64 | w_[0], low = before + term.low;
    w_[2] += term.high + (low < before ? 1 : 0);
    w_[0] = uint64_t(low), w_[1] = uint64_t(low >> 64);
  }
  uint64_t w_[3] = {0, 0, 0};  // little-endian: 64-bit words, not a 128-bit one, so that a sum is 24 bytes
};
static_assert(sizeof(ExactSum) == 24, "ExactSum is three 64-bit words (film files store them)");
}  // namespace lucent
