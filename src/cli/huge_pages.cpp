// The renderer's large arrays (the film's sums, shading points, point hierarchies, photon maps) on
// transparent huge pages where the kernel offers them only on request (Linux's THP "madvise" mode,
// the common default): each first touch of a fresh 4 KiB page is a page fault, slow on virtual
// machines and serialising threads, and a 2 MiB page takes one fault for 512 of them. The
// executable replaces the global operator new for this; blocks under 4 MiB are left as they are.
// The library does not: a program that links it keeps its own allocator.
#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kAdviseFrom = 2 * kHugePage;

void* allocate(std::size_t bytes) {
  void* p = std::malloc(bytes != 0 ? bytes : 1);
  if (p == nullptr) throw std::bad_alloc();
  if (bytes >= kAdviseFrom) {
    // The whole huge pages inside the block; a failure (no THP in this kernel) changes nothing.
    const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
    const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kHugePage - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  }
  return p;
}

}  // namespace

void* operator new(std::size_t bytes) { return allocate(bytes); }
void* operator new[](std::size_t bytes) { return allocate(bytes); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
