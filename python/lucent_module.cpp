// The `lucent` Python module: scenes, renders with any method and its options to NumPy arrays (the
// GIL released while rendering), compare's metrics and tests on arrays in memory, and dumps as
// NumPy structured arrays. python/README.md documents it; tests/python/test_module.py tests it.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif
#include <chrono>
#include <cstring>
#include <filesystem>
#include <future>
#include <thread>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

#include "lucent/core/dump.h"
#include "lucent/render/dump_records.h"
#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/image/comparison.h"
#include "lucent/image/image.h"
#include "lucent/methods/methods.h"
#include "lucent/pipeline/film.h"
#include "lucent/scene/loader.h"
#include "lucent/render/render_session.h"
#include "lucent/trace/visibility.h"

namespace py = pybind11;
using namespace lucent;

namespace {

// Lucent's threads flush denormals (flushDenormals, for speed); the interpreter's thread that loads
// or renders keeps its own floating-point mode, or NumPy on it would flush them too.
class KeepFloatingPointMode {
 public:
#if defined(__SSE__)
  KeepFloatingPointMode() : mode_(_mm_getcsr()) {}
  ~KeepFloatingPointMode() { _mm_setcsr(mode_); }

 private:
  unsigned mode_;
#endif
};

// A scene and its Embree visibility, built once for any number of renders (render/render_session.h:
// the rules of `lucent render` hold for both). Paths arrive as str, bytes or os.PathLike (pybind11's
// std::filesystem::path: a str goes through os.fsencode, so a file name that is not UTF-8 reaches
// its file).
std::shared_ptr<OpenScene> openScene(const std::filesystem::path& file, std::optional<std::pair<int, int>> resolution,
                                     bool strict, std::optional<std::string> isa, bool robust,
                                     std::optional<std::string> memoryLimit, const std::string& gltfMasking,
                                     const std::string& gltfNormalMaps, double lumensPerWatt,
                                     const std::string& gltfCamera) {
  const KeepFloatingPointMode keep;
  SceneSettings settings;
  settings.load = LoadOptions(true);
  // The glTF choices of `lucent render`'s --gltf-masking, --gltf-normal-maps, --lumens-per-watt and
  // --gltf-camera, with their values and bounds.
  if (gltfMasking != "separable" && gltfMasking != "height-correlated")
    throw std::invalid_argument("gltf_masking: expected separable or height-correlated, not '" + gltfMasking + "'");
  if (gltfNormalMaps != "bend" && gltfNormalMaps != "as-given")
    throw std::invalid_argument("gltf_normal_maps: expected bend or as-given, not '" + gltfNormalMaps + "'");
  if (!(lumensPerWatt >= 1e-6 && lumensPerWatt <= 1e6))
    throw std::invalid_argument("lumens_per_watt: must be in [1e-6, 1e6]");
  settings.load.gltf = {gltfMasking == "height-correlated", gltfNormalMaps == "bend", lumensPerWatt, gltfCamera};
  settings.resolution = resolution;
  settings.strict = strict;
  settings.isa = isa.value_or("");
  settings.robust = robust;
  if (memoryLimit) settings.memoryLimit = parseMemorySize(*memoryLimit);
  auto scene = std::make_shared<OpenScene>(file.string(), settings);
  scene->visibility();
  return scene;
}

// Text for a method option from a Python value: booleans as true/false, the rest as str() gives it.
std::string optionText(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  return py::str(value).cast<std::string>();
}

// Channels [first, first + count) of an image as an (height, width, count) float32 array.
py::array_t<float> channelsArray(const Image& image, int first, int count) {
  py::array_t<float> a({image.height(), image.width(), count});
  auto m = a.mutable_unchecked<3>();
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      for (int c = 0; c < count; ++c) m(y, x, c) = image.at(x, y, first + c);
  return a;
}

// An image's channels grouped by layer: "R", "G", "B" the image, "variance.R" ... the variance,
// "paths.direct.R" ... the layer "paths.direct".
py::dict imageArrays(const Image& image) {
  std::vector<std::pair<std::string, std::pair<int, int>>> groups;  // layer, first channel and count
  for (int c = 0; c < image.channelCount(); ++c) {
    const std::string& name = image.channels()[size_t(c)];
    const size_t dot = name.rfind('.');
    const std::string layer = dot == std::string::npos ? "" : name.substr(0, dot);
    if (!groups.empty() && groups.back().first == layer) ++groups.back().second.second;
    else groups.push_back({layer, {c, 1}});
  }
  py::dict out, layers, layerChannels;
  for (const auto& [layer, range] : groups) {
    py::array_t<float> a = channelsArray(image, range.first, range.second);
    py::list suffixes;  // the channels' own names: R, G, B; X, Y, Z for normals; Z for depth
    for (int c = range.first; c < range.first + range.second; ++c) {
      const std::string& name = image.channels()[size_t(c)];
      suffixes.append(layer.empty() ? name : name.substr(layer.size() + 1));
    }
    if (layer.empty()) out["image"] = a;
    else if (layer == "variance") out["variance"] = a;
    else layers[py::str(layer)] = a, layerChannels[py::str(layer)] = suffixes;
  }
  if (!out.contains("variance")) out["variance"] = py::none();
  out["layers"] = layers;
  out["layer_channels"] = layerChannels;
  return out;
}

// Runs `render` on a thread of its own while this one waits for it, taking Python's signals every
// tenth of a second: Ctrl-C (KeyboardInterrupt, or whatever a handler raises) stops the render within
// a fraction of a second through `stop`, and the exception is raised once the render has returned.
RenderResult renderInterruptibly(const std::function<RenderResult(const std::atomic<bool>& stop)>& render) {
  std::atomic<bool> stop{false};
  std::packaged_task<RenderResult()> task([&] { return render(stop); });
  std::future<RenderResult> done = task.get_future();
  std::thread worker(std::move(task));
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    while (done.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        interrupted = true;
        stop = true;
        break;
      }
    }
    done.wait();
    worker.join();
  }
  if (interrupted) {
    try {
      done.get();  // the render's own exception (RenderStopped) gives way to the signal's
    } catch (...) {
    }
    throw py::error_already_set();
  }
  return done.get();
}

