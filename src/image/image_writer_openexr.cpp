// liblucent_image_exr.so's writer: image_codec.h's ImageWriter on OpenEXR and libpng.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <png.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <new>
#include <set>

#include "image/image_codec.h"
#include "image/openexr_threads.h"

namespace lucent {
namespace {

// Below this many values an image is compressed on the calling thread: starting OpenEXR's threads
// would cost more than they save.
constexpr size_t kValuesWorthThreads = size_t(1) << 20;

std::string writeExr(const std::string& path, int width, int height, const std::vector<std::string>& channels,
                     const CodecAttributes& attributes, const float* pixels, int threads) {
  try {
    Imf::Header header(width, height);  // the standard attributes: windows, aspect, line order
    header.compression() = Imf::ZIP_COMPRESSION;
    const size_t count = channels.size();
    if (std::set<std::string>(channels.begin(), channels.end()).size() != count)
      return "two channels have the same name";
    Imf::FrameBuffer frame;
    for (size_t c = 0; c < count; ++c) {
      header.channels().insert(channels[c], Imf::Channel(Imf::FLOAT));
      frame.insert(channels[c], Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(pixels + c)),
                                           sizeof(float) * count, sizeof(float) * count * size_t(width)));
    }
    for (const auto& [key, value] : attributes) {
      if (header.find(key) != header.end()) return "the attribute '" + key + "' is one of the EXR header's own";
      header.insert(key, Imf::StringAttribute(value));
    }
    const bool threaded = size_t(width) * size_t(height) * count >= kValuesWorthThreads;
    Imf::OutputFile file(path.c_str(), header, threaded ? openexrThreads(threads) : 0);
    file.setFrameBuffer(frame);
    file.writePixels(height);
    return "";
  } catch (const std::exception& e) {
    return e.what()[0] ? e.what() : "the file was not written";
  }
}

// libpng reports an error by calling this, which must not return: the message is kept and the
// encoder jumps back to its setjmp.
struct PngWrite {
  std::vector<unsigned char>* out;
  char error[256];
};

[[noreturn]] void pngError(png_structp png, png_const_charp message) {
  auto* write = static_cast<PngWrite*>(png_get_error_ptr(png));
  std::strncpy(write->error, message, sizeof(write->error) - 1);
  png_longjmp(png, 1);
}

void pngAppend(png_structp png, png_bytep data, size_t bytes) {
  auto* write = static_cast<PngWrite*>(png_get_io_ptr(png));
  try {
    write->out->insert(write->out->end(), data, data + bytes);
  } catch (const std::bad_alloc&) {
    png_error(png, "out of memory");
  }
}

std::string encodePng(int width, int height, const unsigned char* rgb, std::vector<unsigned char>& out) {
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (size_t y = 0; y < rows.size(); ++y) rows[y] = const_cast<png_bytep>(rgb + y * size_t(width) * 3);
  PngWrite write{&out, {}};
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &write, pngError, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return "the encoder could not be started";
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return write.error[0] ? write.error : "the encoder failed";
  }
  png_set_write_fn(png, &write, pngAppend, nullptr);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_set_rows(png, info, rows.data());
  png_write_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  png_destroy_write_struct(&png, &info);
  return "";
}

const ImageWriter kWriter{kImageWriterInterface, writeExr, encodePng};

}  // namespace
}  // namespace lucent

extern "C" __attribute__((visibility("default"))) const lucent::ImageWriter* lucentImageWriter() { return &lucent::kWriter; }
