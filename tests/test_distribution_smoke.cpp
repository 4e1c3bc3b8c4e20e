#include <catch2/catch.hpp>
#include "lucent/core/distribution.h"
TEST_CASE("placeholder distribution builds") {
  std::vector<float> w{1, 2, 3};
  lucent::Distribution1D d(w);
  REQUIRE(d.total() == 6.0f);
}
