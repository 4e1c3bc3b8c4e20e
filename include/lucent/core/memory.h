// The memory a render may use. Large allocations (photons, maps, points, shading points, film) are
// checked against it before they are made, so that a render that would not fit stops at once with a
// message naming the option to lower, not minutes later with std::bad_alloc or the kernel's
// out-of-memory killer.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace lucent {

struct MemoryLimitError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What this process could still take: the system's available memory (MemAvailable), or less where
// its control group (a batch system's job allocation) or RLIMIT_AS allows less.
uint64_t availableMemory();

// The process's address-space limit (RLIMIT_AS, ulimit -v), or UINT64_MAX for none: no memory
// limit above it can be honoured (allocations fail first).
uint64_t addressSpaceLimit();

// What this process holds: its resident memory, less the freed heap memory it keeps for reuse
// (retainFreedMemory), which later allocations take first.
uint64_t memoryInUse();

// The most memory the process may hold; 0 restores the default, the memory in use plus the
// available memory when the limit is first needed.
void setMemoryLimit(uint64_t bytes);
uint64_t memoryLimit();

// Throws MemoryLimitError("<what> would need <bytes> beside the <in use> ... (--memory-limit ...):
// <remedy>") when the memory in use plus `bytes` exceeds the limit. The remedy names the options
// that make the allocation smaller, as the user writes them ("lower --photons").
void requireMemory(uint64_t bytes, std::string_view what, std::string_view remedy);

// 1536 -> "1.5 KiB".
std::string memoryText(uint64_t bytes);

// A size as written on the command line: bytes, or a number with the binary suffix K, M, G or T
// (optionally followed by "iB" or "B"): "512M", "1.5G", "8GiB". Throws std::invalid_argument.
uint64_t parseMemorySize(std::string_view text);

}  // namespace lucent
