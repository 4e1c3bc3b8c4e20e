#include "image/image_codec.h"

#include <dlfcn.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <stdexcept>

namespace lucent {

namespace {

// Nanoseconds spent loading modules (codecLoadingSeconds).
std::atomic<uint64_t> loadingNanoseconds{0};

// The module by its name (the library path: the caller's run path, which the build and the install
// give every program linking Lucent, LD_LIBRARY_PATH, the system's directories), else beside the
// program or shared object this code is linked into, or one directory up (a Python module's).
void* openModule(const char* module, std::string& why) {
  if (void* handle = dlopen(module, RTLD_LAZY | RTLD_LOCAL)) return handle;
  why = dlerror();
  Dl_info self;
  if (dladdr(reinterpret_cast<const void*>(&openModule), &self) == 0 || !self.dli_fname) return nullptr;
  const std::filesystem::path here = std::filesystem::path(self.dli_fname).parent_path();
  for (const std::filesystem::path& candidate : {here / module, here.parent_path() / module})
    if (void* handle = dlopen(candidate.c_str(), RTLD_LAZY | RTLD_LOCAL)) return handle;
  return nullptr;
}

// The functions `entry` of `module` returns, checked to be this build's.
template <typename Functions>
const Functions* loadModule(const char* module, const char* entry, uint32_t interfaceVersion, const char* role) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  void* handle = openModule(module, why);
  loadingNanoseconds += uint64_t(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count());
  std::string message = std::string("cannot load Lucent's image ") + role + ": ";
  if (!handle) throw std::runtime_error(message.append(why));
  const auto function = reinterpret_cast<const Functions* (*)()>(dlsym(handle, entry));
  const Functions* functions = function ? function() : nullptr;
  if (!functions || functions->interfaceVersion != interfaceVersion)
    throw std::runtime_error(message.append(module).append(" is not this build's (its interface differs)"));
  return functions;
}

}  // namespace

double codecLoadingSeconds() { return double(loadingNanoseconds.load()) * 1e-9; }

const ImageWriter& imageWriter() {
  static const ImageWriter* writer = loadModule<ImageWriter>("liblucent_image_exr.so", "lucentImageWriter",
                                                             kImageWriterInterface, "writer, which writes image files");
  return *writer;
}

const ImageReader& imageReader(const std::string& format) {
  if (format == "exr") {
    static const ImageReader* exr = loadModule<ImageReader>("liblucent_image_exr.so", "lucentImageReader",
                                                            kImageReaderInterface, "reader, which reads EXR files");
    return *exr;
  }
  static const ImageReader* others =
      loadModule<ImageReader>("liblucent_image_oiio.so", "lucentImageReader", kImageReaderInterface,
                              "reader, which reads HDR, PFM, PNG, JPEG and TIFF files");
  return *others;
}

}  // namespace lucent