py::dict render(OpenScene& scene, std::optional<std::string> method, std::optional<int> threads,
               std::optional<std::filesystem::path> output, std::optional<std::filesystem::path> png,
               std::optional<std::array<int, 4>> crop, std::optional<std::pair<int, int>> samples,
               std::optional<std::string> part, double checkpoint, bool resume, const py::kwargs& kwargs) {
  RenderRequest request;
  request.method = method.value_or("");
  for (const auto& [key, value] : kwargs) request.options.emplace_back(key.cast<std::string>(), optionText(value));
  request.optionName = [](const std::string& option) { return option + "="; };  // as Python spells it
  if (output) request.output = output->string();
  if (png) request.png = png->string();
  if (crop) request.crop = {(*crop)[0], (*crop)[1], (*crop)[2], (*crop)[3]};
  request.samples = samples.value_or(std::pair<int, int>{0, 0});
  request.part = part.value_or("");
  request.checkpointSeconds = checkpoint;
  request.resume = resume;
  request.threads = threads.value_or(0);
  RenderSession rendering(scene, request);
  // On a thread of its own: the interpreter's floating-point mode is not touched.
  RenderResult result = renderInterruptibly([&](const std::atomic<bool>& stop) {
    RenderHooks hooks;
    hooks.stop = &stop;
    hooks.stoppedBy = [] { return std::string("KeyboardInterrupt"); };
    return rendering.run(hooks);
  });
  const RenderOutput& out = result.render;
  py::dict dict = imageArrays(out.image);
  // The names the layer surface's material indices stand for (with layers).
  if (out.film && out.film->layers().features) dict["materials"] = out.film->materialNames();
  py::dict counters, stages, measured;
  for (const auto& [stage, seconds] : out.stats.stageSeconds) stages[py::str(stage)] = seconds;
  for (const auto& [counter, value] : out.stats.counters) counters[py::str(counter)] = value;
  for (const auto& [key, value] : out.measured) measured[py::str(key)] = value;
  dict["method"] = rendering.method().name();
  dict["spp"] = out.sppDone;
  dict["complete"] = out.complete;
  dict["stages"] = stages;
  dict["counters"] = counters;
  dict["measured"] = measured;
  dict["summary"] = py::module_::import("json").attr("loads")(result.summary);
  return dict;
}

