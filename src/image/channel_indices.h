// What the image comparisons share: their size check and the lookup of R, G, B channels.
#pragma once
#include <array>
#include <stdexcept>
#include <string>

#include "lucent/image/image.h"

namespace lucent {

inline void requireSameSize(int width, int height, int referenceWidth, int referenceHeight) {
  if (width != referenceWidth || height != referenceHeight)
    throw std::invalid_argument("image sizes differ: " + std::to_string(width) + "x" + std::to_string(height) +
                                " vs reference " + std::to_string(referenceWidth) + "x" +
                                std::to_string(referenceHeight));
}
inline void requireSameSize(const Image& image, const Image& reference) {
  requireSameSize(image.width(), image.height(), reference.width(), reference.height());
}

// The indices of the channels prefix + "R", "G", "B"; -1 where absent, or, when `role` names the
// image ("the reference"), an error naming the missing channel.
inline std::array<int, 3> rgbIndices(const Image& image, const std::string& prefix, const std::string& role,
                                     const std::string& remedy = "") {
  std::array<int, 3> at{};
  for (int c = 0; c < 3; ++c) {
    const std::string name = prefix + std::string(1, "RGB"[c]);
    at[size_t(c)] = image.channelIndex(name);
    if (at[size_t(c)] < 0 && !role.empty())
      throw std::invalid_argument(role + " has no " + name + " channel" + remedy);
  }
  return at;
}

}  // namespace lucent
