// Octahedral unit vectors in 2 x 16 bits (include/lucent/core/octahedral.h): round-trip accuracy.
#include <catch2/catch.hpp>

#include <cmath>

#include "lucent/core/octahedral.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"

using namespace lucent;

namespace {

double angleBetween(Vec3 a, Vec3 b) {
  // atan2 of |a x b| and a.b stays accurate for tiny angles, unlike acos.
  return std::atan2(double(length(cross(a, b))), double(dot(a, b)));
}

}  // namespace

TEST_CASE("Octahedral encoding round-trips unit vectors within 16-bit accuracy", "[core][octahedral]") {
  std::vector<Vec3> directions;
  Rng rng(3);
  for (int i = 0; i < 200000; ++i) directions.push_back(sampleUniformSphere(rng.uniform2()));
  // Axes, octant diagonals and the folds of the lower hemisphere, where the mapping has creases.
  for (float x : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
    for (float y : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
      for (float z : {-1.0f, -1e-7f, 0.0f, 1e-7f, 1.0f})
        if (x != 0 || y != 0 || z != 0) directions.push_back(normalize(Vec3{x, y, z}));
  double worst = 0;
  for (Vec3 d : directions) {
    const Vec3 decoded = decodeOctahedral(encodeOctahedral(d));
    REQUIRE(std::abs(length(decoded) - 1.0f) < 1e-6f);
    worst = std::max(worst, angleBetween(d, decoded));
  }
  // 65535 steps over [-1, 1]: half a step is 1.5e-5 in each coordinate, stretched by the mapping.
  CHECK(worst < 1e-4);
  CHECK(worst > 1e-6);  // a real quantization, not a pass-through
  // Encoding is idempotent after one round trip.
  for (int i = 0; i < 1000; ++i) {
    const uint32_t e = encodeOctahedral(directions[i]);
    CHECK(encodeOctahedral(decodeOctahedral(e)) == e);
  }
}
