#pragma OPENCL EXTENSION cl_khr_fp64 : enable  // the weights are summed in double, as the CPU sums them

// The environment-lighting PBGI paper's radiance-cache interpolation (3.5, Eq. 5), one work item
// per receiver, from an envpbgi dump: the caches (`envpbgi.caches`), the screen tiles' cache lists
// (`envpbgi.grid_begin`, `envpbgi.grid_caches`), the receivers (`shading_points`) and the tile
// each is shaded in (`envpbgi.receiver_tiles`).
//
// Of its tile's caches, those within their radius whose normal is within the maximum angle of the
// receiver's weigh in with Ward et al.'s 1 / (|x - x_k| / R_k + sqrt(1 - n . n_k)); each gives its
// irradiance towards n, bilinear on its 5 x 5 paraboloid map of normals; the weighted mean times the
// receiver's diffuse reflectance over pi is its indirect light. A receiver no cache qualifies for
// is left to the host (the CPU renders a micro-buffer of its own there): reached 0.

// Frame(normal) of include/lucent/core/math.h (Duff et al. 2017).
inline void frameOf(Vec3 n, Vec3* s, Vec3* t) {
  const float sign = copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  *s = vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
  *t = vec3(b, sign + n.y * n.y * a, -n.y);
}

__kernel void interpolateCaches(__global const RadianceCache* caches, __global const uint* gridBegin,
                                __global const uint* gridCaches, __global const ShadingPoint* points,
                                __global const uint* receiverTiles, uint count, float cosMax,
                                __global Rgb* indirect, __global uint* reached) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const Vec3 x = points[i].position, n = points[i].normal;
  const uint tile = receiverTiles[i];
  Rgb sum = rgb(0.0f, 0.0f, 0.0f);
  double total = 0;
  for (uint j = gridBegin[tile]; j < gridBegin[tile + 1]; ++j) {
    __global const RadianceCache* c = caches + gridCaches[j];
    const float dx = x.x - c->position.x, dy = x.y - c->position.y, dz = x.z - c->position.z;
    const float distance = sqrt(dx * dx + dy * dy + dz * dz);
    const Vec3 cn = c->normal;
    const float cosine = n.x * cn.x + n.y * cn.y + n.z * cn.z;
    if (!((distance < c->radius) & (cosine >= cosMax))) continue;
    const float ward = distance / c->radius + sqrt(fmax(0.0f, 1.0f - cosine));
    const float weight = 1.0f / fmax(ward, 1e-6f);

    // The receiver's normal on the cache's paraboloid map, clamped to the disc.
    Vec3 s, t;
    frameOf(cn, &s, &t);
    const float lx = n.x * s.x + n.y * s.y + n.z * s.z;
    const float ly = n.x * t.x + n.y * t.y + n.z * t.z;
    const float lz = n.x * cn.x + n.y * cn.y + n.z * cn.z;
    const bool above = lz > -0.999f;
    float px = above ? lx / (1.0f + lz) : lx, py = above ? ly / (1.0f + lz) : ly;
    const float r = sqrt(px * px + py * py);
    px = r > 1.0f ? px / r : px, py = r > 1.0f ? py / r : py;
    const float side = 5.0f;
    const float sx = clamp((px + 1.0f) * 0.5f * side - 0.5f, 0.0f, side - 1.0f);
    const float sy = clamp((py + 1.0f) * 0.5f * side - 0.5f, 0.0f, side - 1.0f);
    const int x0 = min((int)sx, 3), y0 = min((int)sy, 3);
    const float fx = sx - (float)x0, fy = sy - (float)y0;
    const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    const int at = y0 * 5 + x0;
    const int texel[4] = {at, at + 1, at + 5, at + 6};
    Rgb e = rgb(0.0f, 0.0f, 0.0f);
    for (int k = 0; k < 4; ++k) e = addRgb(e, scaleRgb(c->indirect[texel[k]], w[k]));
    sum = addRgb(sum, scaleRgb(e, weight));
    total += weight;
  }
  const float invPi = 0.31830988618379067154f;
  const Rgb rho = scaleRgb(diffuseAlbedo(points[i].bsdf), invPi);
  indirect[i] = total > 0 ? mulRgb(rho, scaleRgb(sum, (float)(1.0 / total))) : rgb(0.0f, 0.0f, 0.0f);
  reached[i] = total > 0;
}
