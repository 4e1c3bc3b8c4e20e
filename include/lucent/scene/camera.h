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
  // generate's inverse: the image position (x, y) of a point, and (z) its distance along the view
  // axis, 0 or less for points not in front of the eye (whose x and y mean nothing).
  Vec3 project(Vec3 p) const {
    const Vec3 v = p - eye_;
    const float z = dot(v, forward_);
    if (!(z > 0)) return {0, 0, z};
    const float sx = dot(v, right_) / (z * dot(right_, right_)), sy = dot(v, up_) / (z * dot(up_, up_));
    return {(sx + 1.0f) * 0.5f * float(width_), (1.0f - sy) * 0.5f * float(height_), z};
  }
  // The angle a pixel subtends at the image's centre (radians, small-angle).
  float pixelAngle() const { return 2.0f * length(up_) / float(height_); }
  // A bound, in pixels, of the distance from the image of a sphere's centre to the image of any of
  // its points: they lie at least z - r in front of the eye and at most r aside, which the
  // projection stretches by 1 + tan(the centre's angle off the view axis). Infinite for a sphere
  // that reaches the eye's plane (z <= r).
  float sphereFootprint(Vec3 centre, float radius) const {
    const Vec3 p = project(centre);
    if (!(p.z > radius)) return kInf;
    const float offAxis = std::hypot(p.x - 0.5f * float(width_), p.y - 0.5f * float(height_)) * pixelAngle();
    return radius * (1.0f + offAxis) / ((p.z - radius) * pixelAngle());
  }

 private:
  int width_, height_;
  Vec3 eye_, forward_, right_, up_;
};

}  // namespace lucent
