// The point hierarchy's complete binary tree in heap numbering (Ritschel et al. 2009, 2.1 and 3.1):
// the root is node 1, the children of node i are 2i and 2i + 1, and with n leaves (a power of two)
// the leaves are nodes n .. 2n - 1, leaf n + j holding point j of the ordered point list. Nothing
// about the tree is stored: children, parents and skip pointers are arithmetic on the index, which is
// what lets a GPU thread traverse without a stack (3.1).
#pragma once
#include <bit>
#include <cstdint>

namespace lucent {

inline constexpr uint32_t kRootNode = 1;
// What nextNodeSkippingSubtree returns after the last subtree of the depth-first order.
inline constexpr uint32_t kTraversalEnd = 0;

constexpr uint32_t firstChild(uint32_t node) { return 2 * node; }
constexpr uint32_t secondChild(uint32_t node) { return 2 * node + 1; }
constexpr uint32_t parentNode(uint32_t node) { return node >> 1; }
constexpr bool isLeafNode(uint32_t node, uint32_t leafCount) { return node >= leafCount; }
// Depth of a node: 0 for the root, log2(n) for the leaves.
constexpr uint32_t nodeLevel(uint32_t node) { return 31u - uint32_t(std::countl_zero(node)); }
// Leaf count as a level count: the leaves' level.
constexpr uint32_t leafLevel(uint32_t leafCount) { return nodeLevel(leafCount); }
// The ordered points below a node: [firstLeafPoint, firstLeafPoint + leavesBelow).
constexpr uint32_t leavesBelow(uint32_t node, uint32_t leafCount) { return leafCount >> nodeLevel(node); }
constexpr uint32_t firstLeafPoint(uint32_t node, uint32_t leafCount) {
  return (node - (1u << nodeLevel(node))) * leavesBelow(node, leafCount);
}

// The skip pointer of 3.1, computed rather than stored: the node that follows the whole subtree of
// `node` in depth-first order. Climb while the node is a right child (odd), then step to the right
// sibling; climbing past the root ends the traversal.
constexpr uint32_t nextNodeSkippingSubtree(uint32_t node) {
  const uint32_t up = node >> std::countr_one(node);
  return up == 0 ? kTraversalEnd : up + 1;
}

// Depth-first successor when descending into the node's children (which a leaf has none of).
constexpr uint32_t nextNodeDescending(uint32_t node, uint32_t leafCount) {
  return isLeafNode(node, leafCount) ? nextNodeSkippingSubtree(node) : firstChild(node);
}

}  // namespace lucent
