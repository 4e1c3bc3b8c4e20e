// The kernels of backends/opencl/kernels run on a Lucent dump (docs/dump-format.md), and their
// results compared with the dump's own arrays: what a GPU backend's author runs first, on their
// device, before porting a stage of their own.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/techniques/photons/kd_tree.h"
#include "opencl_device.h"

namespace lucent::opencl {

// A record or one of its fields (record_fields.h): offset and size in bytes; a record's entry has
// an empty field, offset 0 and the record's size.
struct FieldLayout {
  std::string record, field;
  uint32_t offset = 0, size = 0;
};
// As the C++ compiler lays out Lucent's structs.
std::vector<FieldLayout> cppRecordLayout();
// As the device's OpenCL C compiler lays out `recordsSource` (kernels/records.cl's text, unless a
// test hands it another).
std::vector<FieldLayout> openclRecordLayout(const Device& device, const std::string& recordsSource);
// One line per entry whose offset or size differ between the two ("Photon.flags: offset 28 in
// C++, 32 in OpenCL C"); empty when they agree.
std::vector<std::string> layoutDifferences(const std::vector<FieldLayout>& cpp, const std::vector<FieldLayout>& cl);

// Each kernel's results are written as dump arrays of the same names as the reference's into a
// candidate directory, which `lucent check-dump` (compareDumpDirectories) compares with it. Values
// a kernel does not compute (the CPU's part of a stage) are copied from the reference and counted.

// Purcell's kNN-grid estimate (knn_grid.cl) at the shading points of `band` ("band0") from the
// sorted grid map `map` ("global", "caustic") of a purcell or pmfg dump made with --map sort; k
// and the maximum radius are the render's (its JSON summary's options.k and derived.max_radius).
// Up to `capacity` neighbours per point are kept.
struct KnnGridRun {
  std::vector<Rgb> radiance;
  std::vector<float> radius2;
  std::vector<uint32_t> found, status;      // status: knn_grid.cl's
  std::vector<PhotonDistance> neighbours;  // point i's at [i * capacity, i * capacity + min(found, capacity))
  uint32_t capacity = 0;
};
KnnGridRun runKnnGridEstimate(const Device& device, const std::string& dumpDir, const std::string& map,
                              const std::string& band, uint32_t k, float maxRadius, uint32_t capacity = 1024);
// Writes `<band>.indirect` (global map) or `<band>.caustic`, and `<band>.<map>.neighbours` with its
// offsets. Points the kernel leaves to the host (not Lambertian; photons tied at the radius, where
// the photon left out depends on the order met) keep the reference's estimate. Returns how many.
size_t writeKnnGridDumps(const KnnGridRun& run, const std::string& dumpDir, const std::string& map,
                         const std::string& band, const std::string& outDir);

// The environment-lighting paper's radiance-cache interpolation (radiance_cache.cl, Eq. 5) at the
// receivers of an envpbgi dump; the maximum angle is the render's cache_max_angle (degrees).
struct CacheInterpolationRun {
  std::vector<Rgb> indirect;
  std::vector<uint32_t> reached;  // 0 where no cache qualifies (the CPU renders a buffer there)
};
CacheInterpolationRun runCacheInterpolation(const Device& device, const std::string& dumpDir, float maxAngleDegrees);
// Writes `indirect`; receivers no cache reaches keep the reference's value. Returns how many.
size_t writeCacheDumps(const CacheInterpolationRun& run, const std::string& dumpDir, const std::string& outDir);

// The particle-space paper's gathering (particle_gathering.cl) from a particles dump: R3 per row of
// gathering links, then R4 per found radiance particle from R3's results.
struct ParticleGatheringRun {
  std::vector<uint32_t> rowParticle;  // the area particle of each row of gathering links
  std::vector<Rgb> gathered;          // R3, per row
  std::vector<Rgb> byParticle;        // R3 at the used area particles, 0 elsewhere (as dumped)
  std::vector<Rgb> irradiance;        // R4, per found radiance particle
};
ParticleGatheringRun runParticleGathering(const Device& device, const std::string& dumpDir);
// Writes `particles.gathered_irradiance` and `particles.radiance_particle_irradiance`.
void writeParticleDumps(const ParticleGatheringRun& run, const std::string& outDir);

}  // namespace lucent::opencl
