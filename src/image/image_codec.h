// The image file formats' encoders and decoders, in two modules of their own, each loaded the first
// time it is needed: liblucent_image_exr.so writes EXR and PNG and reads EXR with OpenEXR and
// libpng, and liblucent_image_oiio.so reads the other formats Lucent reads (HDR, PFM, PNG, JPEG,
// TIFF) with OpenImageIO. OpenImageIO brings about 260 shared libraries, whose loading takes a
// process 0.3 s of CPU (OpenEXR's and libpng's a few milliseconds): paid only by a process that reads
// one of those formats (a textured scene, an image another renderer wrote), not by each render that
// writes an image, each compare or report of EXRs, each command that refuses its input, or each
// test. image.cpp makes every check and decision; the modules only call their libraries. Their
// interfaces hold only standard types and plain records: the modules link nothing of Lucent's.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lucent {

using CodecAttributes = std::vector<std::pair<std::string, std::string>>;

// The writer's functions. Each returns "" or says why it failed (its library's message).
struct ImageWriter {
  uint32_t interfaceVersion;  // kImageWriterInterface: a module of another build is refused
  // A 32-bit float EXR of interleaved `pixels`, zip-compressed, its channels named, with the string
  // attributes (none of them one of the header's standard attributes), compressed by at most
  // `threads` threads at once.
  std::string (*writeExr)(const std::string& path, int width, int height, const std::vector<std::string>& channels,
                          const CodecAttributes& attributes, const float* pixels, int threads);
  // 8-bit sRGB-encoded RGB, interleaved, as a PNG in memory, marked sRGB.
  std::string (*encodePng)(int width, int height, const unsigned char* rgb, std::vector<unsigned char>& png);
};

// What an opened image's header says, as OpenImageIO gives it (the EXR reader gives the same).
struct CodecImageInfo {
  int width = 0, height = 0, depth = 1, channelCount = 0;
  std::vector<std::string> channelNames;  // may be fewer than channelCount
  std::vector<int> channelBits;           // per channel: its stored value's size (12 in a 12-bit TIFF)
  // The bits a pixel takes in the file where not the channels' sum (0): a palette image's index,
  // which the reader hands over as RGB codes of the palette's.
  int storedPixelBits = 0;
  std::vector<uint8_t> channelIsHalf;     // per channel: stored as a 16-bit float
  // Per channel: for integer codes the largest, which reads as 1 (255 for 8 bits, 4,095 for 12,
  // 32,767 for signed 16-bit codes); 0 for floats.
  std::vector<double> channelLargestCode;
  std::string compression;                // its "compression" attribute, "" where none
  std::string formatName;                 // OpenImageIO's name of the format ("openexr", "pnm"...)
  bool floatFormat = false;               // the image's format is 32-bit float
};

// A reader's functions. Each returns "" or says why it failed (its library's message).
struct ImageReader {
  uint32_t interfaceVersion;  // kImageReaderInterface
  // Opens `name` with the reader of `format` ("exr", "png"...) and only that one, reading from
  // `memory` where it is not null (which must outlive the handle; the EXR reader reads files only),
  // colour unassociated from alpha, decoded by at most `threads` threads at once; `bytes` is the
  // size of the memory or the file. The handle, or null with `error` set.
  void* (*open)(const std::string& name, const std::string& format, const unsigned char* memory, size_t bytes,
                int threads, CodecImageInfo& info, std::string& error);
  // Every channel of the opened image as float, interleaved.
  std::string (*readPixels)(void* image, float* pixels);
  // Its string attributes.
  CodecAttributes (*stringAttributes)(void* image);
  void (*close)(void* image);
};

inline constexpr uint32_t kImageWriterInterface = 2;
inline constexpr uint32_t kImageReaderInterface = 5;

// Each module's functions, loaded on the first call (thread-safe); throws std::runtime_error where
// the module cannot be loaded. The reader of `format` ("exr", "png"...): OpenEXR's for EXR,
// OpenImageIO's for the others.
const ImageWriter& imageWriter();
const ImageReader& imageReader(const std::string& format);

}  // namespace lucent

// The modules' exports: liblucent_image_exr.so has both, liblucent_image_oiio.so the reader.
extern "C" const lucent::ImageWriter* lucentImageWriter();
extern "C" const lucent::ImageReader* lucentImageReader();
