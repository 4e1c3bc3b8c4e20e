// Pinhole camera rays.
#pragma once
#include <cmath>

#include "lucent/scene/scene.h"

namespace lucent {

class PinholeCamera {
 public:
  explicit PinholeCamera(const Camera& c) : width_(c.width), height_(c.height), eye_(c.eye) {
    forward_ = normalize(c.lookAt - c.eye);
    right_ = normalize(cross(forward_, c.up));
    up_ = cross(right_, forward_);
    const float tanHalf = std::tan(0.5f * c.fovY * kPi / 180.0f);
    up_ = up_ * tanHalf;
    right_ = right_ * (tanHalf * float(c.width) / float(c.height));
  }
  Vec3 eye() const { return eye_; }
  // Ray through image position (px, py) in pixels, (0,0) the top-left corner of the image.
  Ray generate(float px, float py) const {
    const float sx = 2.0f * px / width_ - 1.0f, sy = 1.0f - 2.0f * py / height_;
    return {eye_, normalize(forward_ + right_ * sx + up_ * sy)};
  }

 private:
  int width_, height_;
  Vec3 eye_, forward_, right_, up_;
};

}  // namespace lucent