// An (height, width, 3) array, or a dict of one with its variance and layers (render's, read_image's),
// as an Image with compare's channel names.
Image imageFrom(const py::handle& value, const std::string& what) {
  py::object array = py::reinterpret_borrow<py::object>(value), variance = py::none();
  py::dict layers, layerChannels;
  if (py::isinstance<py::dict>(value)) {
    const py::dict d = value.cast<py::dict>();
    array = d["image"];
    if (d.contains("variance")) variance = d["variance"];
    if (d.contains("layers")) layers = d["layers"].cast<py::dict>();
    if (d.contains("layer_channels")) layerChannels = d["layer_channels"].cast<py::dict>();
  }
  std::vector<std::pair<std::string, py::array_t<float, py::array::c_style | py::array::forcecast>>> parts;
  parts.push_back({"", py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array)});
  if (!variance.is_none()) parts.push_back({"variance", py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(variance)});
  for (const auto& [key, layer] : layers)
    parts.push_back({key.cast<std::string>(), py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(layer)});
  // In the order an EXR file's channels are read (R, G, B, then the layers by name), so that the
  // metrics sum in the order `lucent compare` does and give its numbers to the last bit.
  std::sort(parts.begin() + 1, parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const auto& first = parts.front().second;
  if (!first || first.ndim() != 3 || first.shape(2) != 3)
    throw std::invalid_argument(what + ": needs an array of shape (height, width, 3)");
  const int height = int(first.shape(0)), width = int(first.shape(1));
  std::vector<std::string> channels;
  std::vector<size_t> firstChannel;
  for (const auto& [layer, a] : parts) {
    // A layer's channels by the names layer_channels gives (render's and read_image's), else R, G, B.
    std::vector<std::string> suffixes = {"R", "G", "B"};
    if (!layer.empty() && layerChannels.contains(layer)) suffixes = layerChannels[py::str(layer)].cast<std::vector<std::string>>();
    const std::string shape = "(" + std::to_string(height) + ", " + std::to_string(width) + ", " + std::to_string(suffixes.size()) + ")";
    if (!a || a.ndim() != 3 || a.shape(0) != height || a.shape(1) != width || a.shape(2) != py::ssize_t(suffixes.size()))
      throw std::invalid_argument(what + ": layer '" + (layer.empty() ? "image" : layer) + "' is not of shape " + shape);
    firstChannel.push_back(channels.size());
    for (const std::string& c : suffixes) channels.push_back(layer.empty() ? c : layer + "." + c);
  }
  Image image(width, height, channels);
  const size_t stride = channels.size();
  for (size_t p = 0; p < parts.size(); ++p) {
    const float* data = parts[p].second.data();
    const size_t count = size_t(parts[p].second.shape(2));
    for (size_t i = 0; i < size_t(width) * size_t(height); ++i)
      for (size_t c = 0; c < count; ++c) image.pixels()[i * stride + firstChannel[p] + c] = data[count * i + c];
  }
  return image;
}

