// The point order that defines the complete binary tree (paper 2.1): the axis of largest extent of a
// node's points, a split at the median along it (nth_element rather than the paper's full sort: the
// tree needs only the partition, O(n) per level, O(n log n) in all), both halves recursively and in
// parallel.
#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "lucent/techniques/points/point_hierarchy.h"

namespace lucent {

namespace {

struct Item {
  Vec3 p;
  uint32_t index;
};

constexpr size_t kParallelSplit = 4096;
constexpr size_t kParallelBounds = size_t(1) << 16;

Bounds3 boundsOf(const Item* first, size_t count) {
  auto serial = [](const Item* b, const Item* e) {
    Bounds3 box;
    for (const Item* it = b; it != e; ++it) box.extend(it->p);
    return box;
  };
  if (count < kParallelBounds) return serial(first, first + count);
  // Min and max are exact, so the reduction's order does not matter.
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, count, kParallelBounds / 4), Bounds3{},
      [&](const tbb::blocked_range<size_t>& r, Bounds3 box) {
        const Bounds3 part = serial(first + r.begin(), first + r.end());
        box.extend(part.lo);
        box.extend(part.hi);
        return box;
      },
      [](Bounds3 a, const Bounds3& b) {
        a.extend(b.lo);
        a.extend(b.hi);
        return a;
      });
}

void split(Item* first, size_t count) {
  if (count < 2) return;
  const Vec3 e = boundsOf(first, count).extent();
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  // Ties along the axis go by input index: the halves are then unique, and so is the whole order.
  std::nth_element(first, first + count / 2, first + count, [axis](const Item& a, const Item& b) {
    return a.p[axis] < b.p[axis] || (a.p[axis] == b.p[axis] && a.index < b.index);
  });
  const size_t half = count / 2;
  if (count < kParallelSplit) {
    split(first, half);
    split(first + half, half);
  } else {
    tbb::parallel_invoke([&] { split(first, half); }, [&] { split(first + half, half); });
  }
}

}  // namespace

std::vector<uint32_t> medianSplitOrder(std::span<const Vec3> positions) {
  const size_t n = positions.size();
  if (n == 0 || !std::has_single_bit(n) || n > (size_t(1) << 31))
    throw std::invalid_argument("median split: the point count must be a power of two");
  std::vector<Item> items(n);
  for (size_t i = 0; i < n; ++i) items[i] = {positions[i], uint32_t(i)};
  split(items.data(), n);
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = items[i].index;
  return order;
}

}  // namespace lucent
