// Purcell et al. 2003, 2.3 (Fig. 6): the kNN-grid radiance estimate, one work item per shading
// point, from a purcell or pmfg dump's sorted grid map (`<map>.photons`, `.grid`, `.photon_list`,
// `.first_photon`) and its shading points (`band<N>.shading_points`).
//
// The search explores shells of cells about the query's cell (shell s: the cells at Chebyshev
// distance s), each shell's cells in z, y, x order and each cell's photons in photon-list order.
// While fewer than k photons are accepted, any photon within the maximum radius is, and the search
// radius grows to include it; then the radius stays and photons within it are accepted. The search
// ends after a shell beyond which no cell can hold a photon within reach. Lucent's CPU search reads
// the same cells in longer runs where the order cannot change the result
// (src/methods/photonmap/knn_grid.h); this is the plain loop a GPU thread runs.
//
// The estimate (Jensen 2001, eq. 7.6) of a Lambertian point: the power of the accepted photons that
// light the point's side (photonLights), less the share of the farthest one when it defined the
// radius, times kd / pi over pi r^2. Points with other materials are left to the host (status 1).

inline float axisOf(Vec3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

inline int cellAlong(__global const UniformGrid* g, float p, int a) {
  const float f = floor((p - axisOf(g->lo, a)) * axisOf(g->invCellSize, a));
  return f < 0 ? 0 : (f >= (float)g->res[a] ? g->res[a] - 1 : (int)f);
}

inline float cellLo(__global const UniformGrid* g, int a, int i) {
  return axisOf(g->lo, a) + (float)i * axisOf(g->cellSize, a);
}

// Distance along axis a from x to cell i's slab, less the grid's slack (never more than the truth).
inline float axisGap(__global const UniformGrid* g, int a, int i, float x) {
  const float lo = cellLo(g, a, i), hi = lo + axisOf(g->cellSize, a);
  return fmax(fmax(lo - x, x - hi) - g->slack, 0.0f);
}

// Distance from p to the cells beyond shells 0..s about c, less the slack; infinite when none.
inline float distanceBeyondShell(__global const UniformGrid* g, Vec3 p, const int c[3], int s) {
  float d = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (c[a] - s > 0) d = fmin(d, axisOf(p, a) - cellLo(g, a, c[a] - s));
    if (c[a] + s + 1 < g->res[a]) d = fmin(d, cellLo(g, a, c[a] + s + 1) - axisOf(p, a));
  }
  return d - g->slack;
}

// The octahedral direction of `bits` bits per coordinate, not normalized
// (include/lucent/core/octahedral.h).
inline Vec3 octahedralDirection(uint e, int bits) {
  const uint mask = (1u << bits) - 1u;
  const float scale = 2.0f / (float)mask;
  const float x = (float)(e & mask) * scale - 1.0f, y = (float)((e >> bits) & mask) * scale - 1.0f;
  const float z = 1.0f - fabs(x) - fabs(y), fold = fmax(-z, 0.0f);
  return vec3(x - copysign(fold, x), y - copysign(fold, y), z);
}

inline Vec3 normalize3(Vec3 v) {
  const float l = sqrt(dot3(v, v));
  return vec3(v.x / l, v.y / l, v.z / l);
}

// Which photons light the point's side (include/lucent/techniques/photons/photon.h): arriving from
// above its shading normal, landed on a surface facing within 60 degrees of its facing normal, and
// off its plane by no more than the angle between the normals explains on a mesh (sin a).
inline bool photonLights(Photon p, Vec3 shadingNormal, Vec3 facingNormal, Vec3 offset, float d2) {
  const Vec3 incoming = octahedralDirection(p.direction, 16);
  const Vec3 facing = normalize3(octahedralDirection(p.flags >> 11, 10));
  const float c = dot3(facing, facingNormal), h = dot3(offset, facingNormal);
  const float offPlane = 0.01f;
  return (dot3(incoming, shadingNormal) > 0) & (c > 0.5f) & (h * h <= d2 * (1 - c * c + offPlane * offPlane));
}

typedef struct {
  Vec3 q, shadingNormal, facingNormal;
  uint k, found, used, capacity, farthestCount;
  float maxRadius2, radius2, farthestD2;
  Rgb sum, farthest;
} Search;

inline void visitCell(Search* s, __global const Photon* photons, __global const uint* photonList,
                      __global const uint* firstPhoton, __global const UniformGrid* g, int x, int y, int z,
                      __global PhotonDistance* neighbours) {
  const uint cell = (uint)(x + g->res[0] * (y + g->res[1] * z));
  const uint begin = firstPhoton[cell], end = firstPhoton[cell + 1];
  if (begin == end) return;
  const float gx = axisGap(g, 0, x, s->q.x), gy = axisGap(g, 1, y, s->q.y), gz = axisGap(g, 2, z, s->q.z);
  const float limit2 = s->found < s->k ? s->maxRadius2 : s->radius2;
  if (gx * gx + gy * gy + gz * gz > limit2) return;  // no photon in it can be accepted
  for (uint j = begin; j < end; ++j) {
    const uint id = photonList[j];
    const Photon p = photons[id];
    const Vec3 offset = sub3(p.position, s->q);
    const float d2 = dot3(offset, offset);
    if (s->found < s->k) {
      if (!(d2 <= s->maxRadius2)) continue;
      s->radius2 = fmax(s->radius2, d2);
    } else if (!(d2 <= s->radius2)) {
      continue;
    }
    if (s->found < s->capacity) neighbours[s->found].d2 = d2, neighbours[s->found].index = id;
    ++s->found;
    const bool front = photonLights(p, s->shadingNormal, s->facingNormal, offset, d2);
    const Rgb share = front ? p.power : rgb(0.0f, 0.0f, 0.0f);
    s->used += front;
    s->sum = addRgb(s->sum, share);
    if (d2 > s->farthestD2) s->farthestD2 = d2, s->farthest = share, s->farthestCount = 1;
    else if (d2 == s->farthestD2) ++s->farthestCount;
  }
}

