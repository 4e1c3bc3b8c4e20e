// liblucent_image_exr.so's reader: image_codec.h's ImageReader for EXR files, on OpenEXR. It gives
// what the OpenImageIO reader gave for the same file (tests/image/test_image_codecs.cpp checks
// both on crafted files): the first part, channels in OpenImageIO's order, unsigned integer channels
// scaled to [0, 1], the string attributes by their names; subsampled channels (a luminance-chroma
// image's) refused.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <exception>
#include <memory>
#include <span>
#include <string_view>

#include "image/image_codec.h"
#include "image/openexr_threads.h"

namespace lucent {
namespace {

// Below this many bytes of file a decode stays on the calling thread: starting OpenEXR's threads
// would cost more than they save.
constexpr size_t kBytesWorthThreads = size_t(1) << 20;

// The widest and tallest data window read (image.cpp bounds the pixels to 2^26).
constexpr int64_t kMostSide = int64_t(1) << 26;

bool sameLetters(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

// A channel's name as layer ("diffuse.", with its dot; "" where none) and suffix ("R").
struct ChannelName {
  std::string name, layer, suffix;
  int rank = 10000;  // the suffix's place among the reserved names, case ignored
  Imf::PixelType type;
};

// The suffixes that come first in a layer, in this order; where a layer has X and Y or Z it holds a
// position or normal, and X, Y, Z come right after the colours.
constexpr std::array kColourOrder = {"R",  "Red", "G",  "Green", "B",  "Blue", "Y",  "real", "imag", "A",
                                     "Alpha", "AR", "RA", "AG", "GA", "AB", "BA", "Z", "Depth", "Zback"};
constexpr std::array kVectorOrder = {"R",  "Red",  "G",  "Green", "B",  "Blue", "X",  "Y",  "Z",     "real",
                                     "imag", "A", "Alpha", "AR", "RA", "AG", "GA", "AB", "BA", "Depth", "Zback"};

bool hasSuffix(const std::vector<ChannelName>& channels, size_t begin, size_t end, std::string_view suffix) {
  for (size_t i = begin; i < end; ++i)
    if (sameLetters(channels[i].suffix, suffix)) return true;
  return false;
}

// The file's channels sorted as OpenImageIO presents them: by layer, then by the suffix's reserved
// rank, then by suffix.
std::vector<ChannelName> channelsInOrder(const Imf::ChannelList& list) {
  std::vector<ChannelName> channels;
  for (auto c = list.begin(); c != list.end(); ++c) channels.push_back({c.name(), {}, {}, 10000, c.channel().type});
  for (ChannelName& c : channels) {
    const size_t dot = c.name.find_last_of('.');
    c.layer = dot == std::string::npos ? "" : c.name.substr(0, dot + 1);
    c.suffix = dot == std::string::npos ? c.name : c.name.substr(dot + 1);
  }
  std::stable_sort(channels.begin(), channels.end(), [](const ChannelName& a, const ChannelName& b) { return a.layer < b.layer; });
  for (size_t begin = 0; begin < channels.size();) {
    size_t end = begin + 1;
    while (end < channels.size() && channels[end].layer == channels[begin].layer) ++end;
    const bool vector = hasSuffix(channels, begin, end, "X") &&
                        (hasSuffix(channels, begin, end, "Y") || hasSuffix(channels, begin, end, "Z"));
    for (size_t i = begin; i < end; ++i) {
      const std::span<const char* const> order = vector ? std::span<const char* const>(kVectorOrder) : kColourOrder;
      const auto place = std::find_if(order.begin(), order.end(), [&](const char* s) { return sameLetters(channels[i].suffix, s); });
      if (place != order.end()) channels[i].rank = int(place - order.begin());
    }
    std::sort(channels.begin() + long(begin), channels.begin() + long(end), [](const ChannelName& a, const ChannelName& b) {
      return a.rank != b.rank ? a.rank < b.rank : a.suffix < b.suffix;
    });
    begin = end;
  }
  return channels;
}

const char* compressionName(Imf::Compression compression) {
  switch (compression) {
    case Imf::NO_COMPRESSION: return "none";
    case Imf::RLE_COMPRESSION: return "rle";
    case Imf::ZIPS_COMPRESSION: return "zips";
    case Imf::ZIP_COMPRESSION: return "zip";
    case Imf::PIZ_COMPRESSION: return "piz";
    case Imf::PXR24_COMPRESSION: return "pxr24";
    case Imf::B44_COMPRESSION: return "b44";
    case Imf::B44A_COMPRESSION: return "b44a";
    case Imf::DWAA_COMPRESSION: return "dwaa";
    case Imf::DWAB_COMPRESSION: return "dwab";
    default: return "unknown";
  }
}

struct Opened {
  std::unique_ptr<Imf::MultiPartInputFile> file;
  std::vector<ChannelName> channels;
  Imath::Box2i window;
};

void* open(const std::string& name, const std::string& format, const unsigned char* memory, size_t bytes, int threads,
           CodecImageInfo& info, std::string& error) {
  if (format != "exr" || memory) {
    error = "only EXR files are read by OpenEXR";
    return nullptr;
  }
  try {
    auto opened = std::make_unique<Opened>();
    opened->file = std::make_unique<Imf::MultiPartInputFile>(name.c_str(),
                                                             bytes >= kBytesWorthThreads ? openexrThreads(threads) : 0);
    const Imf::Header& header = opened->file->header(0);
    if (header.hasType() && Imf::isDeepData(header.type())) {
      error = "it holds deep data (samples per pixel), not an image";
      return nullptr;
    }
    opened->channels = channelsInOrder(header.channels());
    if (opened->channels.empty()) {
      error = "it has no channels";
      return nullptr;
    }
    for (const ChannelName& c : opened->channels)
      if (const Imf::Channel& channel = header.channels()[c.name.c_str()];
          channel.xSampling != 1 || channel.ySampling != 1) {
        error = "its channel '" + c.name + "' is subsampled";
        return nullptr;
      }
    opened->window = header.dataWindow();
    const int64_t width = int64_t(opened->window.max.x) - opened->window.min.x + 1;
    const int64_t height = int64_t(opened->window.max.y) - opened->window.min.y + 1;
    if (width < 1 || height < 1 || width > kMostSide || height > kMostSide) {
      error = "its data window claims " + std::to_string(width) + " x " + std::to_string(height) + " pixels";
      return nullptr;
    }
    info.width = int(width), info.height = int(height);
    info.channelCount = int(opened->channels.size());
    bool anyFloat = false, mixed = false;
    for (const ChannelName& c : opened->channels) {
      const bool half = c.type == Imf::HALF;
      info.channelNames.push_back(c.name);
      info.channelBits.push_back(half ? 16 : 32);
      info.channelIsHalf.push_back(half);
      info.channelLargestCode.push_back(c.type == Imf::UINT ? 4294967295.0 : 0.0);  // as readPixels scales them
      anyFloat = anyFloat || c.type == Imf::FLOAT;
      mixed = mixed || c.type != opened->channels[0].type;
    }
    // OpenImageIO's one format for all channels: the widest type, float where they differ.
    info.floatFormat = anyFloat || mixed;
    info.compression = compressionName(header.compression());
    info.formatName = "openexr";
    return opened.release();
  } catch (const std::exception& e) {
    error = e.what()[0] ? e.what() : "its header cannot be read";
    return nullptr;
  }
}

std::string readPixels(void* image, float* pixels) {
  const Opened& opened = *static_cast<Opened*>(image);
  try {
    const size_t width = size_t(opened.window.max.x - opened.window.min.x + 1);
    const size_t height = size_t(opened.window.max.y - opened.window.min.y + 1);
    const size_t count = opened.channels.size();
    // Unsigned integers are read into their float's place and converted there, scaled to [0, 1] as
    // OpenImageIO converts them (in float arithmetic, by 1 / (2^32 - 1) rounded to a float).
    Imf::FrameBuffer frame;
    for (size_t c = 0; c < count; ++c)
      frame.insert(opened.channels[c].name,
                   Imf::Slice::Make(opened.channels[c].type == Imf::UINT ? Imf::UINT : Imf::FLOAT, pixels + c,
                                    opened.window, sizeof(float) * count, sizeof(float) * count * width));
    Imf::InputPart part(*opened.file, 0);
    part.setFrameBuffer(frame);
    part.readPixels(opened.window.min.y, opened.window.max.y);
    for (size_t c = 0; c < count; ++c)
      if (opened.channels[c].type == Imf::UINT)
        for (size_t p = 0; p < width * height; ++p) {
          uint32_t stored;
          std::memcpy(&stored, pixels + p * count + c, sizeof stored);
          pixels[p * count + c] = float(stored) * (1.0f / 4294967295.0f);
        }
    return "";
  } catch (const std::exception& e) {
    return e.what()[0] ? e.what() : "its pixels cannot be read: truncated or damaged";
  }
}

CodecAttributes stringAttributes(void* image) {
  CodecAttributes attributes;
  const Imf::Header& header = static_cast<Opened*>(image)->file->header(0);
  // As OpenImageIO names them: three standard ones renamed, none empty, and not the part's type
  // ("scanlineimage"), which OpenEXR adds to every header it reads.
  static const std::pair<std::string_view, const char*> kRenamed[] = {
      {"capDate", "DateTime"}, {"comments", "ImageDescription"}, {"owner", "Copyright"}};
  for (auto a = header.begin(); a != header.end(); ++a) {
    const auto* text = dynamic_cast<const Imf::StringAttribute*>(&a.attribute());
    if (!text || text->value().empty() || a.name() == std::string_view("type")) continue;
    std::string name = a.name();
    for (const auto& [exr, oiio] : kRenamed)
      if (name == exr) name = oiio;
    attributes.emplace_back(name, text->value());
  }
  return attributes;
}

void close(void* image) { delete static_cast<Opened*>(image); }

const ImageReader kReader{kImageReaderInterface, open, readPixels, stringAttributes, close};

}  // namespace
}  // namespace lucent

extern "C" __attribute__((visibility("default"))) const lucent::ImageReader* lucentImageReader() { return &lucent::kReader; }