py::object compare(const py::handle& image, const py::handle& reference, const std::string& metric,
                   std::optional<double> maxError, bool test, int block, std::optional<double> within, double alpha,
                   const std::string& layer, const std::string& imageLayer, double ppd,
                   std::optional<double> startExposure, std::optional<double> stopExposure, bool imageSrgb,
                   bool referenceSrgb, bool ldr) {
  ComparisonSettings settings;
  settings.ldr = ldr;
  settings.metric = metric, settings.maxError = maxError, settings.test = test, settings.block = block;
  settings.within = within, settings.alpha = alpha, settings.layer = layer, settings.imageLayer = imageLayer;
  settings.pixelsPerDegree = ppd, settings.startExposure = startExposure, settings.stopExposure = stopExposure;
  // How the values were stored: a dict's "encoding", "largest_code" and "srgb" (read_image's, from
  // the file), else half floats for NumPy's float16 (rounded as an EXR's half channels are) and
  // floats otherwise.
  const auto roundingOf = [](const py::handle& value) {
    if (py::isinstance<py::dict>(value)) {
      const py::dict d = value.cast<py::dict>();
      if (d.contains("encoding")) {
        const std::string name = d["encoding"].cast<std::string>();
        const std::optional<ColourEncoding> encoding = colourEncodingNamed(name);
        if (!encoding) throw std::invalid_argument("unknown encoding '" + name + "' (read_image gives one)");
        ImageHeader header;
        header.colourEncoding = *encoding;
        if (*encoding == ColourEncoding::Integer) {
          header.largestCode = d.contains("largest_code") ? d["largest_code"].cast<double>() : 0.0;
          if (!(header.largestCode >= 1 && header.largestCode < 0x1p32))
            throw std::invalid_argument("an integer encoding needs its largest_code, from 1 to 2^32 - 1 (read_image gives it)");
        }
        return storedRoundingOf(header, d.contains("srgb") && d["srgb"].cast<bool>());
      }
    }
    const py::object a = py::isinstance<py::dict>(value) ? py::object(value.cast<py::dict>()["image"])
                                                         : py::reinterpret_borrow<py::object>(value);
    const py::array array = py::array::ensure(a);
    const bool half = array && array.dtype().kind() == 'f' && array.dtype().itemsize() == 2;
    return StoredRounding{half ? ColourEncoding::Half : ColourEncoding::Float, false};
  };
  // A list or tuple of arrays: independent runs of one renderer.
  std::vector<Image> runs;
  std::vector<StoredRounding> rounding;
  if (py::isinstance<py::list>(image) || py::isinstance<py::tuple>(image)) {
    for (const py::handle run : image) {
      runs.push_back(imageFrom(run, "run " + std::to_string(runs.size() + 1)));
      rounding.push_back(roundingOf(run));
    }
    if (runs.size() < 2) throw std::invalid_argument("runs: give two or more arrays, or one array");
  } else {
    runs.push_back(imageFrom(image, "image"));
    rounding = {roundingOf(image)};
  }
  Image b = imageFrom(reference, "reference");
  const StoredRounding referenceRounding = roundingOf(reference);
  // A reference dict's material names (render's and read_image's "materials") name the breakdown by surface.
  if (py::isinstance<py::dict>(reference) && reference.cast<py::dict>().contains("materials"))
    settings.materialNames = reference.cast<py::dict>()["materials"].cast<std::vector<std::string>>();
  ImageComparison result;
  {
    py::gil_scoped_release release;
    const KeepFloatingPointMode keep;
    flushDenormals();  // as lucent compare computes: a denormal variance reads as none there
    Candidate candidate = runs.size() == 1 ? Candidate(std::move(runs[0])) : Candidate(std::move(runs));
    candidate.rounding = std::move(rounding), candidate.referenceRounding = referenceRounding;
    result = compareImagePair(std::move(candidate), std::move(b), settings, imageSrgb, referenceSrgb);
  }
  return py::module_::import("json").attr("loads")(result.json);
}

