// What every lobe gives (see kinds.h): its flags, a value with its sampling density, a sample.
// Lobes work in the local shading frame: normal on +z, wo and wi pointing away from the surface.
#pragma once
#include <algorithm>
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

// What a lobe does to light, for methods to ask instead of naming material kinds: it reflects
// and/or transmits; its scattering is diffuse (Lambertian), glossy (a continuous lobe that depends
// on wo) and/or specular (Dirac deltas); it is two-sided (shaded alike from either side of the
// surface, the frame turned to the viewer) or keeps its winding's inside and outside (glass).
enum class BsdfFlags : uint32_t {
  None = 0,
  Reflection = 1,
  Transmission = 2,
  Diffuse = 4,
  Glossy = 8,
  Specular = 16,
  TwoSided = 32,
};
constexpr BsdfFlags operator|(BsdfFlags a, BsdfFlags b) { return BsdfFlags(uint32_t(a) | uint32_t(b)); }
constexpr bool has(BsdfFlags flags, BsdfFlags f) { return (uint32_t(flags) & uint32_t(f)) == uint32_t(f); }
// Only Dirac deltas: nothing to evaluate, no light to connect to (mirror, smooth glass).
constexpr bool onlySpecular(BsdfFlags f) { return has(f, BsdfFlags::Specular) && !has(f, BsdfFlags::Diffuse) && !has(f, BsdfFlags::Glossy); }
// Only a Lambertian term: its radiance is albedo / pi times the irradiance, whatever wo.
constexpr bool onlyDiffuse(BsdfFlags f) { return has(f, BsdfFlags::Diffuse) && !has(f, BsdfFlags::Glossy) && !has(f, BsdfFlags::Specular); }

// A lobe's parameter as dumps name it (src/render/dump_records.cpp): its name, whether it holds
// floats (else uint32), and its 4-byte words. A lobe lists its members in order, without padding.
struct LobeField {
  const char* name;
  bool isFloat;
  uint32_t count;
};
template <class Lobe>
constexpr uint32_t lobeFieldBytes() {
  uint32_t bytes = 0;
  for (const LobeField& f : Lobe::fields) bytes += 4 * f.count;
  return bytes;
}

// Radiance is transported from the camera; importance (photon flux) from the lights. They differ in
// refraction, where radiance is scaled by (eta_i / eta_t)^2 and flux is not (Veach 1997, 5.2).
enum class Transport { Radiance, Importance };

// A lobe's value f(wo, wi) and the density with which its sample picks wi, computed together.
struct BsdfValue {
  Rgb f;
  float pdf = 0;
};

struct BsdfSample {
  Vec3 wi;
  Rgb weight;       // f * |cos| / pdf (for delta lobes, the lobe's weight)
  float pdf = 0;    // solid angle; for delta lobes the discrete probability of the chosen lobe
  bool delta = false;
  bool valid = false;
};

// Per channel, part / whole clamped to 1, 0 where whole is: a term's share of a lobe's value.
inline Rgb channelShare(Rgb part, Rgb whole) {
  return {whole.r > 0 ? std::min(1.0f, part.r / whole.r) : 0.0f, whole.g > 0 ? std::min(1.0f, part.g / whole.g) : 0.0f,
          whole.b > 0 ? std::min(1.0f, part.b / whole.b) : 0.0f};
}

// A direction wi drawn from one lobe of a mixture, weighed by the whole mixture's value and density
// (`lobe.evaluate`, wo above the surface): valid where both are positive on the side the lobe
// scatters to, above the surface or (`through`, a transmitting lobe) below it.
template <class Lobe>
BsdfSample mixtureSample(const Lobe& lobe, Vec3 wo, Vec3 wi, bool through = false) {
  BsdfSample s;
  s.wi = wi;
  if (through ? !(s.wi.z < 0) : !(s.wi.z > 0)) return s;
  const BsdfValue v = lobe.evaluate(wo, s.wi);
  s.pdf = v.pdf;
  if (!(s.pdf > 0)) return s;
  s.weight = v.f * (std::abs(s.wi.z) / s.pdf);
  s.valid = true;
  return s;
}

// A lobe's flags where its parameters decide some (a glTF material transmits where its transmission
// is above 0): its instanceFlags(), else its kind's.
template <class Lobe>
constexpr BsdfFlags instanceFlags(const Lobe& lobe) {
  if constexpr (requires { lobe.instanceFlags(); })
    return lobe.instanceFlags();
  else
    return Lobe::flags;
}

}  // namespace lucent
