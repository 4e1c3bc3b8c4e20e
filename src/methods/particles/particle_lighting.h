// The lighting stage (4.2): light from the light sources into the area particles they reach
// (4.2.1), then scattered along the particle links (4.2.2, Fig. 5), and the particles' reflected
// radiance from the flux they hold.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"
#include "methods/particles/area_particles.h"
#include "methods/particles/particle_links.h"

namespace lucent {

// Stage L1: each particle's flux straight from the lights, Delta A times its irradiance. For a
// point light of power Phi that is the paper's Phi / (4 pi) * Delta A cos(theta) / d^2 with one
// shadow ray; a directional light gives E_perp cos(theta) Delta A with one; area lights and the
// environment are sampled with `samples` shadow rays per particle (pipeline/direct_light.h).
// Particles whose normal faces away from a light get none of it. Adds the shadow rays to `rays`.
std::vector<Rgb> emitLight(const Scene& scene, const Visibility& vis, std::span<const AreaParticle> particles,
                           int samples, uint64_t seed, uint64_t& rays);

struct ScatterCounters {
  uint64_t litParticles = 0;  // work items: particles with direct light
  uint64_t deposits = 0;      // packets of flux that reached a particle
  uint64_t lost = 0;          // packets that left along a link without a particle
};

// Stage L2 (Fig. 5): every lit particle i sends rho_i phi_i / n_s^2 along each of its n_s^2
// scattering links (the first bounce), and each of these packets then goes on for bounces - 1 more
// bounces, each along one link of the particle it reached chosen at random, carrying rho times
// itself (notes A4: the packet, not the particle's flux, so that energy is not multiplied). So
// `bounces` is n_b, the scattering bounces in all (5.1's reading: the image holds n_b + 1 indirect
// bounces with the gathering). Returns each particle's flux: its direct flux plus what arrived.
// Flux is summed in 64-bit fixed point, whose additions commute, so the result does not depend on
// the order in which threads add (a GPU backend would use 64-bit atomic adds alike).
std::vector<Rgb> scatterLight(std::span<const AreaParticle> particles, std::span<const Rgb> directFlux,
                              const ParticleLinks& links, int bounces, uint64_t seed, ScatterCounters& counters);

// 4.2.2: a particle's reflected radiance from its flux, L = (rho / pi) phi / Delta A.
inline Rgb particleRadiance(const AreaParticle& p, Rgb flux) { return p.reflectance * flux * (kInvPi / p.area); }

// Stage R3 (4.3.1) at one particle: the irradiance from its gathering links' end particles,
// E = (pi / N) sum_k L(k*), a link without a particle giving nothing. The links are cosine-
// distributed, so this is the Monte Carlo estimate of the irradiance with pdf cos / pi.
inline Rgb gatherIrradiance(std::span<const uint32_t> links, std::span<const Rgb> radiance) {
  Rgb sum;
  for (uint32_t k : links)
    if (k != kNoParticle) sum += radiance[k];
  return sum * (kPi / float(links.size()));
}

}  // namespace lucent
