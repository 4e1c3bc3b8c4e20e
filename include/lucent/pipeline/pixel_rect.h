// A rectangle of an image's pixels: a crop, a tile, a band of rows.
#pragma once
#include <cstdint>

namespace lucent {

// The pixels [x0, x1) x [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  uint64_t pixelCount() const { return uint64_t(width()) * uint64_t(height()); }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  // Whether `inner` lies inside this rectangle.
  bool contains(const PixelRect& inner) const {
    return inner.x0 >= x0 && inner.y0 >= y0 && inner.x1 <= x1 && inner.y1 <= y1;
  }
  bool operator==(const PixelRect&) const = default;
};

}  // namespace lucent
