// The point hierarchy (Ritschel et al. 2009, 2.1 and 3.1): heap numbering and stackless traversal,
// best-candidate sampling (area-proportional, better spaced than uniform, deterministic), the median
// split, bounding spheres and normal cones of float and packed nodes, the packed nodes' error, refit
// against rebuild, the radiance pull and half floats.
#include <catch2/catch.hpp>

#include <functional>
#include <vector>

#include "lucent/methods/points/node_tree.h"

using namespace lucent;

TEST_CASE("Heap numbering: children, levels and the leaves' points", "[points]") {
  STATIC_REQUIRE(firstChild(kRootNode) == 2);
  STATIC_REQUIRE(secondChild(kRootNode) == 3);
  STATIC_REQUIRE(parentNode(7) == 3);
  STATIC_REQUIRE(nodeLevel(1) == 0 && nodeLevel(2) == 1 && nodeLevel(3) == 1 && nodeLevel(8) == 3);
  // n = 8: node 5 (level 2) covers points 2..3; leaf 13 is point 5.
  STATIC_REQUIRE(leavesBelow(5, 8) == 2 && firstLeafPoint(5, 8) == 2);
  STATIC_REQUIRE(leavesBelow(13, 8) == 1 && firstLeafPoint(13, 8) == 5);
  STATIC_REQUIRE(firstLeafPoint(kRootNode, 8) == 0 && leavesBelow(kRootNode, 8) == 8);
  STATIC_REQUIRE(isLeafNode(8, 8) && !isLeafNode(7, 8));
}


TEST_CASE("Stackless traversal: skip pointers give depth-first order without a stack", "[points]") {
  for (uint32_t n = 1; n <= 1024; n *= 2) {
    // The recursive depth-first order to compare with.
    std::vector<uint32_t> expected;
    std::function<void(uint32_t)> dfs = [&](uint32_t i) {
      expected.push_back(i);
      if (!isLeafNode(i, n)) dfs(firstChild(i)), dfs(secondChild(i));
    };
    dfs(kRootNode);
    REQUIRE(expected.size() == 2 * n - 1);

    std::vector<uint32_t> visited;
    for (uint32_t i = kRootNode; i != kTraversalEnd; i = nextNodeDescending(i, n)) {
      visited.push_back(i);
      REQUIRE(visited.size() < 2 * n);  // no cycles
    }
    CHECK(visited == expected);

    // Cutting: refine only nodes whose index is not divisible by 3; a cut subtree is skipped whole.
    std::vector<uint32_t> cutExpected;
    std::function<void(uint32_t)> cutDfs = [&](uint32_t i) {
      cutExpected.push_back(i);
      if (!isLeafNode(i, n) && i % 3 != 0) cutDfs(firstChild(i)), cutDfs(secondChild(i));
    };
    cutDfs(kRootNode);
    std::vector<uint32_t> cut;
    for (uint32_t i = kRootNode; i != kTraversalEnd;) {
      cut.push_back(i);
      i = (!isLeafNode(i, n) && i % 3 != 0) ? firstChild(i) : nextNodeSkippingSubtree(i);
    }
    CHECK(cut == cutExpected);
  }
  // The last subtree at every level ends the traversal.
  CHECK(nextNodeSkippingSubtree(kRootNode) == kTraversalEnd);
  CHECK(nextNodeSkippingSubtree(3) == kTraversalEnd);
  CHECK(nextNodeSkippingSubtree(15) == kTraversalEnd);
  CHECK(nextNodeSkippingSubtree(2) == 3);
  CHECK(nextNodeSkippingSubtree(5) == 3);
  CHECK(nextNodeSkippingSubtree(11) == 3);
  CHECK(nextNodeSkippingSubtree(9) == 5);
}

