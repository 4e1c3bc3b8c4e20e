// Float images with named channels (interleaved), and their EXR/PNG input and output.
#pragma once
#include <cstdint>
#include <span>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lucent/core/files.h"
#include "lucent/core/math.h"

namespace lucent {

// Largest image Lucent reads, and a camera may ask for (the path tracer keeps about 40 bytes per
// pixel).
inline constexpr uint64_t kMaxImagePixels = uint64_t(1) << 26;
// Widest and tallest image a camera may ask for.
inline constexpr int kMaxImageSide = 65536;

class Image {
 public:
  Image() = default;
  // Channel names follow the EXR convention: "R","G","B" for the beauty image and
  // "layer.R" etc. for extra layers (e.g. "albedo.R", "normal.X", "depth.Z").
  Image(int width, int height, std::vector<std::string> channels);

  int width() const { return width_; }
  int height() const { return height_; }
  int channelCount() const { return static_cast<int>(channels_.size()); }
  const std::vector<std::string>& channels() const { return channels_; }
  // Index of a channel by name, or -1.
  int channelIndex(const std::string& name) const;

  float& at(int x, int y, int c) { return pixels_[(size_t(y) * width_ + x) * channels_.size() + c]; }
  float at(int x, int y, int c) const { return pixels_[(size_t(y) * width_ + x) * channels_.size() + c]; }
  std::vector<float>& pixels() { return pixels_; }
  const std::vector<float>& pixels() const { return pixels_; }

 private:
  int width_ = 0, height_ = 0;
  std::vector<std::string> channels_;
  std::vector<float> pixels_;
};

// String attributes stored in the EXR header (e.g. "lucent:method" -> "pt").
using ImageMetadata = std::vector<std::pair<std::string, std::string>>;

// Loads the module that writes image files (liblucent_image_exr.so, found through the program's
// run path or LD_LIBRARY_PATH), which the functions below load on first use: a scene opened for
// rendering (OpenScene) loads it first, so that a missing module stops a render before it starts,
// not when its image is written. Throws std::runtime_error where it cannot be loaded. (It reads
// EXRs too; the other formats are read by liblucent_image_oiio.so, loaded by the first read of one.)
void loadImageWriter();
// Seconds this process has spent loading the image modules (dynamic linking, their static
// initialisers): set-up, which a scene's clock leaves out. The reader of textures
// (liblucent_image_oiio.so and OpenImageIO's 260 libraries, about 0.25 s) loads with the first
// texture, inside a scene's loading.
double codecLoadingSeconds();

// Writes 32-bit float EXR with every channel and the metadata. The file is written under a
// temporary name in the same directory and renamed, so no partial file is ever visible.
// Throws std::runtime_error naming the path on failure.
void writeExr(const Image& image, const std::string& path, const ImageMetadata& metadata = {});
// Writes the R, G, B channels as 8-bit sRGB-encoded PNG, clamped to [0,1]; atomically, as writeExr.
void writePng(const Image& image, const std::string& path);
// The R, G, B channels as writePng writes them, encoded in memory (for pages that embed images).
std::vector<unsigned char> encodePng(const Image& image);
// The EXR and, when pngPath is not empty, the PNG, and any other files given (a render's film file),
// written as one: if any cannot be written, none exists afterwards.
void writeExrAndPng(const Image& image, const std::string& exrPath, const ImageMetadata& metadata,
                    const std::string& pngPath, std::vector<FileToWrite> alsoWrite = {});
// How a file stores its colour values: 32-bit floats, half floats (or floats cut to 24 bits),
// integer codes (ImageHeader::largestCode), Radiance's RGBE (8-bit mantissas under one exponent per
// pixel), or lossily (JPEG; EXR's DWA compressions, B44 of half floats).
enum class ColourEncoding { Float, Half, Integer, SharedExponent, Lossy };
// "float", "half", "integer", "rgbe", "lossy"; and back (std::nullopt for another name).
const char* colourEncodingName(ColourEncoding encoding);
std::optional<ColourEncoding> colourEncodingNamed(const std::string& name);

// What an image file's header says, read without its pixels.
struct ImageHeader {
  int width = 0, height = 0;
  std::vector<std::string> channels;
  std::vector<std::string> halfChannels;  // those stored as 16-bit floats (EXR half)
  ColourEncoding colourEncoding = ColourEncoding::Float;  // of R, G, B (Half: of any colour channel)
  // Integer codes: the largest code of R, G and B, which reads as 1 (the fewest of their steps:
  // 255 for 8 bits, 4,095 for 12, 32,767 for signed 16-bit codes).
  double largestCode = 0;
  // Whether a variance channel (variance.R, LAYER.variance.R, ...) is among them: small variances
  // are then 0, and the noise they describe unknown.
  bool hasHalfVariance() const {
    for (const std::string& name : halfChannels)
      if (name.find("variance.") != std::string::npos) return true;
    return false;
  }
  // Whether a colour channel (R, G, B, LAYER.R, ...; not a variance) is among them: its values are
  // then rounded to 11 significant bits.
  bool hasHalfColour() const {
    for (const std::string& name : halfChannels) {
      const bool colour = name == "R" || name == "G" || name == "B" ||
                          (name.size() > 2 && name[name.size() - 2] == '.' && std::string("RGB").find(name.back()) != std::string::npos);
      if (colour && name.find("variance.") == std::string::npos) return true;
    }
    return false;
  }
};
// The header of an image in a format Lucent reads (EXR, Radiance HDR, PNG, JPEG, TIFF, by the
// extension; its content must be that format), checked as readImage checks it (a regular file, at most
// 2^26 pixels and 1,024 channels, no more pixel data than the file's bytes could hold however they
// are compressed). Throws std::runtime_error naming the file.
ImageHeader readImageHeader(const std::string& path);
// Reads an image as float, with its channel names and string metadata: the values as stored.
// Refuses what readImageHeader refuses before any pixel is allocated.
Image readImage(const std::string& path, ImageMetadata* metadata = nullptr);
// readImage of a PNG or JPEG (`extension` ".png" or ".jpg") held in memory (an image embedded in a
// glTF file), checked alike; `name` names it in messages.
Image readImageFromMemory(const std::string& name, const std::string& extension, std::span<const unsigned char> bytes,
                          ImageMetadata* metadata = nullptr);
// Whether stored values are sRGB-encoded: the colour space the file's metadata names
// ("oiio:ColorSpace", which OpenImageIO reports: sRGB for 8-bit JPEG, PNG, TIFF...; linear for HDR),
// or, where it names none (an EXR), the extension (sRGB for .png, .jpg and .jpeg).
bool isSrgbEncoded(const std::string& path, const ImageMetadata& metadata);
// readImage with sRGB-encoded values decoded to linear (every channel but alpha).
Image readLinearImage(const std::string& path, ImageMetadata* metadata = nullptr);

}  // namespace lucent
