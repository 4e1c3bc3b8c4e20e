// The image file formats' encoders and decoders (OpenImageIO), in a module of their own,
// liblucent_image_codec.so, loaded the first time an image is read or written: OpenImageIO brings
// about 260 shared libraries, whose loading took every process 0.25 s at its start (5 ms without
// them), paid by each command that refuses its input, each render written only as a film, and
// each test. image.cpp makes every check and decision; the module only calls OpenImageIO. Its
// interface holds only standard types and plain records: the module links nothing of Lucent's.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lucent {

// What an opened image's header says, as OpenImageIO gives it.
struct CodecImageInfo {
  int width = 0, height = 0, depth = 1, channelCount = 0;
  std::vector<std::string> channelNames;  // may be fewer than channelCount
  std::vector<int> channelBytes;          // per channel: its stored value's size
  std::vector<uint8_t> channelIsHalf;     // per channel: stored as a 16-bit float
  std::string compression;                // its "compression" attribute, "" where none
  std::string formatName;                 // OpenImageIO's name of the format ("openexr", "pnm"...)
  bool floatFormat = false;               // the image's format is 32-bit float
};

using CodecAttributes = std::vector<std::pair<std::string, std::string>>;

// The module's functions. Each returns "" or says why it failed (OpenImageIO's message).
struct ImageCodec {
  uint32_t interfaceVersion;  // kImageCodecInterface: a module of another build is refused
  // A 32-bit float EXR of interleaved `pixels`, its channels named, `alphaChannel` the alpha's
  // index or -1, with the string attributes.
  std::string (*writeExr)(const std::string& path, int width, int height, const std::vector<std::string>& channels,
                          int alphaChannel, const CodecAttributes& attributes, const float* pixels);
  // 8-bit sRGB-encoded RGB, interleaved, as a PNG in memory.
  std::string (*encodePng)(int width, int height, const unsigned char* rgb, std::vector<unsigned char>& png);
  // Opens `name` with the reader of `format` ("exr", "png"...) and only that one, reading `bytes`
  // from `memory` where it is not null (which must outlive the handle), colour unassociated from
  // alpha; the handle, or null with `error` set.
  void* (*open)(const std::string& name, const std::string& format, const unsigned char* memory, size_t bytes,
                CodecImageInfo& info, std::string& error);
  // Every channel of the opened image as float, interleaved.
  std::string (*readPixels)(void* image, float* pixels);
  // Its string attributes.
  CodecAttributes (*stringAttributes)(void* image);
  void (*close)(void* image);
};

inline constexpr uint32_t kImageCodecInterface = 1;

// The module's functions, loaded on the first call (thread-safe); throws std::runtime_error where
// the module cannot be loaded.
const ImageCodec& imageCodec();

}  // namespace lucent

// The module's one export.
extern "C" const lucent::ImageCodec* lucentImageCodec();
