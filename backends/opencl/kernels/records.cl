// Lucent's dump records (docs/dump-format.md) as OpenCL C reads them: the same fields, in the same
// order, with the same names as the C++ structs. Only scalars and arrays of scalars: no
// 3-component vector types (float3 is 16 bytes in OpenCL C and std430, 12 in CUDA), every record a
// multiple of 4 bytes with no padding. record_fields.h lists every field; the layout kernel
// (layout.cl) reports where this compiler puts each one, and the host compares that with the C++
// offsets, so a record declared differently here fails before any kernel reads it.
#pragma OPENCL FP_CONTRACT OFF

typedef struct {
  float x, y, z;
} Vec3;

typedef struct {
  float r, g, b;
} Rgb;

typedef struct {
  Vec3 position;
  Rgb power;       // W
  uint direction;  // octahedral, 2 x 16 bits, towards where the photon came from
  uint flags;      // bits 0-7 bounces, 8-9 kd-tree axis, 10 caustic, 11-30 facing normal (2 x 10 bits)
} Photon;

typedef struct {
  float d2;    // squared distance from the query
  uint index;  // the photon's index in the map's photons
} PhotonDistance;

typedef struct {
  Vec3 lo, hi, cellSize, invCellSize;
  int res[3];
  float slack;
} UniformGrid;

// SurfaceBsdf: the material's kind (include/lucent/scene/bsdf/kinds.h) and its lobe's parameters
// (include/lucent/scene/bsdf/*.h) in a union of 88 bytes (the largest lobe's).
typedef struct {
  Rgb kd;
} LambertianLobe;

typedef struct {
  Rgb kd, ks;
  float ns;
} PhongLobe;

typedef struct {
  Rgb tint;
} MirrorLobe;

typedef struct {
  float ni;
} GlassLobe;

typedef struct {
  Rgb kd, ks;
  float alpha, f90, dielectricF0, dielectricF90;
  uint masking;  // 0 separable, 1 height-correlated
  Rgb sheenColour;
  float sheenRoughness;
  float coat, coatAlpha;
  Vec3 coatNormal;  // in the shading frame of the point's normal
  float transmission;
  float volumeIor;
} GltfMetalRoughLobe;

typedef struct {
  uint type;  // 0 diffuse, 1 Phong, 2 mirror, 3 glass, 4 glTF
  union {
    LambertianLobe lambertian;
    PhongLobe phong;
    MirrorLobe mirror;
    GlassLobe glass;
    GltfMetalRoughLobe gltf;
  };
} SurfaceBsdf;

// The Lambertian term's albedo of a shading point's lobe (none is specular), as SurfaceBsdf::diffuse
// gives it, but for a glTF sheen layer's scaling, which reads the sheen's albedo table (not here).
Rgb diffuseAlbedo(SurfaceBsdf b) {
  if (b.type == 4) {
    const float s = (1.0f - b.gltf.coat * 0.04f) * (1.0f - b.gltf.transmission);
    return (Rgb){b.gltf.kd.r * s, b.gltf.kd.g * s, b.gltf.kd.b * s};
  }
  return b.type == 1 ? b.phong.kd : b.lambertian.kd;
}

typedef struct {
  Vec3 position, geometricNormal, normal, wo;
  Rgb weight;
  SurfaceBsdf bsdf;
  uint pixel, sample, branch, triangle, medium;
} ShadingPoint;

typedef struct {
  Vec3 position, normal;
  float radius;
  Rgb environment[25], indirect[25];
} RadianceCache;

typedef struct {
  Vec3 position, normal;
  float area;
  Rgb reflectance;
  uint triangle;
} AreaParticle;

// Vector helpers on the records' own types (no float3).
inline Vec3 vec3(float x, float y, float z) { Vec3 v = {x, y, z}; return v; }
inline Vec3 sub3(Vec3 a, Vec3 b) { return vec3(a.x - b.x, a.y - b.y, a.z - b.z); }
inline float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Rgb rgb(float r, float g, float b) { Rgb c = {r, g, b}; return c; }
inline Rgb addRgb(Rgb a, Rgb b) { return rgb(a.r + b.r, a.g + b.g, a.b + b.b); }
inline Rgb scaleRgb(Rgb a, float s) { return rgb(a.r * s, a.g * s, a.b * s); }
inline Rgb mulRgb(Rgb a, Rgb b) { return rgb(a.r * b.r, a.g * b.g, a.b * b.b); }
