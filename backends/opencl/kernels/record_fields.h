/* Every dump record a kernel reads, field by field: one list for the C++ host and for OpenCL C, so
   that both report the offset and size of the same fields (layout.cl; the host's
   checkRecordLayout). RECORD(type) stands for the whole record (its size), FIELD(type, member) for
   one member, nested members with a dot. Valid C++ and OpenCL C alike. */
#define LUCENT_RECORD_FIELDS(RECORD, FIELD)                                                          \
  RECORD(Vec3) FIELD(Vec3, x) FIELD(Vec3, y) FIELD(Vec3, z)                                          \
  RECORD(Rgb) FIELD(Rgb, r) FIELD(Rgb, g) FIELD(Rgb, b)                                              \
  RECORD(Photon) FIELD(Photon, position) FIELD(Photon, power) FIELD(Photon, direction)               \
  FIELD(Photon, flags)                                                                               \
  RECORD(PhotonDistance) FIELD(PhotonDistance, d2) FIELD(PhotonDistance, index)                      \
  RECORD(UniformGrid) FIELD(UniformGrid, lo) FIELD(UniformGrid, hi) FIELD(UniformGrid, cellSize)     \
  FIELD(UniformGrid, invCellSize) FIELD(UniformGrid, res) FIELD(UniformGrid, slack)                  \
  RECORD(ShadingPoint) FIELD(ShadingPoint, position) FIELD(ShadingPoint, geometricNormal)            \
  FIELD(ShadingPoint, normal) FIELD(ShadingPoint, wo) FIELD(ShadingPoint, weight)                    \
  FIELD(ShadingPoint, bsdf.type) FIELD(ShadingPoint, bsdf.lambertian.kd)                            \
  FIELD(ShadingPoint, bsdf.phong.kd) FIELD(ShadingPoint, bsdf.phong.ks)                              \
  FIELD(ShadingPoint, bsdf.phong.ns) FIELD(ShadingPoint, bsdf.mirror.tint)                           \
  FIELD(ShadingPoint, bsdf.glass.ni) FIELD(ShadingPoint, bsdf.gltf.kd) FIELD(ShadingPoint, bsdf.gltf.ks) \
  FIELD(ShadingPoint, bsdf.gltf.alpha) FIELD(ShadingPoint, bsdf.gltf.f90)                            \
  FIELD(ShadingPoint, bsdf.gltf.dielectricF0) FIELD(ShadingPoint, bsdf.gltf.dielectricF90)           \
  FIELD(ShadingPoint, bsdf.gltf.masking) FIELD(ShadingPoint, bsdf.gltf.sheenColour)                 \
  FIELD(ShadingPoint, bsdf.gltf.sheenRoughness) FIELD(ShadingPoint, bsdf.gltf.coat)                 \
  FIELD(ShadingPoint, bsdf.gltf.coatAlpha) FIELD(ShadingPoint, bsdf.gltf.coatNormal)                 \
  FIELD(ShadingPoint, bsdf.gltf.transmission) FIELD(ShadingPoint, bsdf.gltf.volumeIor)                \
  FIELD(ShadingPoint, pixel) FIELD(ShadingPoint, sample)                                             \
  FIELD(ShadingPoint, branch) FIELD(ShadingPoint, triangle) FIELD(ShadingPoint, medium)              \
  RECORD(RadianceCache) FIELD(RadianceCache, position) FIELD(RadianceCache, normal)                  \
  FIELD(RadianceCache, radius) FIELD(RadianceCache, environment) FIELD(RadianceCache, indirect)      \
  RECORD(AreaParticle) FIELD(AreaParticle, position) FIELD(AreaParticle, normal)                     \
  FIELD(AreaParticle, area) FIELD(AreaParticle, reflectance) FIELD(AreaParticle, triangle)
