// The micro-buffer (Ritschel et al. 2009, 2.2 and 3.1): a tiny frame buffer per gather point whose
// pixels each hold the nearest visible node of the point hierarchy, as the paper packs them: the
// node's index in 24 bits and its depth in 8 bits of one 32-bit word.
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace lucent {

// Buffer sides the paper uses (8 x 8 to 24 x 24) and up to 32 x 32.
inline constexpr int kMinMicroBufferSide = 8;
inline constexpr int kMaxMicroBufferSide = 32;
// Interior nodes are splatted when at most a pixel's solid angle (the paper's criterion) and at most
// MicroRenderSettings::splatReach pixel spacings wide (HemisphereMapping::spacing): into their
// pixel's 3 x 3 neighbourhood, or 5 x 5 when wider than one spacing. Wider ones are refined.
constexpr int kMaxSplatReach = 2;

// 24 index bits hold heap numbers up to 2^24 - 1: at most 2^23 leaves (3.1).
inline constexpr uint32_t kMicroIndexBits = 24;
inline constexpr uint32_t kMicroIndexMask = (1u << kMicroIndexBits) - 1;
inline constexpr uint32_t kMaxMicroRenderPoints = 1u << 23;
inline constexpr uint32_t kEmptyMicroPixel = 0xffffffffu;
inline constexpr uint32_t kMaxDepthCode = 254;  // 255 with index 2^24 - 1 is the empty pixel

// Depth in 8 bits, logarithmic over 12 octaves below the scene's extent: 254 / 12 codes per unit of
// log2Bits (below; codesPerOctave counts those units), 15 to 29 per octave, so depths 4.8% apart get
// different codes at any distance. Nearer than 2^-12 of the extent (up to 6% beyond it, as
// log2Bits reads low) is code 0. With the depth in the high byte, "nearer, then lower
// node index" is one unsigned comparison of packed words (the order an atomicMin would keep on a
// GPU).
struct DepthCoding {
  float logNear = 0;   // log2 of the distance coded 0
  float codesPerOctave = 254.0f / 12.0f;

  static DepthCoding forExtent(float sceneExtent) {
    DepthCoding c;
    c.logNear = std::log2(std::max(sceneExtent, 1e-30f)) - 12.0f;
    return c;
  }
  // log2 as a positive float's bits read it: the exponent plus the mantissa taken linearly, within
  // 0.086 of log2, monotonic, and a few instructions where log2f is a call (gathering 1.5% faster).
  static float log2Bits(float x) { return float(std::bit_cast<int32_t>(x)) * 0x1p-23f - 127.0f; }
  uint32_t code(float distance) const {
    const float x = (log2Bits(std::max(distance, 1e-30f)) - logNear) * codesPerOctave;
    return x <= 0 ? 0u : uint32_t(std::min(x, float(kMaxDepthCode)));
  }
};

// The node of a pixel that sees a surface from its back side (any node seen from behind: node 0 is
// no node, the root being 1): it hides what lies beyond and sends no light, as the back of a
// one-sided surface does in the path tracer's closed rooms.
inline constexpr uint32_t kBackFaceMicroNode = 0;

constexpr uint32_t packMicroPixel(uint32_t depthCode, uint32_t node) { return depthCode << kMicroIndexBits | node; }
// A pixel below the gather point's geometric surface (GatherPoint::surfaceNormal): the surface
// itself, nearer than any node, so no splat or ray replaces it.
inline constexpr uint32_t kSurfaceItselfPixel = packMicroPixel(0, kBackFaceMicroNode);
constexpr uint32_t microPixelNode(uint32_t pixel) { return pixel & kMicroIndexMask; }
constexpr uint32_t microPixelDepth(uint32_t pixel) { return pixel >> kMicroIndexBits; }
// Whether a pixel shows a node's front, whose light it then receives (not empty, not a back face).
constexpr bool microPixelShowsNode(uint32_t pixel) {
  return pixel != kEmptyMicroPixel && microPixelNode(pixel) != kBackFaceMicroNode;
}

}  // namespace lucent
