// A perfect mirror with reflectance `tint`: a Dirac delta in the mirror direction.
#pragma once
#include "lucent/scene/bsdf/lobe.h"

namespace lucent {

struct MirrorLobe {
  Rgb tint;
  static constexpr LobeField fields[] = {{"tint", true, 3}};

  static constexpr BsdfFlags flags = BsdfFlags::Reflection | BsdfFlags::Specular | BsdfFlags::TwoSided;
  BsdfValue evaluate(Vec3, Vec3) const { return {}; }
  BsdfSample sample(Vec3 wo, float, Vec2, Transport) const {
    BsdfSample s;
    if (wo.z <= 0) return s;
    s.wi = {-wo.x, -wo.y, wo.z};
    s.weight = tint;
    s.pdf = 1;
    s.delta = s.valid = true;
    return s;
  }
  Rgb albedo() const { return tint; }
  Rgb bound() const { return tint; }
  Rgb diffuse() const { return Rgb(0.0f); }
  Rgb diffuseShare(Vec3, Vec3) const { return Rgb(0.0f); }
};
static_assert(sizeof(MirrorLobe) == lobeFieldBytes<MirrorLobe>(), "a lobe is a plain record of its fields");

}  // namespace lucent
