#pragma OPENCL EXTENSION cl_khr_fp64 : enable  // R4 sums areas in double, as the CPU does
// The particle-space paper's gathering (Chang, Park and Ihm, 4.3.1-4.3.2), from a particles dump:
// stage R3, one work item per row of gathering links, then stage R4, one work item per radiance
// particle found around the shading points.

// R3: a particle's irradiance from the radiance of its gathering links' end particles,
// E = (pi / N) sum_k L(k*), a link without a particle (0xffffffff) giving nothing; the links are
// cosine-distributed, so this is the Monte Carlo estimate with pdf cos / pi.
__kernel void gatherOverLinks(__global const uint* links, uint linksPerRow, uint rows, __global const Rgb* radiance,
                              __global Rgb* gathered) {
  const uint row = get_global_id(0);
  if (row >= rows) return;
  Rgb sum = rgb(0.0f, 0.0f, 0.0f);
  for (uint j = 0; j < linksPerRow; ++j) {
    const uint end = links[(size_t)row * linksPerRow + j];
    if (end != 0xffffffffu) sum = addRgb(sum, radiance[end]);
  }
  gathered[row] = scaleRgb(sum, 3.14159265358979323846f / (float)linksPerRow);
}

// R4: a radiance particle's irradiance, its estimation list's gathered flux over the list's own
// area (area in double, as the CPU sums it); an empty list gives none. Item j reads list
// listOfItem[j] (the dump's lists are by found radiance particle, or by every radiance particle).
__kernel void estimateFromLists(__global const ulong* listOffsets, __global const uint* listParticles,
                                __global const AreaParticle* particles, __global const Rgb* gatheredByParticle,
                                __global const uint* listOfItem, uint items, __global Rgb* irradiance) {
  const uint item = get_global_id(0);
  if (item >= items) return;
  const uint k = listOfItem[item];
  Rgb sum = rgb(0.0f, 0.0f, 0.0f);
  double area = 0;
  for (ulong j = listOffsets[k]; j < listOffsets[k + 1]; ++j) {
    const uint m = listParticles[j];
    sum = addRgb(sum, scaleRgb(gatheredByParticle[m], particles[m].area));
    area += particles[m].area;
  }
  irradiance[item] = area > 0 ? rgb(sum.r / (float)area, sum.g / (float)area, sum.b / (float)area)
                              : rgb(0.0f, 0.0f, 0.0f);
}
