// Arrays that parallel loops fill. A std::vector value-initializes what resize() adds: one thread
// writes, and so faults in, every page before the loop runs (RING's 18 MB of shading points took
// 7 ms so, on one core). With UninitializedAllocator, resize() leaves new elements unconstructed;
// each element must then be constructed by its writer (placement new, std::uninitialized_copy),
// in parallel, before it is read.
#pragma once
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace lucent {

template <class T>
struct UninitializedAllocator : std::allocator<T> {
  using value_type = T;
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };

  // resize()'s default construction: nothing is written.
  template <class U>
  void construct(U*) noexcept {
    static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>,
                  "only plain records may be left unconstructed");
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T>
using UninitializedVector = std::vector<T, UninitializedAllocator<T>>;

}  // namespace lucent
