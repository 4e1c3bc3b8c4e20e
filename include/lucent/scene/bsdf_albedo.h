// A material's scattering measured without rendering (`lucent bsdf`): what a backend author holds
// their own BSDF to.
#pragma once
#include <cstdint>

#include "lucent/scene/bsdf.h"

namespace lucent {

// The directional albedo E(wo) = integral over the sphere of f(wo, wi) |cos theta_i| for radiance
// transport (light refracted into glass carries the (eta_i / eta_t)^2 of radiance), with wo at
// cos theta = cosTheta from the normal in the xz plane (for glass, negative from inside), estimated
// as the mean weight of `samples` BSDF samples (delta lobes included) drawn with numbers keyed by
// `seed`, with the standard error of that mean per channel.
struct AlbedoEstimate {
  Rgb albedo, standardError;
};
AlbedoEstimate directionalAlbedo(const SurfaceBsdf& bsdf, float cosTheta, uint32_t samples, uint64_t seed);

}  // namespace lucent