// Per shading point: radiance (0 where not estimated), the estimate's squared radius, the photons
// accepted (found), their indices and squared distances (the first `capacity`, in search order) and a status: 0 estimated,
// 1 not a Lambertian surface (left to the host), 2 more photons found than `capacity`, 3 estimated
// with two or more photons at exactly the radius (which of them is left out depends on the order
// the search meets them: another search may leave out another).
__kernel void knnGridEstimate(__global const Photon* photons, __global const uint* photonList,
                              __global const uint* firstPhoton, __global const UniformGrid* grid,
                              __global const ShadingPoint* points, uint pointCount, uint k, float maxRadius,
                              uint capacity, __global Rgb* radiance, __global float* radius2Out,
                              __global uint* foundOut, __global PhotonDistance* neighbours, __global uint* status) {
  const uint i = get_global_id(0);
  if (i >= pointCount) return;
  const ShadingPoint sp = points[i];
  Search s;
  s.q = sp.position;
  s.shadingNormal = sp.normal;
  const Vec3 n = sp.geometricNormal;
  s.facingNormal = dot3(sp.wo, n) > 0 ? n : vec3(-n.x, -n.y, -n.z);
  s.k = k, s.found = 0, s.used = 0, s.capacity = capacity, s.farthestCount = 0;
  s.maxRadius2 = maxRadius * maxRadius, s.radius2 = 0, s.farthestD2 = -1;
  s.sum = rgb(0.0f, 0.0f, 0.0f), s.farthest = s.sum;
  __global PhotonDistance* ids = neighbours + (size_t)i * capacity;

  __global const UniformGrid* g = grid;
  const int c[3] = {cellAlong(g, s.q.x, 0), cellAlong(g, s.q.y, 1), cellAlong(g, s.q.z, 2)};
  bool done = false;
  // After max(res) shells every cell is explored (a backstop: the host checks the grid is finite).
  const int lastShell = max(g->res[0], max(g->res[1], g->res[2]));
  for (int shell = 0; !done && shell <= lastShell; ++shell) {
    // The shell's cells in z, y, x order. A row strictly inside the shell holds only its two x ends
    // and a slab strictly inside it only its y faces and x ends: where those lie outside the grid,
    // the rows and slabs are stepped over, not walked (on a grid of 1 x 1 x 2^21 cells, walking
    // them made a search's work grow with the square of its shells).
    const bool xEnds = c[0] - shell >= 0 || c[0] + shell < g->res[0];
    const bool yFaces = c[1] - shell >= 0 || c[1] + shell < g->res[1];
    const int y0 = max(c[1] - shell, 0), y1 = min(c[1] + shell, g->res[1] - 1);
    for (int z = max(c[2] - shell, 0); z <= min(c[2] + shell, g->res[2] - 1); ++z) {
      const bool zFace = abs(z - c[2]) == shell;
      if (!zFace && !xEnds && !yFaces) {
        z = c[2] + shell - 1;  // on to the far z face
        continue;
      }
      for (int y = y0; y <= y1; ++y) {
        if (zFace || abs(y - c[1]) == shell) {
          for (int x = max(c[0] - shell, 0); x <= min(c[0] + shell, g->res[0] - 1); ++x)
            visitCell(&s, photons, photonList, firstPhoton, g, x, y, z, ids);
        } else if (xEnds) {
          if (c[0] - shell >= 0) visitCell(&s, photons, photonList, firstPhoton, g, c[0] - shell, y, z, ids);
          if (c[0] + shell < g->res[0]) visitCell(&s, photons, photonList, firstPhoton, g, c[0] + shell, y, z, ids);
        } else {
          y = c[1] + shell - 1;  // on to the far y face
        }
      }
    }
    const float beyond = distanceBeyondShell(g, s.q, c, shell);
    const float beyond2 = beyond > 0 ? beyond * beyond : 0;
    done = beyond == INFINITY || beyond2 > s.maxRadius2 || (s.found >= s.k && beyond2 > s.radius2);
  }

  const float r2 = s.found < s.k ? s.maxRadius2 : s.radius2;
  const bool lambertian = sp.bsdf.type == 0;
  Rgb L = rgb(0.0f, 0.0f, 0.0f);
  if (lambertian && r2 > 0) {
    const Rgb inside = s.farthestD2 == r2 ? rgb(s.sum.r - s.farthest.r, s.sum.g - s.farthest.g, s.sum.b - s.farthest.b)
                                          : s.sum;
    const float invPi = 0.31830988618379067154f, pi = 3.14159265358979323846f;
    L = scaleRgb(mulRgb(inside, scaleRgb(sp.bsdf.lambertian.kd, invPi)), 1.0f / (pi * r2));
  }
  radiance[i] = L;
  radius2Out[i] = r2;
  foundOut[i] = s.found;
  const bool tied = s.farthestCount > 1 && s.farthestD2 == r2;
  status[i] = !lambertian ? 1u : (s.found > capacity ? 2u : (tied ? 3u : 0u));
}