// The NumPy dtype of a dump record type, from the record table (lucent/render/dump_records.h, whose
// offsets a test checks against the C++ structs).
py::dtype recordDtype(const std::string& type) {
  const auto found = dumpRecordTypes().find(type);
  if (found == dumpRecordTypes().end()) throw std::invalid_argument("no dump record type '" + type + "'");
  const DumpRecordType& record = found->second;
  if (record.fields.size() == 1 && record.fields[0].count == 1 && std::string(record.fields[0].name) == "value")
    return py::dtype(record.fields[0].kind == DumpFieldKind::F32 ? "<f4" : record.fields[0].kind == DumpFieldKind::U64 ? "<u8" : "<u4");
  py::list names, formats, offsets;
  const std::vector<uint32_t> fieldOffsets = dumpFieldOffsets(record);
  for (size_t i = 0; i < record.fields.size(); ++i) {
    const DumpField& f = record.fields[i];
    const char* base = "";
    switch (f.kind) {
      case DumpFieldKind::F32: base = "<f4"; break;
      case DumpFieldKind::F16: base = "<f2"; break;
      case DumpFieldKind::U32: base = "<u4"; break;
      case DumpFieldKind::I32: base = "<i4"; break;
      case DumpFieldKind::U16: base = "<u2"; break;
      case DumpFieldKind::U64: base = "<u8"; break;
    }
    names.append(f.name);
    const std::string shape = f.columns > 0 ? "(" + std::to_string(f.count / f.columns) + "," + std::to_string(f.columns) + ")"
                                            : "(" + std::to_string(f.count) + ",)";
    formats.append(f.count > 1 ? py::str(shape + base) : py::str(base));
    offsets.append(fieldOffsets[i]);
  }
  py::dict spec;
  spec["names"] = names, spec["formats"] = formats, spec["offsets"] = offsets, spec["itemsize"] = found->second.bytes;
  return py::dtype::from_args(spec);
}

py::array readDumpArray(const std::filesystem::path& file) {
  const std::string path = file.string();
  const DumpHeader header = readDumpHeader(path);
  const std::string type = recordTypeName(header);
  if (!dumpRecordTypes().count(type)) throw std::runtime_error("'" + path + "': unknown record type '" + type + "'");
  const py::dtype dtype = recordDtype(type);
  if (uint32_t(dtype.itemsize()) != header.recordBytes)
    throw std::runtime_error("'" + path + "': " + type + " records of " + std::to_string(header.recordBytes) +
                             " bytes, not " + std::to_string(dtype.itemsize()));
  py::array out;
  readDumpRecords(path, type, header.recordBytes, [&](uint64_t count) {
    out = py::array(dtype, std::vector<py::ssize_t>{py::ssize_t(count)});
    return out.mutable_data();
  });
  return out;
}

// Writes records as the dump file `file` (DIR/NAME.bin, docs/dump-format.md) of record type `type`:
// a structured array of record_dtype(type)'s dtype, or for uint32, uint64 and float any numeric
// array (converted); without a type, the one whose dtype the array has.
void writeDumpArray(const std::filesystem::path& file, const py::array& records, std::optional<std::string> type) {
  const std::string path = file.string();
  if (file.extension() != ".bin") throw std::invalid_argument("'" + path + "': a dump file's name ends in .bin");
  const py::dtype dtype = records.dtype();
  if (!type) {
    for (const auto& [name, record] : dumpRecordTypes())
      if (recordDtype(name).equal(dtype)) type = name;
    if (!type) {
      const std::string plain = dtype.kind() == 'u' && dtype.itemsize() == 4   ? "uint32"
                                : dtype.kind() == 'u' && dtype.itemsize() == 8 ? "uint64"
                                : dtype.kind() == 'f' && dtype.itemsize() == 4 ? "float"
                                                                               : "";
      if (plain.empty())
        throw std::invalid_argument("'" + path + "': no dump record type has the array's dtype " +
                                    py::repr(dtype).cast<std::string>() + "; give type=");
      type = plain;
    }
  }
  if (!dumpRecordTypes().count(*type)) throw std::invalid_argument("no dump record type '" + *type + "'");
  const py::dtype wanted = recordDtype(*type);
  const bool scalar = !wanted.has_fields();
  if (!scalar && !wanted.equal(dtype))
    throw std::invalid_argument("'" + path + "': the array's dtype is not record_dtype('" + *type + "')");
  // Records in the dtype's layout, C order; a scalar type's values converted to it.
  const py::object typed = scalar ? records.attr("astype")(wanted) : py::object(records);
  const py::array flat = py::array::ensure(typed, py::array::c_style);
  if (!flat) throw std::invalid_argument("'" + path + "': the array cannot be read as records");
  const uint64_t count = uint64_t(flat.size());
  const std::filesystem::path directory = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  writeDump(directory.string(), file.stem().string(), *type, flat.data(), uint32_t(wanted.itemsize()), count);
}

}  // namespace

