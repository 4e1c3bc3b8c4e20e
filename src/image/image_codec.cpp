#include "image/image_codec.h"

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>

namespace lucent {

namespace {

constexpr const char* kModule = "liblucent_image_codec.so";

// The module by its name (the library path: the caller's run path, which the build and the install
// give every program linking Lucent, LD_LIBRARY_PATH, the system's directories), else beside the
// program or shared object this code is linked into, or one directory up (a Python module's).
void* openModule(std::string& why) {
  if (void* module = dlopen(kModule, RTLD_LAZY | RTLD_LOCAL)) return module;
  why = dlerror();
  Dl_info self;
  if (dladdr(reinterpret_cast<const void*>(&imageCodec), &self) == 0 || !self.dli_fname) return nullptr;
  const std::filesystem::path here = std::filesystem::path(self.dli_fname).parent_path();
  for (const std::filesystem::path& candidate : {here / kModule, here.parent_path() / kModule})
    if (void* module = dlopen(candidate.c_str(), RTLD_LAZY | RTLD_LOCAL)) return module;
  return nullptr;
}

const ImageCodec* loadCodec() {
  std::string why;
  void* module = openModule(why);
  std::string message = "cannot load Lucent's image codec, which reads and writes image files: ";
  if (!module) throw std::runtime_error(message.append(why));
  const auto entry = reinterpret_cast<const ImageCodec* (*)()>(dlsym(module, "lucentImageCodec"));
  const ImageCodec* codec = entry ? entry() : nullptr;
  if (!codec || codec->interfaceVersion != kImageCodecInterface)
    throw std::runtime_error(message.append(kModule).append(" is not this build's (its interface differs)"));
  return codec;
}

}  // namespace

const ImageCodec& imageCodec() {
  static const ImageCodec* codec = loadCodec();
  return *codec;
}

}  // namespace lucent
