#include "lucent/image/image.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "lucent/core/files.h"
#include "lucent/core/memory.h"
#include "lucent/core/srgb.h"
#include "lucent/core/text.h"
#include "image/image_codec.h"

namespace lucent {

namespace fs = std::filesystem;

Image::Image(int width, int height, std::vector<std::string> channels)
    : width_(width), height_(height), channels_(std::move(channels)) {
  if (width < 0 || height < 0) throw std::invalid_argument("image size must be non-negative");
  pixels_.assign(size_t(width) * size_t(height) * channels_.size(), 0.0f);
}

int Image::channelIndex(const std::string& name) const {
  for (size_t c = 0; c < channels_.size(); ++c)
    if (channels_[c] == name) return static_cast<int>(c);
  return -1;
}

namespace {

void checkPixelCount(const Image& image, const std::string& path) {
  if (image.pixels().size() != size_t(image.width()) * image.height() * image.channelCount())
    throw std::runtime_error("cannot write image '" + path + "': pixel buffer does not match " +
                             std::to_string(image.width()) + "x" + std::to_string(image.height()) +
                             "x" + std::to_string(image.channelCount()));
  if (image.channelCount() == 0)
    throw std::runtime_error("cannot write image '" + path + "': it has no channels");
}

}  // namespace

namespace {

// The threads oneTBB may use (--threads), which the codecs' compression and decoding keep to.
int threadsAllowed() { return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)); }

FileToWrite exrFile(const Image& image, const std::string& path, const ImageMetadata& metadata) {
  checkPixelCount(image, path);
  const ImageWriter& writer = imageWriter();  // loaded before any file of the set is written
  return {path, "image", [&image, metadata, &writer](const fs::path& tmp) {
            const std::string why = writer.writeExr(tmp.string(), image.width(), image.height(), image.channels(),
                                                    metadata, image.pixels().data(), threadsAllowed());
            if (!why.empty()) throw WriteFailure(why);
          }};
}

FileToWrite pngFile(const Image& image, const std::string& path) {
  checkPixelCount(image, path);
  if (image.channelIndex("R") < 0 || image.channelIndex("G") < 0 || image.channelIndex("B") < 0)
    throw std::runtime_error("cannot write image '" + path + "': it needs R, G and B channels");
  imageWriter();  // loaded before any file of the set is written
  return {path, "image", [&image](const fs::path& tmp) {
            const std::vector<unsigned char> png = encodePng(image);
            std::ofstream out(tmp, std::ios::binary);
            out.write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
            out.close();
            if (!out) throw WriteFailure(std::strerror(errno));
          }};
}

}  // namespace

std::vector<unsigned char> encodePng(const Image& image) {
  const int rgb[3] = {image.channelIndex("R"), image.channelIndex("G"), image.channelIndex("B")};
  if (rgb[0] < 0 || rgb[1] < 0 || rgb[2] < 0) throw std::runtime_error("a PNG needs the image's R, G and B channels");
  std::vector<unsigned char> bytes(size_t(image.width()) * image.height() * 3);
  size_t i = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      for (int c : rgb) {
        float v = image.at(x, y, c);
        v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
        bytes[i++] = linearToSrgb8(v);
      }
  std::vector<unsigned char> png;
  if (const std::string why = imageWriter().encodePng(image.width(), image.height(), bytes.data(), png); !why.empty())
    throw std::runtime_error("cannot encode a PNG: " + why);
  return png;
}

void loadImageWriter() { imageWriter(); }

void writeExr(const Image& image, const std::string& path, const ImageMetadata& metadata) {
  writeFilesAtomically({exrFile(image, path, metadata)});
}

void writePng(const Image& image, const std::string& path) { writeFilesAtomically({pngFile(image, path)}); }

void writeExrAndPng(const Image& image, const std::string& exrPath, const ImageMetadata& metadata,
                    const std::string& pngPath, std::vector<FileToWrite> alsoWrite) {
  std::vector<FileToWrite> files = {exrFile(image, exrPath, metadata)};
  if (!pngPath.empty()) files.push_back(pngFile(image, pngPath));
  for (FileToWrite& f : alsoWrite) files.push_back(std::move(f));
  writeFilesAtomically(files);
}

