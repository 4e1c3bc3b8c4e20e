// The wavefront path tracer's shading of Lambertian hits, many paths at a time: the scene data and
// random numbers of each hit are fetched into a structure of arrays (one slot per path, a "lane"),
// then every step that is the same arithmetic for all lanes runs as one loop over the lanes, which
// the compiler vectorizes (eight lanes per instruction with AVX2, chosen at run time). Each lane
// computes exactly what PathTracer::shade computes for its path, in the same order, so images are
// bit-identical whichever code shades a hit.
#pragma once
#include <cstdint>

#include "lucent/core/rng.h"
#include "lucent/scene/camera.h"

namespace lucent {

inline constexpr int kMaxLanes = 128;

struct DiffuseLanes {
  uint32_t count = 0;
  // Fetched per lane (PathTracer::fetchDiffuseLane). Normals: ng* the triangle's geometric one,
  // normal* the vertex normals interpolated (not yet normalized).
  alignas(64) float dirX[kMaxLanes], dirY[kMaxLanes], dirZ[kMaxLanes];  // the incoming ray
  alignas(64) float posX[kMaxLanes], posY[kMaxLanes], posZ[kMaxLanes];           // the hit point
  alignas(64) float normalX[kMaxLanes], normalY[kMaxLanes], normalZ[kMaxLanes];  // vertex normals interpolated
  alignas(64) int32_t hasNormals[kMaxLanes];
  alignas(64) float ngx[kMaxLanes], ngy[kMaxLanes], ngz[kMaxLanes];  // the triangle's geometric normal
  alignas(64) float kdR[kMaxLanes], kdG[kMaxLanes], kdB[kMaxLanes];  // textured albedo
  alignas(64) int32_t emits[kMaxLanes];  // Ke not black: only then is gatherEmission called
  alignas(64) float uLight[kMaxLanes], uLightX[kMaxLanes], uLightY[kMaxLanes], uBsdfX[kMaxLanes], uBsdfY[kMaxLanes];
  alignas(64) uint32_t path[kMaxLanes];  // the wave's path in this lane

  // The light sample. Triangle lights (fetchDiffuseLane): vertices q*, normal, area and pmf; the
  // lanes sample the point. Other lights (sampleOtherLights): the finished sample, wi* to lightDelta.
  alignas(64) int32_t lightIsTriangle[kMaxLanes];
  alignas(64) float q0x[kMaxLanes], q0y[kMaxLanes], q0z[kMaxLanes], q1x[kMaxLanes], q1y[kMaxLanes],
      q1z[kMaxLanes], q2x[kMaxLanes], q2y[kMaxLanes], q2z[kMaxLanes];
  alignas(64) float lightNx[kMaxLanes], lightNy[kMaxLanes], lightNz[kMaxLanes], lightArea[kMaxLanes],
      lightPmf[kMaxLanes];
  alignas(64) float wiX[kMaxLanes], wiY[kMaxLanes], wiZ[kMaxLanes], lightDistance[kMaxLanes];
  alignas(64) float pointX[kMaxLanes], pointY[kMaxLanes], pointZ[kMaxLanes];
  alignas(64) float leR[kMaxLanes], leG[kMaxLanes], leB[kMaxLanes], lightPdf[kMaxLanes];
  alignas(64) int32_t lightDelta[kMaxLanes];

  // Computed (shadeDiffuseLanes): the shading normal and the side the viewer is on, for the
  // first-hit layers and emission; next-event estimation and BSDF sampling.
  alignas(64) float snX[kMaxLanes], snY[kMaxLanes], snZ[kMaxLanes];
  alignas(64) int32_t frontFace[kMaxLanes];
  alignas(64) int32_t shadowQueued[kMaxLanes];
  alignas(64) float shadowOx[kMaxLanes], shadowOy[kMaxLanes], shadowOz[kMaxLanes], shadowDx[kMaxLanes],
      shadowDy[kMaxLanes], shadowDz[kMaxLanes], shadowTMax[kMaxLanes];
  alignas(64) float directR[kMaxLanes], directG[kMaxLanes], directB[kMaxLanes];  // before the throughput
  alignas(64) int32_t scattered[kMaxLanes];
  alignas(64) float weightR[kMaxLanes], weightG[kMaxLanes], weightB[kMaxLanes], scatterPdf[kMaxLanes];
  alignas(64) float nextOx[kMaxLanes], nextOy[kMaxLanes], nextOz[kMaxLanes], nextDx[kMaxLanes],
      nextDy[kMaxLanes], nextDz[kMaxLanes];
};

// The camera samples of a wave: pixel, sample index and pixel corner in; each path's seeded
// generator (after the two jitter numbers) and camera ray direction out. The same numbers as
// seeding an Rng and calling PinholeCamera::generate one sample at a time.
struct CameraLanes {
  uint32_t count = 0;
  alignas(64) uint64_t pixel[kMaxLanes], sample[kMaxLanes];
  alignas(64) float x[kMaxLanes], y[kMaxLanes];
  alignas(64) Rng rng[kMaxLanes];
  alignas(64) float dirX[kMaxLanes], dirY[kMaxLanes], dirZ[kMaxLanes];
};
void startCameraPaths(CameraLanes& lanes, uint64_t seed, const PinholeCamera& camera);

// Every lane's shading normal and frame, its light sample's shadow ray and what it brings, and the
// cosine-distributed next direction.
void shadeDiffuseLanes(DiffuseLanes& lanes);

}  // namespace lucent