PYBIND11_MODULE(lucent, m) {
  m.doc() = "Lucent, a CPU reference renderer for global illumination: scenes, renders to NumPy arrays, "
            "lucent compare's metrics and tests on arrays, and stage dumps as structured arrays";
  // Messages quote file names, which need not be UTF-8: their bytes that are not are shown as U+FFFD
  // (pybind11's own translation drops such a message). Registered first, so tried after OptionError's.
  py::register_exception_translator([](std::exception_ptr thrown) {
    const auto raise = [](PyObject* type, const char* what) {
      PyObject* message = PyUnicode_DecodeUTF8(what, Py_ssize_t(std::strlen(what)), "replace");
      PyErr_SetObject(type, message);
      Py_XDECREF(message);
    };
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const std::invalid_argument& e) {
      raise(PyExc_ValueError, e.what());
    } catch (const std::runtime_error& e) {
      raise(PyExc_RuntimeError, e.what());
    }
  });
  py::register_exception<OptionError>(m, "OptionError", PyExc_ValueError);
  py::class_<OpenScene, std::shared_ptr<OpenScene>>(m, "Scene", "A loaded scene with its Embree visibility")
      .def_property_readonly("path", [](const OpenScene& s) { return py::module_::import("os").attr("fsdecode")(py::bytes(s.path())); })
      .def_property_readonly("width", [](const OpenScene& s) { return s.scene().camera.width; })
      .def_property_readonly("height", [](const OpenScene& s) { return s.scene().camera.height; })
      .def_property_readonly("triangles", [](const OpenScene& s) { return s.scene().indices.size() / 3; });
  m.def("load_scene", &openScene, py::arg("path"), py::arg("resolution") = py::none(), py::arg("strict") = false,
        py::arg("isa") = py::none(), py::arg("robust") = false, py::arg("memory_limit") = py::none(),
        py::arg("gltf_masking") = "height-correlated", py::arg("gltf_normal_maps") = "bend",
        py::arg("lumens_per_watt") = GltfOptions{}.lumensPerWatt, py::arg("gltf_camera") = "",
        "Loads a scene file or a glTF file as `lucent render` does: resolution=(width, height) overrides the "
        "camera's; strict refuses a scene whose files hold what a render would leave out; isa names the "
        "instruction set of Embree's kernels and the lane loops (sse4.2, avx, avx2, avx512); robust asks for "
        "Embree's robust traversal; memory_limit ('8G') bounds the memory the renders may take; "
        "gltf_masking, gltf_normal_maps, lumens_per_watt and gltf_camera read glTF files as the options of "
        "those names do.");
  m.def("methods", [] {
    std::vector<std::string> names;
    for (const Method* method : renderingMethods()) names.push_back(method->name());
    return names;
  }, "The rendering methods' names");
  m.def("render", &render, py::arg("scene"), py::arg("method") = py::none(), py::arg("threads") = py::none(),
        py::arg("output") = py::none(), py::arg("png") = py::none(), py::arg("crop") = py::none(),
        py::arg("samples") = py::none(), py::arg("part") = py::none(), py::arg("checkpoint") = 0.0,
        py::arg("resume") = false,
        "Renders the scene with a method (default: the scene's render block's, else pt) and its options as keyword "
        "arguments (spp=64, variance=True, ...: the names of `lucent render --method M --help` with _ for -), as "
        "`lucent render` does: output='OUT.exr' (and png='OUT.png') writes the image with its metadata; crop=(x0, "
        "y0, x1, y1), samples=(first, count) or part='rows:K/N' render a part of a split render, its film kept "
        "beside the output for `lucent merge`; checkpoint=SECONDS and resume=True keep and resume OUT.film. "
        "Returns a dict: image and variance (height x width x 3 float32, variance None unless asked for), layers "
        "(name -> array), method, spp, complete, stages, counters, measured, and summary (the JSON line of "
        "`lucent render`).");
  m.def("compare", &compare, py::arg("image"), py::arg("reference"), py::arg("metric") = "relmse",
        py::arg("max_error") = py::none(), py::arg("test") = false, py::arg("block") = 8, py::arg("within") = py::none(),
        py::arg("alpha") = 0.01, py::arg("layer") = "", py::arg("image_layer") = "", py::arg("ppd") = kFlipPixelsPerDegree,
        py::arg("start_exposure") = py::none(), py::arg("stop_exposure") = py::none(), py::arg("image_srgb") = false,
        py::arg("reference_srgb") = false, py::arg("ldr") = false,
        "lucent compare on arrays in memory: each of image and reference is a (height, width, 3) array or a dict "
        "like render's (image, variance, layers); image may be a list of two or more such runs (renders with other "
        "seeds), whose spread is the noise of test and within. Returns compare's JSON as a dict (without the file "
        "names): its 'verdict' is 'pass', 'fail' or 'inconclusive'.");
  m.def("read_image", [](const std::filesystem::path& file) {
    const std::string path = file.string();
    ImageMetadata metadata;
    const Image image = readLinearImage(path, &metadata);
    py::dict out = imageArrays(image);
    out["srgb"] = isSrgbEncoded(path, metadata);  // pass as compare's image_srgb / reference_srgb
    const ImageHeader header = readImageHeader(path);
    out["encoding"] = colourEncodingName(header.colourEncoding);  // compare allows for its rounding
    if (header.colourEncoding == ColourEncoding::Integer) out["largest_code"] = uint64_t(header.largestCode);
    const std::vector<std::string> materials = materialNamesOf(metadata);
    if (!materials.empty()) out["materials"] = materials;
    out["channels"] = image.channels();
    return out;
  }, py::arg("path"), "An image file (EXR, HDR, PNG, ...) as a dict like render's: image, variance, layers, "
                      "srgb (an 8-bit sRGB file, decoded to linear) and encoding (how its values were stored, whose "
                      "rounding compare allows for: float, half, integer (with largest_code, 255 for 8-bit codes), rgbe "
                      "or lossy)");
  m.def("record_types", [] {
    std::vector<std::string> names;
    for (const auto& [name, type] : dumpRecordTypes()) names.push_back(name);
    return names;
  }, "The names of every dump record type (docs/dump-format.md), each with its record_dtype");
  m.def("record_dtype", &recordDtype, py::arg("type"), "The NumPy dtype of a dump record type (docs/dump-format.md)");
  m.def("read_dump", &readDumpArray, py::arg("path"), "A dump file as a NumPy structured array of its records");
  m.def("write_dump", &writeDumpArray, py::arg("path"), py::arg("records"), py::arg("type") = py::none(),
        "Writes records as a dump file (DIR/NAME.bin) that check-dump compares: a structured array of "
        "record_dtype(type)'s dtype (the type found from the dtype when not given), or a numeric array for "
        "uint32, uint64 and float");
}
