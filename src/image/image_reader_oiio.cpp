// liblucent_image_oiio.so: image_codec.h's ImageReader on OpenImageIO, for every format but EXR.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "image/image_codec.h"

namespace lucent {
namespace {

// OpenImageIO's message, or `otherwise` where a reader failed without one (its PFM reader
// does on a truncated file): "" would read as success.
std::string failure(const std::string& message, const char* otherwise) { return message.empty() ? otherwise : message; }

struct Opened {
  std::unique_ptr<OIIO::Filesystem::IOMemReader> memory;
  std::unique_ptr<OIIO::ImageInput> in;
};

void* open(const std::string& name, const std::string& format, const unsigned char* memory, size_t bytes, int threads,
           CodecImageInfo& info, std::string& error) {
  OIIO::attribute("threads", threads);  // its conversions keep to --threads
  auto opened = std::make_unique<Opened>();
  // Created by the format's name: given the path, create() also tries every other reader when the
  // file is not valid for its own.
  opened->in = OIIO::ImageInput::create(format, false);
  auto& in = opened->in;
  if (in && memory) {
    opened->memory = std::make_unique<OIIO::Filesystem::IOMemReader>(const_cast<unsigned char*>(memory), bytes);
    if (!in->set_ioproxy(opened->memory.get())) {
      error = "its reader cannot read from memory";
      return nullptr;
    }
  }
  OIIO::ImageSpec header, config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  if (!in || !in->open(name, header, config)) {
    error = failure(in ? in->geterror() : OIIO::geterror(), "its header cannot be read");
    return nullptr;
  }
  const OIIO::ImageSpec& spec = in->spec();
  info.width = spec.width, info.height = spec.height, info.depth = spec.depth, info.channelCount = spec.nchannels;
  info.channelNames = spec.channelnames;
  // A TIFF of 10, 12 or 14 bits is read as 16-bit codes, scaled to their full range: its steps
  // are those of its own bits. A palette TIFF's bits are its index's: its colours are the
  // palette's codes, of the channels' size (TIFF's PhotometricInterpretation 3).
  const int bitsPerSample = spec.get_int_attribute("oiio:BitsPerSample", 0);
  const bool palette = std::string(in->format_name()) == "tiff" && spec.get_int_attribute("tiff:PhotometricInterpretation", -1) == 3;
  if (palette) info.storedPixelBits = std::max(bitsPerSample, 1);
  for (int c = 0; c < spec.nchannels; ++c) {
    const OIIO::TypeDesc type = spec.channelformat(c);
    const int bits = !palette && bitsPerSample > 0 && bitsPerSample < int(8 * type.size()) ? bitsPerSample
                                                                                          : int(8 * type.size());
    info.channelBits.push_back(bits);
    info.channelIsHalf.push_back(type == OIIO::TypeDesc::HALF);
    const bool integer = !type.is_floating_point();
    info.channelLargestCode.push_back(!integer ? 0.0 : std::ldexp(1.0, type.is_signed() ? bits - 1 : bits) - 1);
  }
  info.compression = spec.get_string_attribute("compression", "");
  info.formatName = in->format_name();
  info.floatFormat = spec.format == OIIO::TypeDesc::FLOAT;
  return opened.release();
}

std::string readPixels(void* image, float* pixels) {
  auto& in = static_cast<Opened*>(image)->in;
  if (!in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, pixels))
    return failure(in->geterror(), "its pixels cannot be read: truncated or damaged");
  return "";
}

CodecAttributes stringAttributes(void* image) {
  CodecAttributes attributes;
  for (const OIIO::ParamValue& p : static_cast<Opened*>(image)->in->spec().extra_attribs)
    if (p.type() == OIIO::TypeDesc::STRING) attributes.emplace_back(p.name().string(), p.get_string());
  return attributes;
}

void close(void* image) {
  std::unique_ptr<Opened> opened(static_cast<Opened*>(image));
  opened->in->close();
}

const ImageReader kReader{kImageReaderInterface, open, readPixels, stringAttributes, close};

}  // namespace
}  // namespace lucent

extern "C" __attribute__((visibility("default"))) const lucent::ImageReader* lucentImageReader() { return &lucent::kReader; }