namespace {

// The most bytes of pixel data, as the readers hand them over, that a byte of a compressed file
// decodes to: deflate's limit is 1,032 (EXR's zip and pxr24, PNG, TIFF's deflate), and a PNG's
// 1-bit palette indices become 3 bytes of RGB each: 1,032 x 8 x 3 = 24,768 below 2^15.
constexpr uint64_t kMostDecodedPerByte = uint64_t(1) << 15;

// The values OpenEXR reads at a fixed size whatever an attribute's size field says.
const std::map<std::string, int32_t> kExrFixedSizes = {
    {"box2i", 16},    {"box2f", 16},    {"chromaticities", 32}, {"compression", 1}, {"deepImageState", 1},
    {"double", 8},    {"envmap", 1},    {"float", 4},           {"int", 4},         {"keycode", 28},
    {"lineOrder", 1}, {"m33f", 36},     {"m33d", 72},           {"m44f", 64},       {"m44d", 128},
    {"rational", 8},  {"tiledesc", 9},  {"timecode", 8},        {"v2i", 8},         {"v2f", 8},
    {"v2d", 16},      {"v3i", 12},      {"v3f", 12},            {"v3d", 24}};

// Why an OpenEXR file's headers would make OpenEXR allocate more than the file holds (it allocates
// each attribute's claimed size, and a line-offset table for the claimed data window, as it reads
// the header: a 300-byte file claimed a 1.8 GB attribute), or "" where they would not. The layout:
// the magic and version words, then per part attributes (name, type name, int32 size, value) up to
// an empty name, parts up to an empty header where the file has several (version bit 12).
std::string exrHeaderProblem(std::ifstream& in, uint64_t fileBytes) {
  const auto readByte = [&]() {
    const int c = in.get();
    if (c == std::char_traits<char>::eof()) throw std::runtime_error("its header ends early");
    return char(c);
  };
  const auto readWord = [&]() {
    char b[4];
    for (char& c : b) c = readByte();
    int32_t v;
    std::memcpy(&v, b, 4);
    return v;
  };
  try {
    in.seekg(4);
    const int32_t version = readWord();
    const bool multipart = (version & 0x1000) != 0;
    // Names are read as OpenEXR reads them: up to a NUL or 256 bytes whatever the long-names flag
    // (which it checks afterwards), the next field starting where that stops.
    const auto readName = [&]() {
      std::string name;
      for (int n = 255; n >= 0; --n) {
        const char c = readByte();
        if (c == 0) break;
        name += c;
      }
      return name;
    };
    for (int part = 0;; ++part) {
      bool empty = true;
      int64_t width = 0, height = 0;
      uint64_t pixelBytes = 0;
      int compression = 0;
      uint32_t tileX = 0, tileY = 0;
      for (;;) {
        const std::string name = readName();
        if (name.empty()) break;
        empty = false;
        const std::string type = readName();
        const int32_t size = readWord();
        const uint64_t at = uint64_t(in.tellg());
        if (size < 0 || uint64_t(size) > fileBytes - std::min(fileBytes, at))
          return "attribute '" + excerpt(name) + "' claims " + std::to_string(size) + " bytes, more than the file holds";
        // OpenEXR reads a typed value by its type and goes on where that ends, whatever the size
        // says: the size must be the value's, or the fields after it are not where they seem.
        const auto fixed = kExrFixedSizes.find(type);
        if (fixed != kExrFixedSizes.end() && size != fixed->second)
          return "attribute '" + excerpt(name) + "' of type " + excerpt(type) + " claims " + std::to_string(size) +
                 " bytes, not " + std::to_string(fixed->second);
        if (type == "chlist") {
          int32_t consumed = 0;
          for (;;) {  // channel names, each followed by 16 bytes, up to an empty name
            const std::string channel = readName();
            consumed += int32_t(channel.size()) + 1;
            if (channel.empty()) break;
            const int32_t pixelType = readWord();  // uint, half, float
            for (int k = 0; k < 3; ++k) readWord();
            pixelBytes += pixelType == 1 ? 2 : 4;
            consumed += 16;
            if (consumed > size) break;
          }
          if (consumed != size) return "its channel list's size is not its content's";
        } else if (type == "preview") {
          if (size < 8) return "a preview of " + std::to_string(size) + " bytes";
          const uint32_t w = uint32_t(readWord()), h = uint32_t(readWord());
          if (uint64_t(w) * h * 4 + 8 != uint64_t(size)) return "its preview's size is not its content's";
          in.seekg(size - 8, std::ios::cur);
        } else if ((name == "dataWindow" || name == "displayWindow") && type == "box2i") {
          const int32_t x0 = readWord(), y0 = readWord(), x1 = readWord(), y1 = readWord();
          const int64_t w = int64_t(x1) - x0 + 1, h = int64_t(y1) - y0 + 1;
          if (w < 1 || h < 1 || uint64_t(w) * uint64_t(h) > kMaxImagePixels)
            return std::string(name) + " claims " + std::to_string(w) + " x " + std::to_string(h) +
                   " pixels (at most 2^26)";
          if (name == "dataWindow") width = w, height = h;
        } else if (name == "compression" && type == "compression") {
          compression = static_cast<unsigned char>(readByte());
        } else if (name == "tiles" && type == "tiledesc") {
          tileX = uint32_t(readWord()), tileY = uint32_t(readWord());
          readByte();
        } else {
          in.seekg(size, std::ios::cur);
        }
      }
      // Each chunk (a run of lines, or a tile) has an 8-byte offset in the file, which OpenEXR
      // reads into a table as long as the data window makes it.
      const int64_t linesPerChunk = compression == 3 || compression == 5 ? 16  // zip, pxr24
                                    : compression >= 4 && compression <= 8 ? 32  // piz, b44, b44a, dwaa
                                    : compression == 9                     ? 256 // dwab
                                                                           : 1;
      const uint64_t chunks = tileX > 0 && tileY > 0
                                  ? uint64_t((width + tileX - 1) / tileX) * uint64_t((height + tileY - 1) / tileY)
                                  : uint64_t((height + linesPerChunk - 1) / linesPerChunk);
      if (!empty && chunks * 8 > fileBytes)
        return "its data window needs " + std::to_string(chunks) + " chunk offsets, more than the file holds";
      // OpenEXR allocates a chunk's decoded bytes when it opens the file, before any pixel is read:
      // neither a chunk nor the whole image may hold more than the file's bytes can decode to.
      const uint64_t most = compression == 0 ? fileBytes : fileBytes * kMostDecodedPerByte;
      const uint64_t chunkBytes = tileX > 0 && tileY > 0 ? uint64_t(std::min<int64_t>(tileX, width)) *
                                                               uint64_t(std::min<int64_t>(tileY, height)) * pixelBytes
                                                         : uint64_t(width) * uint64_t(linesPerChunk) * pixelBytes;
      if (!empty && (chunkBytes > most || uint64_t(width) * uint64_t(height) * pixelBytes > most))
        return "its data window or tiles claim more pixel bytes than its " + std::to_string(fileBytes) +
               " bytes can hold";
      if (!multipart || empty) break;
      if (part >= 64) return "more than 64 parts";
    }
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// Why a JPEG stream is cut short, or "" where it reaches its end-of-image marker. libjpeg reads a
// truncated file with a warning that OpenImageIO drops, and fills what is missing with grey: a
// texture cut in half would render without a word. Walks the markers (each segment's length, the
// entropy-coded data after each start-of-scan up to the next marker that is neither a stuffed
// 0xFF00 nor a restart) to EOI; what follows EOI is not read.
std::string jpegStreamProblem(std::span<const unsigned char> b) {
  if (b.size() < 2 || b[0] != 0xFF || b[1] != 0xD8) return "not a JPEG stream (no start-of-image marker)";
  size_t at = 2;
  while (true) {
    while (at < b.size() && b[at] != 0xFF) ++at;  // libjpeg too skips bytes between segments
    while (at < b.size() && b[at] == 0xFF) ++at;  // fill bytes
    if (at >= b.size()) break;
    const unsigned char marker = b[at++];
    if (marker == 0xD9) return "";
    if ((marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) continue;
    if (at + 2 > b.size()) break;
    const size_t length = size_t(b[at]) << 8 | b[at + 1];
    if (length < 2) return "a segment's length is below 2";
    if (at + length > b.size()) break;
    at += length;
    if (marker != 0xDA) continue;
    // Entropy-coded data: up to a marker.
    while (at + 1 < b.size() && !(b[at] == 0xFF && b[at + 1] != 0x00 && !(b[at + 1] >= 0xD0 && b[at + 1] <= 0xD7)))
      at += b[at] == 0xFF ? 2 : 1;
    if (at + 1 >= b.size()) break;
  }
  return "the file ends before the image does (no end-of-image marker): truncated";
}

std::string lowercase(std::string text) {
  for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// The formats Lucent reads, by extension (docs/scene-format.md, map_Kd).
constexpr std::string_view kReadableExtensions[] = {".exr", ".hdr", ".pfm", ".png", ".jpg", ".jpeg", ".tif", ".tiff"};

// An opened image: its reader and the reader's handle, its header, and the bytes it reads where they
// are in memory.
struct OpenedImage {
  std::vector<unsigned char> bytes;  // what the reader reads, where the file was read whole first
  CodecImageInfo info;
  const ImageReader* reader = nullptr;
  void* handle = nullptr;
  OpenedImage() = default;
  OpenedImage(OpenedImage&& o) noexcept
      : bytes(std::move(o.bytes)), info(std::move(o.info)), reader(o.reader), handle(std::exchange(o.handle, nullptr)) {}
  OpenedImage& operator=(OpenedImage&&) = delete;
  ~OpenedImage() {
    if (handle) reader->close(handle);
  }
};

// The reader of `extension` (".png"...) opened on `name`, reading `memory` where given (which must
// outlive the result), its header checked against `sourceBytes`, what the file or memory holds.
OpenedImage openWithReader(const std::string& name, const std::string& extension, uint64_t sourceBytes,
                           std::optional<std::span<const unsigned char>> memory) {
  // The reader of the file's extension, and only that one: OpenImageIO's open() tries every reader
  // it has on a file its own does not take, and some abort the process on a crafted file (its RLA
  // reader asserts on a channel type; found by fuzzing).
  if (std::find(std::begin(kReadableExtensions), std::end(kReadableExtensions), extension) ==
      std::end(kReadableExtensions))
    throw std::runtime_error("cannot read image '" + name +
                             "': not a format Lucent reads (.exr, .hdr, .pfm, .png, .jpg or .jpeg, .tif or .tiff)");
  // Colour as stored beside its alpha (PNG's and glTF's convention), not premultiplied by it.
  OpenedImage opened;
  static const unsigned char kNoBytes = 0;  // an empty memory is still read from memory
  std::string error;
  const std::string format = extension.substr(1);
  opened.reader = &imageReader(format);
  opened.handle = opened.reader->open(name, format, memory ? (memory->empty() ? &kNoBytes : memory->data()) : nullptr,
                                      memory ? memory->size() : sourceBytes, threadsAllowed(), opened.info, error);
  if (!opened.handle) throw std::runtime_error("cannot read image '" + name + "': " + error);
  const CodecImageInfo& spec = opened.info;
  // The header's size is checked before any pixel is allocated (a 69-byte PNG may claim 20,000 x
  // 20,000).
  if (spec.width < 1 || spec.height < 1 || spec.channelCount < 1 || spec.channelCount > 1024 ||
      uint64_t(spec.width) * uint64_t(spec.height) > kMaxImagePixels)
    throw std::runtime_error("cannot read image '" + name + "': its header claims " + std::to_string(spec.width) + " x " +
                             std::to_string(spec.height) + " pixels of " + std::to_string(spec.channelCount) +
                             " channels (at most 2^26 pixels and 1,024 channels)");
  if (spec.depth > 1)
    throw std::runtime_error("cannot read image '" + name + "': a volume of " + std::to_string(spec.depth) +
                             " slices, not an image");
  // And against the source's size: a 4.6 KB EXR claiming 8192 x 8192 pixels of 10 float channels
  // would have 2.7 GB allocated and filled before its missing data failed the read.
  uint64_t pixelBits = uint64_t(spec.storedPixelBits);
  if (pixelBits == 0)
    for (const int bits : spec.channelBits) pixelBits += uint64_t(bits);
  const uint64_t stored = (uint64_t(spec.width) * uint64_t(spec.height) * pixelBits + 7) / 8;
  const std::string& compression = spec.compression;
  // A PFM's floats are stored as they are.
  const bool raw = compression == "none" || extension == ".pfm";
  const uint64_t most = raw ? sourceBytes : sourceBytes * kMostDecodedPerByte;
  if (stored > most)
    throw std::runtime_error("cannot read image '" + name + "': its header claims " + std::to_string(spec.width) +
                             " x " + std::to_string(spec.height) + " pixels of " + std::to_string(spec.channelCount) +
                             " channels (" + std::to_string(stored) + " bytes), more than its " +
                             std::to_string(sourceBytes) + " bytes can hold" +
                             (compression.empty() ? "" : " compressed as " + compression));
  return opened;
}

// The opened file, its header checked (see readImageHeader).
OpenedImage openChecked(const std::string& path) {
  // A device or pipe (/dev/zero) would be read for ever.
  const std::string problem = regularFileProblem(path);
  if (problem == "not found") throw std::runtime_error("image file not found: '" + path + "'");
  if (!problem.empty()) throw std::runtime_error("cannot read image '" + path + "': " + problem);
  std::error_code ec;
  const uint64_t fileBytes = std::filesystem::file_size(path, ec);
  {
    std::ifstream file(path, std::ios::binary);
    char magic[4] = {};
    file.read(magic, 4);
    if (file && std::memcmp(magic, "\x76\x2f\x31\x01", 4) == 0) {
      const std::string why = exrHeaderProblem(file, ec ? 0 : fileBytes);
      if (!why.empty()) throw std::runtime_error("cannot read image '" + path + "': a damaged EXR header: " + why);
    }
  }
  const std::string extension = lowercase(std::filesystem::path(path).extension().string());
  if (extension == ".jpg" || extension == ".jpeg") {
    // Read once: checked to its end, then decoded from memory.
    std::ifstream file(path, std::ios::binary);
    std::vector<unsigned char> bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (const std::string why = jpegStreamProblem(bytes); !why.empty())
      throw std::runtime_error("cannot read image '" + path + "': " + why);
    OpenedImage opened = openWithReader(path, extension, bytes.size(), bytes);
    opened.bytes = std::move(bytes);  // the buffer the reader reads moves with it
    return opened;
  }
  return openWithReader(path, extension,
                        ec ? std::numeric_limits<uint64_t>::max() / kMostDecodedPerByte : fileBytes, std::nullopt);
}

std::vector<std::string> channelNames(const CodecImageInfo& info) {
  std::vector<std::string> names = info.channelNames;
  for (int c = int(names.size()); c < info.channelCount; ++c) names.push_back("channel" + std::to_string(c));
  names.resize(size_t(info.channelCount));
  return names;
}

// A grey PFM ("Pf") is read as the same value in R, G and B: compared as a colour image.
bool isGreyPfm(const CodecImageInfo& info) {
  return info.formatName == "pnm" && info.channelCount == 1 && info.floatFormat;
}

std::vector<std::string> channelsAsRead(const CodecImageInfo& info) {
  return isGreyPfm(info) ? std::vector<std::string>{"R", "G", "B"} : channelNames(info);
}

}  // namespace

const char* colourEncodingName(ColourEncoding encoding) {
  switch (encoding) {
    case ColourEncoding::Float: return "float";
    case ColourEncoding::Half: return "half";
    case ColourEncoding::Integer: return "integer";
    case ColourEncoding::SharedExponent: return "rgbe";
    case ColourEncoding::Lossy: return "lossy";
  }
  return "float";
}

std::optional<ColourEncoding> colourEncodingNamed(const std::string& name) {
  for (const ColourEncoding e : {ColourEncoding::Float, ColourEncoding::Half, ColourEncoding::Integer,
                                 ColourEncoding::SharedExponent, ColourEncoding::Lossy})
    if (name == colourEncodingName(e)) return e;
  return std::nullopt;
}

ImageHeader readImageHeader(const std::string& path) {
  const OpenedImage opened = openChecked(path);
  const CodecImageInfo& spec = opened.info;
  ImageHeader header{spec.width, spec.height, channelsAsRead(spec), {}};
  for (int c = 0; c < spec.channelCount && size_t(c) < header.channels.size(); ++c) {
    const std::string& name = header.channels[size_t(c)];
    const double largestCode = spec.channelLargestCode[size_t(c)];
    if (spec.channelIsHalf[size_t(c)]) header.halfChannels.push_back(name);
    else if ((name == "R" || name == "G" || name == "B") && largestCode > 0)
      header.largestCode = header.largestCode > 0 ? std::min(header.largestCode, largestCode) : largestCode;
  }
  // EXR's DWA compressions are lossy, B44 for half channels; PXR24 rounds floats to 24 bits (half
  // floats' allowance is the nearest above it). A TIFF may hold JPEG data.
  const std::string& compression = spec.compression;
  const bool lossy = spec.formatName == "jpeg" || compression == "jpeg" || compression == "dwaa" || compression == "dwab" ||
                     ((compression == "b44" || compression == "b44a") && header.hasHalfColour());
  if (lossy) header.colourEncoding = ColourEncoding::Lossy;
  else if (spec.formatName == "hdr") header.colourEncoding = ColourEncoding::SharedExponent;
  // Half floats before integer codes: an EXR may mix half channels with 32-bit unsigned ones, whose
  // steps are far finer.
  else if (header.hasHalfColour() || compression == "pxr24") header.colourEncoding = ColourEncoding::Half;
  else if (header.largestCode > 0) header.colourEncoding = ColourEncoding::Integer;
  if (header.colourEncoding != ColourEncoding::Integer) header.largestCode = 0;
  return header;
}

namespace {

Image readOpened(OpenedImage opened, const std::string& name, ImageMetadata* metadata) {
  const CodecImageInfo& spec = opened.info;
  // The pixels as floats, and the decoder's scanlines: OpenImageIO decodes up to 256 at a time in
  // their stored format (up to 8 bytes a channel; for a Radiance header claiming 19,854,521 x 2
  // pixels it asked for 61 GB, found by fuzzing), OpenEXR fewer.
  const uint64_t floats = uint64_t(spec.width) * uint64_t(spec.height) * uint64_t(spec.channelCount);
  requireMemory(floats * sizeof(float) * (isGreyPfm(spec) ? 4 : 1) + 256 * uint64_t(spec.width) * uint64_t(spec.channelCount) * 8,
                "the image '" + name + "'", "raise --memory-limit if the machine has the memory");
  Image image(spec.width, spec.height, channelNames(spec));
  if (const std::string why = opened.reader->readPixels(opened.handle, image.pixels().data()); !why.empty())
    throw std::runtime_error("cannot read image '" + name + "': " + why);
  if (isGreyPfm(spec)) {
    Image rgb(spec.width, spec.height, {"R", "G", "B"});
    for (int y = 0; y < spec.height; ++y)
      for (int x = 0; x < spec.width; ++x)
        for (int c = 0; c < 3; ++c) rgb.at(x, y, c) = image.at(x, y, 0);
    image = std::move(rgb);
  }
  if (metadata) *metadata = opened.reader->stringAttributes(opened.handle);
  return image;
}

}  // namespace

Image readImage(const std::string& path, ImageMetadata* metadata) { return readOpened(openChecked(path), path, metadata); }

Image readImageFromMemory(const std::string& name, const std::string& extension, std::span<const unsigned char> bytes,
                          ImageMetadata* metadata) {
  if (extension != ".png" && extension != ".jpg")
    throw std::runtime_error("cannot read image '" + name + "': only PNG and JPEG are read from memory");
  if (extension == ".jpg")
    if (const std::string why = jpegStreamProblem(bytes); !why.empty())
      throw std::runtime_error("cannot read image '" + name + "': " + why);
  return readOpened(openWithReader(name, extension, bytes.size(), bytes), name, metadata);
}

bool isSrgbEncoded(const std::string& path, const ImageMetadata& metadata) {
  for (const auto& [key, value] : metadata)
    if (key == "oiio:ColorSpace") return lowercase(value).find("srgb") != std::string::npos;
  const std::string ext = lowercase(fs::path(path).extension().string());
  return ext == ".jpg" || ext == ".jpeg" || ext == ".png";
}

Image readLinearImage(const std::string& path, ImageMetadata* metadataOut) {
  ImageMetadata metadata;
  Image image = readImage(path, &metadata);
  if (metadataOut) *metadataOut = metadata;
  if (!isSrgbEncoded(path, metadata)) return image;
  for (int c = 0; c < image.channelCount(); ++c) {
    if (image.channels()[size_t(c)] == "A") continue;  // alpha is stored linear
    for (int y = 0; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) image.at(x, y, c) = srgbToLinear(image.at(x, y, c));
  }
  return image;
}

}  // namespace lucent
