// libFuzzer target for the glTF loader: one input is one glTF file, written as model.glb when it
// starts with the binary container's magic ("glTF") and as model.gltf otherwise, then loaded as a
// scene of its own (its camera, triangles, materials, textures and lights). Every rejection must be a
// SceneError or a MemoryLimitError; anything else that escapes, a crash, a sanitizer report, a hang
// (-timeout) or a large allocation (-malloc_limit_mb) is a defect. TinyGLTF is Debian's shared build, not instrumented:
// the sanitizers see Lucent's checks and reads, and TinyGLTF's own faults only as crashes. Seeds:
// scripts/fuzz-corpus.py.
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "fuzz_files.h"
#include "lucent/core/memory.h"
#include "lucent/scene/loader.h"

// 64 MiB beside what the fuzzer holds at its start: an accessor, instance or image that would need
// more is refused (SceneError or MemoryLimitError) before anything is allocated. With 1 GiB, the
// seeds that claim 2^20 elements without a bufferView ran 134 inputs a second, not 1,700: decoding
// large scenes under the sanitizers finds nothing a small one would not.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lucent::setMemoryLimit(lucent::memoryInUse() + (uint64_t(64) << 20));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const std::filesystem::path& dir = lucent::fuzz::scratchDirectory();
  const std::filesystem::path file = dir / (input.substr(0, 4) == "glTF" ? "model.glb" : "model.gltf");
  lucent::fuzz::writeFile(file, input);
  try {
    lucent::loadScene(file.string(), lucent::LoadOptions(true));
  } catch (const lucent::SceneError&) {
  } catch (const lucent::MemoryLimitError&) {
  }
  std::error_code ec;
  std::filesystem::remove(file, ec);
  return 0;
}
