// lucent report REFERENCE CANDIDATE... -o REPORT.html [--runs K] [--label NAME]... [--seconds S]...
//               [--alpha A] [--within D] [--exposure STOPS] [--ppd P] [--layer NAME [--image-layer NAME]]
// Writes one self-contained HTML page (images embedded as PNG data, no outside resources)
// comparing each candidate with the reference: the images side by side and as an A/B flip at
// pixel zoom, the relMSE, FLIP and noise test's |z| heatmaps with colour bars, the numbers of
// `lucent compare --test` (of `lucent compare` on the colours where the reference has no variance
// layers) and of `lucent compare --metric flip`, the bias per region, and relMSE against seconds where the candidates' times are known
// (--seconds, a sidecar CANDIDATE.json's "seconds", or the lucent:render_seconds a Lucent render
// stores; the sidecar's renderer, samples and device are shown too). Prints one JSON line; exits 0
// when the page is written, 1 on bad input (no page is written then).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "cli/commands.h"
#include "cli/comparison_options.h"
#include "render/output_paths.h"
#include "core/json_text.h"
#include "lucent/core/text.h"
#include "lucent/core/files.h"
#include "lucent/image/flip.h"
#include "lucent/image/metrics.h"
#include "lucent/image/noise_tests.h"

namespace lucent::cli {

namespace {

struct ReportOptions {
  std::string reference, output, layer, imageLayer;
  std::vector<std::string> candidates, labels;
  std::vector<double> seconds;
  int runs = 1;  // images per candidate: independent runs of one renderer
  double alpha = 0.01, exposure = 0, pixelsPerDegree = kFlipPixelsPerDegree;
  std::optional<double> within;
  bool ldr = false;
};

std::string escapeHtml(const std::string& text) {
  std::string out;
  for (const char c : text) switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  return out;
}

std::string base64(const std::vector<unsigned char>& bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t n = uint32_t(bytes[i]) << 16 | (i + 1 < bytes.size() ? uint32_t(bytes[i + 1]) << 8 : 0u) |
                       (i + 2 < bytes.size() ? uint32_t(bytes[i + 2]) : 0u);
    out += kDigits[n >> 18 & 63];
    out += kDigits[n >> 12 & 63];
    out += i + 1 < bytes.size() ? kDigits[n >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[n & 63] : '=';
  }
  return out;
}

std::string pngDataUri(const Image& image) { return "data:image/png;base64," + base64(encodePng(image)); }

// Four significant digits, as printf's %.4g (the page's test formats compare's numbers alike).
std::string number(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

std::string metadataValue(const ImageMetadata& metadata, const std::string& key) {
  for (const auto& [k, v] : metadata)
    if (k == key) return v;
  return "";
}

std::optional<double> renderSeconds(const ImageMetadata& metadata) {
  const std::string text = metadataValue(metadata, "lucent:render_seconds");
  if (text.empty()) return std::nullopt;
  try {
    const double seconds = std::stod(text);
    if (std::isfinite(seconds) && seconds > 0) return seconds;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

// What a Lucent render stored about itself, as HTML for the page's captions: the method, spp,
// seed, time and version, and the options folded away.
std::string provenance(const ImageMetadata& metadata) {
  std::string out;
  for (const char* key : {"lucent:method", "lucent:spp", "lucent:seed", "lucent:render_seconds", "lucent:version"}) {
    const std::string value = metadataValue(metadata, key);
    if (value.empty()) continue;
    if (!out.empty()) out += " · ";
    out += escapeHtml(std::string(key).substr(7) + " " + value);
  }
  if (out.empty()) return "no Lucent metadata";
  const std::string options = metadataValue(metadata, "lucent:options");
  if (!options.empty()) out += " <details><summary>options</summary><code>" + escapeHtml(options) + "</code></details>";
  return out;
}

Image exposed(Image image, double stops) {
  const float scale = float(std::exp2(stops));
  for (float& v : image.pixels()) v *= scale;
  return image;
}

// What rendered a candidate, from its sidecar CANDIDATE.json (the image's file name with .json
// appended: run1.exr.json, so that run1.exr and run1.png have their own), which any renderer can write: {"renderer": "...", "samples": N, "seconds": S,
// "device": "..."}, every key optional. Other keys are listed, not read.
struct Sidecar {
  std::string path, renderer, device;
  std::optional<double> samples, seconds;
  std::vector<std::string> ignored;
};

std::optional<Sidecar> readSidecar(const std::string& imagePath) {
  Sidecar sidecar;
  sidecar.path = imagePath + ".json";
  std::error_code ec;
  if (!std::filesystem::exists(sidecar.path, ec)) return std::nullopt;
  const auto bad = [&](const std::string& why) { return std::invalid_argument("sidecar '" + sidecar.path + "': " + why); };
  if (const std::string problem = admitInputFile(sidecar.path); !problem.empty()) throw bad(problem);
  std::ifstream in(sidecar.path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in && !in.eof()) throw bad("cannot be read");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw bad(std::string("not JSON (") + e.what() + ")");
  }
  if (!json.is_object()) throw bad("not a JSON object");
  for (const auto& [key, value] : json.items()) {
    if (key == "renderer" || key == "device") {
      if (!value.is_string()) throw bad("'" + key + "' must be text");
      (key == "renderer" ? sidecar.renderer : sidecar.device) = value.get<std::string>();
    } else if (key == "samples" || key == "seconds") {
      if (!value.is_number() || !(value.get<double>() > 0) || !std::isfinite(value.get<double>()))
        throw bad("'" + key + "' must be a positive number");
      (key == "samples" ? sidecar.samples : sidecar.seconds) = value.get<double>();
    } else {
      sidecar.ignored.push_back(key);
    }
  }
  return sidecar;
}

struct ReportEntry {
  std::string path, label;  // path: its first run's
  std::vector<std::string> runs;
  std::optional<Sidecar> sidecar;
  std::optional<double> seconds;
  ImageMetadata metadata;
  ImageError error;
  std::optional<NoiseTest> test;
  std::optional<EquivalenceTest> equivalence;
  std::vector<SurfaceDifference> surfaces;  // where the reference has surface layers
  FlipResult flip;
  double errorScale = 0;
  std::string imageUri, errorUri, statisticUri, flipUri;
};

// The CSS class of a verdict: passed, failed, inconclusive.
const char* verdictClass(Verdict verdict) {
  return verdict == Verdict::Pass ? "passed" : verdict == Verdict::Fail ? "failed" : "inconclusive";
}

std::string verdictCell(const std::string& key, Verdict verdict) {
  return "<td data-key=\"" + key + "\" class=\"" + verdictClass(verdict) + "\">" +
         (verdict == Verdict::Pass ? "passed" : verdict == Verdict::Fail ? "failed" : "inconclusive") + "</td>";
}

bool hasVarianceLayers(const Image& image) {
  for (const char* c : {"variance.R", "variance.G", "variance.B"})
    if (image.channelIndex(c) < 0) return false;
  return true;
}

// An <img> the page's self-check expects to decode to width x height.
std::string imageTag(const std::string& uri, int width, int height, const std::string& alt,
                     const std::string& attributes = "") {
  return "<img src=\"" + uri + "\" alt=\"" + escapeHtml(alt) + "\" data-width=\"" + std::to_string(width) +
         "\" data-height=\"" + std::to_string(height) + "\"" + attributes + ">";
}

std::string cell(const std::string& key, const std::string& text) {
  return "<td data-key=\"" + key + "\">" + escapeHtml(text) + "</td>";
}

// relMSE against seconds on log-log axes, one labelled point per timed candidate.
std::string speedAccuracyChart(const std::vector<ReportEntry>& candidates) {
  struct Point {
    double seconds, relmse;
    std::string label;
  };
  std::vector<Point> points;
  for (const ReportEntry& c : candidates)
    if (c.seconds && c.error.overall.relmse > 0 && std::isfinite(c.error.overall.relmse))
      points.push_back({*c.seconds, c.error.overall.relmse, c.label});
  if (points.empty()) return "";
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const Point& p : points) {
    x0 = std::min(x0, std::log10(p.seconds)), x1 = std::max(x1, std::log10(p.seconds));
    y0 = std::min(y0, std::log10(p.relmse)), y1 = std::max(y1, std::log10(p.relmse));
  }
  x0 = std::floor(x0), y0 = std::floor(y0);
  x1 = std::max(std::ceil(x1), x0 + 1), y1 = std::max(std::ceil(y1), y0 + 1);
  const double width = 640, height = 380, left = 70, right = 160, top = 20, bottom = 50;
  auto sx = [&](double s) { return left + (std::log10(s) - x0) / (x1 - x0) * (width - left - right); };
  auto sy = [&](double e) { return top + (y1 - std::log10(e)) / (y1 - y0) * (height - top - bottom); };
  std::ostringstream svg;
  svg << "<svg id=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" role=\"img\" aria-label=\"relMSE against seconds\">";
  svg << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << width - left - right << "\" height=\""
      << height - top - bottom << "\" fill=\"none\" stroke=\"#888\"/>";
  for (double k = x0; k <= x1; ++k) {
    const double x = sx(std::pow(10.0, k));
    svg << "<line x1=\"" << x << "\" x2=\"" << x << "\" y1=\"" << top << "\" y2=\"" << height - bottom
        << "\" stroke=\"#ddd\"/><text x=\"" << x << "\" y=\"" << height - bottom + 18
        << "\" text-anchor=\"middle\">" << number(std::pow(10.0, k)) << "</text>";
  }
  for (double k = y0; k <= y1; ++k) {
    const double y = sy(std::pow(10.0, k));
    svg << "<line x1=\"" << left << "\" x2=\"" << width - right << "\" y1=\"" << y << "\" y2=\"" << y
        << "\" stroke=\"#ddd\"/><text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">"
        << number(std::pow(10.0, k)) << "</text>";
  }
  svg << "<text x=\"" << (left + width - right) / 2 << "\" y=\"" << height - 8
      << "\" text-anchor=\"middle\">seconds</text><text transform=\"translate(16," << (top + height - bottom) / 2
      << ") rotate(-90)\" text-anchor=\"middle\">relMSE</text>";
  for (size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    svg << "<g class=\"point\" data-label=\"" << escapeHtml(p.label) << "\"><circle cx=\"" << sx(p.seconds)
        << "\" cy=\"" << sy(p.relmse) << "\" r=\"5\" fill=\"hsl(" << (i * 137) % 360
        << ",65%,45%)\"/><text x=\"" << sx(p.seconds) + 8 << "\" y=\"" << sy(p.relmse) + 4 << "\">"
        << escapeHtml(p.label) << "</text></g>";
  }
  svg << "</svg>";
  return svg.str();
}

// What the FLIP map shows: which FLIP, its observer and exposures, and its pooled numbers.
std::string flipCaption(const FlipResult& f, double pixelsPerDegree) {
  std::string text = std::string(f.hdr ? "HDR" : "LDR") + "-FLIP at " + number(pixelsPerDegree) + " pixels per degree";
  if (f.hdr)
    text += ", " + std::to_string(f.exposures) + " exposures from " + number(f.startExposure) + " to " +
            number(f.stopExposure) + " stops";
  return escapeHtml(text) + ": mean <span data-key=\"flip-mean\">" + number(f.mean) +
         "</span>, weighted median <span data-key=\"flip-weighted_median\">" + number(f.weightedMedian) +
         "</span>, weighted quartiles <span data-key=\"flip-first_quartile\">" + number(f.weightedQuartile1) +
         "</span> and <span data-key=\"flip-third_quartile\">" + number(f.weightedQuartile3) + "</span>.";
}

std::string colourBar(const std::string& uri, const std::string& top, const std::string& what) {
  return "<div class=\"colour-bar\">" + imageTag(uri, 256, 12, "colour bar") + "<div><span>0</span><span>" +
         escapeHtml(what) + "</span><span>" + escapeHtml(top) + "</span></div></div>";
}

const char* kStyle = R"(
body { font: 14px/1.4 system-ui, sans-serif; margin: 24px; color: #222; background: #fafafa; }
h1 { font-size: 22px; } h2 { font-size: 18px; margin-top: 32px; border-top: 1px solid #ccc; padding-top: 16px; }
table { border-collapse: collapse; margin: 8px 0; } td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
th { background: #eee; } td:first-child { text-align: left; }
.passed { color: #176b1b; font-weight: bold; } .failed { color: #b3261e; font-weight: bold; }
.inconclusive { color: #8a5a00; font-weight: bold; }
.images { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
figure { margin: 0; } figcaption { font-size: 12px; color: #555; max-width: 512px; }
.pixelated { image-rendering: pixelated; width: calc(var(--zoom) * var(--w)); max-width: 100%; }
figure { max-width: calc(50% - 16px); }
.viewer { position: relative; overflow: auto; max-width: 100%; max-height: 640px; border: 1px solid #aaa;
          display: inline-block; cursor: crosshair; background: #000; }
.viewer img { display: block; image-rendering: pixelated; }
.viewer img.b { position: absolute; left: 0; top: 0; visibility: hidden; }
.viewer.showing-reference img.b { visibility: visible; }
.viewer.showing-reference img.a { visibility: hidden; }
.controls button { margin-right: 4px; } .controls .state { font-weight: bold; margin-left: 8px; }
.colour-bar img { width: 256px; height: 12px; display: block; }
.colour-bar div { display: flex; justify-content: space-between; width: 256px; font-size: 12px; }
table.regions td { text-align: center; min-width: 84px; } table.regions td.rejected { background: #f6c9c5; }
.note { color: #555; } details { display: inline; } details code { display: block; word-break: break-all; }
)";

// Flip and zoom; the self-check records on <body> whether every image decoded to its size and
// whether flipping shows the other image (a headless browser's test reads them).
const char* kScript = R"(
const referenceUri = document.getElementById('reference-image').src;
for (const img of document.querySelectorAll('img[data-reference]')) img.src = referenceUri;
function setZoom(viewer, zoom) {
  viewer.dataset.zoom = zoom;
  for (const img of viewer.querySelectorAll('img')) img.style.width = (img.dataset.width * zoom) + 'px';
  viewer.parentElement.querySelector('.zoom').textContent = zoom + 'x';
}
function flip(viewer) {
  viewer.classList.toggle('showing-reference');
  viewer.parentElement.querySelector('.state').textContent =
      viewer.classList.contains('showing-reference') ? 'reference' : viewer.dataset.label;
}
let current = null;
for (const viewer of document.querySelectorAll('.viewer')) {
  const box = viewer.parentElement;
  setZoom(viewer, +viewer.dataset.zoom);
  viewer.addEventListener('click', () => flip(viewer));
  viewer.addEventListener('mouseenter', () => { current = viewer; });
  viewer.addEventListener('mousemove', (e) => {
    const img = viewer.querySelector('img.a'), r = img.getBoundingClientRect(), zoom = +viewer.dataset.zoom;
    const x = Math.floor((e.clientX - r.left) / zoom), y = Math.floor((e.clientY - r.top) / zoom);
    box.querySelector('.pixel').textContent = 'pixel ' + x + ', ' + y;
  });
  for (const button of box.querySelectorAll('button[data-zoom]'))
    button.addEventListener('click', () => setZoom(viewer, +button.dataset.zoom));
  box.querySelector('button.flip').addEventListener('click', () => flip(viewer));
  let timer = null;
  box.querySelector('input.auto').addEventListener('change', (e) => {
    clearInterval(timer);
    if (e.target.checked) timer = setInterval(() => flip(viewer), 600);
  });
}
document.addEventListener('keydown', (e) => {
  if (current && (e.key === 'f' || e.key === ' ')) { e.preventDefault(); flip(current); }
});
async function selfCheck() {
  const images = [...document.images];
  const results = await Promise.allSettled(images.map((img) => img.decode()));
  const failed = [];
  results.forEach((r, k) => {
    const img = images[k];
    if (r.status !== 'fulfilled' || img.naturalWidth !== +img.dataset.width || img.naturalHeight !== +img.dataset.height)
      failed.push(img.alt);
  });
  let flips = 0;
  for (const viewer of document.querySelectorAll('.viewer')) {
    const a = viewer.querySelector('img.a');
    const before = getComputedStyle(a).visibility;
    flip(viewer);
    const after = getComputedStyle(a).visibility;
    flip(viewer);
    if (before === 'visible' && after === 'hidden' && getComputedStyle(a).visibility === 'visible') ++flips;
  }
  Object.assign(document.body.dataset, {imagesExpected: images.length, imagesDecoded: images.length - failed.length,
                                        imagesFailed: failed.join('; '), viewersFlipped: flips, checked: 'yes'});
}
selfCheck();
)";

// A candidate's section: where it came from, the flip viewer, the images and heatmaps side by side,
// the regions of the noise test and the difference by surface.
void candidateSection(std::ostringstream& html, const ReportOptions& opt, const ReportEntry& c, size_t i, int w, int h,
                      int zoom, const std::string& bar) {
  html << "<section id=\"candidate-" << i << "\"><h2>" << escapeHtml(c.label) << "</h2>\n<p class=\"note\"><code>"
       << escapeHtml(c.path) << "</code>"
       << (c.runs.size() > 1 ? " and " + std::to_string(c.runs.size() - 1) + " more runs (their mean is shown)" : "")
       << ": " << provenance(c.metadata);
  if (c.sidecar) {
    html << " · <span data-key=\"sidecar\">" << escapeHtml(c.sidecar->path) << ":";
    if (!c.sidecar->renderer.empty()) html << " renderer " << escapeHtml(c.sidecar->renderer);
    if (c.sidecar->samples) html << " · samples " << number(*c.sidecar->samples);
    if (c.sidecar->seconds) html << " · seconds " << number(*c.sidecar->seconds);
    if (!c.sidecar->device.empty()) html << " · device " << escapeHtml(c.sidecar->device);
    html << "</span>";
  }
  html << "</p>\n";
  html << "<div class=\"flip-box\"><div class=\"controls\">Zoom <button data-zoom=\"1\">1x</button><button "
          "data-zoom=\"2\">2x</button><button data-zoom=\"4\">4x</button><button data-zoom=\"8\">8x</button>"
          "<button data-zoom=\"16\">16x</button> <span class=\"zoom\">1x</span> · <button class=\"flip\">Flip "
          "(click, f or space)</button><label><input type=\"checkbox\" class=\"auto\"> flip every 0.6 s</label>"
          "<span class=\"state\">"
       << escapeHtml(c.label) << "</span> <span class=\"pixel\"></span></div>\n<div class=\"viewer\" data-zoom=\""
       << zoom << "\" data-label=\"" << escapeHtml(c.label) << "\">" << imageTag(c.imageUri, w, h, c.label, " class=\"a\"")
       << imageTag("", w, h, "reference (flip of " + c.label + ")", " class=\"b\" data-reference") << "</div></div>\n";
  html << "<div class=\"images\"><figure>" << imageTag(c.imageUri, w, h, c.label + " (side by side)", " class=\"pixelated\"")
       << "<figcaption>" << escapeHtml(c.label) << "</figcaption></figure><figure>"
       << imageTag("", w, h, "reference (side by side with " + c.label + ")", " class=\"pixelated\" data-reference")
       << "<figcaption>reference</figcaption></figure><figure>"
       << imageTag(c.errorUri, w, h, "relMSE heatmap of " + c.label, " class=\"pixelated\"")
       << colourBar(bar, number(c.errorScale), "per-pixel relMSE")
       << "<figcaption>Per-pixel relMSE, (c − r)² / (r + 0.01)², over R, G, B; magenta: NaN or infinite."
          "</figcaption></figure><figure>"
       << imageTag(c.flipUri, w, h, "FLIP map of " + c.label, " class=\"pixelated\"") << colourBar(bar, "1", "FLIP")
       << "<figcaption>" << flipCaption(c.flip, opt.pixelsPerDegree) << "</figcaption></figure>";
  if (c.test)
    html << "<figure>" << imageTag(c.statisticUri, w, h, "test statistic heatmap of " + c.label, " class=\"pixelated\"")
         << colourBar(bar, "5", "block |z|")
         << "<figcaption>|z| of the noise test per block of pixels (largest over R, G, B); magenta: infinite.</figcaption>"
            "</figure>";
  html << "</div>\n";
  if (c.test) {
    const NoiseTest& t = *c.test;
    html << "<p>Relative difference Σ(c − r) / Σr (bias) and z per region; rejected regions in red"
         << (c.equivalence ? "; with --within, the (1 − 2α) interval of its deciding channel (R, G or B), red where it "
                             "leaves ±" + number(*opt.within)
                           : "")
         << ". Blocks of "
         << t.block << " x " << t.block << " pixels rejected: " << t.blocksRejected << " of " << t.blocks
         << "; least block p-value " << number(t.minBlockPValue) << ".</p>\n";
    const std::string undecided = !t.noise.undecided.empty() ? t.noise.undecided
                                  : c.equivalence          ? c.equivalence->noise.undecided
                                                           : "";
    if (!undecided.empty())
      html << "<p class=\"inconclusive\" data-key=\"undecided\">Inconclusive: " << escapeHtml(undecided) << ".</p>\n";
    html << "<table class=\"regions\">";
    const int grid = int(std::lround(std::sqrt(double(t.regions.size() - 1))));
    for (int row = 0; row < grid; ++row) {
      html << "<tr>";
      for (int col = 0; col < grid; ++col) {
        const size_t k = size_t(1 + row * grid + col);
        const RegionTest& r = t.regions[k];
        html << "<td" << (r.rejected ? " class=\"rejected\"" : "") << " data-key=\"region-" << k << "\">"
             << "<span data-key=\"region-" << k << "-relative_difference\">" << number(r.relativeDifference)
             << "</span><br>z <span data-key=\"region-" << k << "-z\">" << number(r.z) << "</span>";
        if (c.equivalence) {
          const EquivalenceRegion& e = c.equivalence->regions[k];
          html << "<br><span class=\"" << verdictClass(e.verdict) << "\">" << "RGB"[e.channel] << " [<span data-key=\"region-" << k
               << "-interval_low\">" << number(e.low) << "</span>, <span data-key=\"region-" << k
               << "-interval_high\">" << number(e.high) << "</span>]</span>";
        }
        html << "</td>";
      }
      html << "</tr>";
    }
    html << "</table>\n";
  }
  if (!c.surfaces.empty()) {
    html << "<p>By surface (what each pixel's centre shows in the reference): relative difference Σ(c − r) / Σr "
            "with its (1 − 2α) interval.</p>\n<table class=\"surfaces\" data-key=\"by_surface\"><tr><th>surface</th>"
            "<th>pixels</th><th>difference</th><th>interval</th></tr>";
    for (const SurfaceDifference& d : c.surfaces) {
      const bool known = std::isfinite(d.low) && std::isfinite(d.high);
      html << "<tr><td>" << escapeHtml(d.name) << "</td><td>" << d.pixels << "</td><td>" << number(d.relativeDifference)
           << "</td><td>" << (known ? number(d.low) + " to " + number(d.high) : std::string("unknown")) << "</td></tr>";
    }
    html << "</table>\n";
  }
  html << "</section>\n";
}

std::string reportPage(const ReportOptions& opt, const Image& reference, const ImageMetadata& referenceMetadata,
                       const std::vector<ReportEntry>& candidates, bool tested) {
  const int w = reference.width(), h = reference.height();
  // Small images are shown enlarged by a whole factor, so that their pixels stay square.
  const int zoom = std::max(1, 384 / std::max(w, h));
  const std::string bar = pngDataUri(heatmapColourBar(256, 12));
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Lucent report: "
       << escapeHtml(opt.reference) << "</title><style>" << kStyle << "</style></head><body style=\"--zoom: "
       << zoom << "; --w: " << w << "px\">\n";
  html << "<h1>Lucent comparison report</h1>\n<p>Reference <code>" << escapeHtml(opt.reference) << "</code>, " << w
       << " × " << h << ": " << provenance(referenceMetadata) << "</p>\n<p>Images shown at exposure "
       << number(opt.exposure) << " stops, sRGB, " << zoom << "x.</p>\n";
  if (tested)
    html << "<p>Noise test (<code>lucent compare --test</code>): per pixel and channel Welch's z = (c − r) / "
            "√(var<sub>c</sub> + var<sub>r</sub>), and the same for the whole image and a 4 × 4 grid of regions; "
            "an image passes when no block of pixels and no region is rejected at α = "
         << number(opt.alpha) << " with a Bonferroni correction.</p>\n";
  else
    html << "<p class=\"note\" id=\"untested\">The reference has no variance layers (render it with "
            "<code>--method pt --variance</code>): the noise test was not run; the numbers are "
            "<code>lucent compare</code>'s on the colours.</p>\n";

  html << "<h2>Summary</h2>\n<table id=\"summary\"><tr><th>Candidate</th><th>Seconds</th><th>relMSE</th><th>RMSE</th>"
          "<th>MAE</th><th>SMAPE</th><th>FLIP</th><th>Non-finite</th>";
  if (tested)
    html << "<th>Within noise</th><th>Blocks rejected</th><th>Fraction at α</th><th>Bias (whole image)</th>"
            "<th>z (whole image)</th>";
  if (tested && opt.within)
    html << "<th>Within ±" << number(*opt.within) << "</th><th>Interval (whole image)</th>";
  html << "</tr>\n";
  for (size_t i = 0; i < candidates.size(); ++i) {
    const ReportEntry& c = candidates[i];
    html << "<tr data-candidate=\"" << i << "\"><td><a href=\"#candidate-" << i << "\">" << escapeHtml(c.label)
         << "</a></td>" << cell("seconds", c.seconds ? number(*c.seconds) : "–") << cell("relmse", number(c.error.overall.relmse))
         << cell("rmse", number(c.error.overall.rmse)) << cell("mae", number(c.error.overall.mae))
         << cell("smape", number(c.error.overall.smape)) << cell("flip", number(c.flip.mean)) << cell("non_finite", std::to_string(c.error.nonFinite));
    if (c.test) {
      const NoiseTest& t = *c.test;
      html << verdictCell("passed", t.verdict)
           << cell("blocks_rejected", std::to_string(t.blocksRejected))
           << cell("fraction_rejected_at_alpha", number(double(t.blocksRejectedAtAlpha) / double(t.blocks)))
           << cell("relative_difference", number(t.regions[0].relativeDifference))
           << cell("z", number(t.regions[0].z));
    }
    if (c.equivalence) {
      const EquivalenceTest& e = *c.equivalence;
      html << verdictCell("equivalent", e.verdict) << "<td>" << "RGB"[e.regions[0].channel] << " "
           << "<span data-key=\"interval_low\">" << number(e.regions[0].low) << "</span> to <span data-key=\"interval_high\">"
           << number(e.regions[0].high) << "</span></td>";
    }
    html << "</tr>\n";
  }
  html << "</table>\n";
  const std::string chart = speedAccuracyChart(candidates);
  if (!chart.empty())
    html << "<h2>Speed and accuracy</h2>\n<p class=\"note\">relMSE against the reference and seconds to render "
            "(given with --seconds or stored by the render).</p>\n"
         << chart << "\n";

  html << "<h2>Reference</h2>\n<figure>"
       << imageTag(pngDataUri(exposed(rgbChannels(reference), opt.exposure)), w, h, "reference",
                   " id=\"reference-image\" class=\"pixelated\"")
       << "<figcaption>" << escapeHtml(opt.reference) << "</figcaption></figure>\n";

  for (size_t i = 0; i < candidates.size(); ++i) candidateSection(html, opt, candidates[i], i, w, h, zoom, bar);
  html << "<script>" << kScript << "</script>\n</body></html>\n";
  return html.str();
}

// The options' ranges and counts (checked here: CLI11's range checks print their bounds with 309
// digits and let NaN through).
void checkReportOptions(const ReportOptions& opt) {
  if (!(opt.alpha >= 1e-12 && opt.alpha <= 0.25)) throw std::invalid_argument("--alpha must lie in [1e-12, 0.25]");
  if (opt.within && !(std::isfinite(*opt.within) && *opt.within > 0 && *opt.within <= 10))
    throw std::invalid_argument("--within must lie in (0, 10]");
  if (!(opt.exposure >= -30 && opt.exposure <= 30)) throw std::invalid_argument("--exposure must lie in [-30, 30]");
  checkPixelsPerDegree(opt.pixelsPerDegree);
  for (const double s : opt.seconds)
    if (!(std::isfinite(s) && s > 0)) throw std::invalid_argument("--seconds must be positive and finite");
  if (opt.runs < 1 || opt.candidates.size() % size_t(opt.runs) != 0)
    throw std::invalid_argument("--runs " + std::to_string(opt.runs) + ": " + std::to_string(opt.candidates.size()) +
                                " images are not whole candidates of that many runs each");
  const size_t count = opt.candidates.size() / size_t(opt.runs);
  if (!opt.labels.empty() && opt.labels.size() != count)
    throw std::invalid_argument("--label is given " + std::to_string(opt.labels.size()) + " times for " +
                                std::to_string(count) + " candidates");
  if (!opt.seconds.empty() && opt.seconds.size() != count)
    throw std::invalid_argument("--seconds is given " + std::to_string(opt.seconds.size()) + " times for " +
                                std::to_string(count) + " candidates");
}

// The JSON line: the report, the reference and each candidate's numbers and verdicts.
std::string reportLine(const ReportOptions& opt, const std::vector<ReportEntry>& candidates, bool tested) {
  nlohmann::ordered_json line;
  line["report"] = opt.output;
  line["reference"] = opt.reference;
  line["tested"] = tested;
  line["candidates"] = nlohmann::ordered_json::array();
  for (const ReportEntry& c : candidates) {
    nlohmann::ordered_json entry = {{"label", c.label}, {"image", c.path}};
    if (c.runs.size() > 1) entry["runs"] = c.runs;
    entry["relmse"] = c.error.overall.relmse, entry["flip"] = c.flip.mean;
    if (c.seconds) entry["seconds"] = *c.seconds;
    if (c.sidecar) {
      nlohmann::ordered_json sidecar = {{"path", c.sidecar->path}};
      if (!c.sidecar->renderer.empty()) sidecar["renderer"] = c.sidecar->renderer;
      if (c.sidecar->samples) sidecar["samples"] = *c.sidecar->samples;
      if (c.sidecar->seconds) sidecar["seconds"] = *c.sidecar->seconds;
      if (!c.sidecar->device.empty()) sidecar["device"] = c.sidecar->device;
      if (!c.sidecar->ignored.empty()) sidecar["not_read"] = c.sidecar->ignored;
      entry["sidecar"] = sidecar;
    }
    if (c.test) entry["passed"] = c.test->verdict == Verdict::Pass, entry["test"] = verdictName(c.test->verdict);
    if (c.equivalence)
      entry["equivalent"] = c.equivalence->verdict == Verdict::Pass, entry["within"] = verdictName(c.equivalence->verdict);
    if (!c.surfaces.empty()) entry["by_surface"] = nlohmann::ordered_json::parse(surfaceDifferencesJson(c.surfaces));
    line["candidates"].push_back(entry);
  }
  return jsonText(line);
}

int runReport(const ReportOptions& opt) {
  checkReportOptions(opt);
  const size_t count = opt.candidates.size() / size_t(opt.runs), runs = size_t(opt.runs);
  std::vector<std::string> inputs = opt.candidates;
  inputs.push_back(opt.reference);
  checkOutputFile(opt.output, ".html", "-o", inputs);
  // Sizes and channels from the headers first: a mismatch is reported before any pixel is decoded.
  const ImageHeader referenceHeader = readImageHeader(opt.reference);
  std::vector<bool> halfVariance;
  std::vector<ImageHeader> headers;
  for (const std::string& path : opt.candidates) {
    const ImageHeader& header = headers.emplace_back(readImageHeader(path));
    halfVariance.push_back(header.hasHalfVariance());
    try {
      checkComparable(header, referenceHeader, true);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + path + "' vs '" + opt.reference + "': " + e.what());
    }
  }
  ImageMetadata referenceMetadata;
  const Image referenceWhole = readLinearImage(opt.reference, &referenceMetadata);
  // With --layer, every image is its layer's R, G, B and variance (chooseLayer, as compare --layer).
  auto chosen = [&](const Image& candidate, const std::string& path) {
    try {
      return chooseLayer(candidate, referenceWhole, opt.layer, opt.imageLayer);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + path + "' vs '" + opt.reference + "': " + e.what());
    }
  };
  Image referenceFile = referenceWhole;
  if (!opt.layer.empty()) {
    try {
      referenceFile = chooseLayer(referenceWhole, referenceWhole, opt.layer).reference;
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + opt.reference + "': " + e.what());
    }
  }
  const bool referenceIsSrgb = isSrgbEncoded(opt.reference, referenceMetadata);
  const bool tested = hasVarianceLayers(referenceFile);
  std::vector<std::string> materialNames;
  try {
    materialNames = materialNamesOf(referenceMetadata);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("'" + opt.reference + "': " + e.what());
  }
  const Image reference = rgbChannels(referenceFile);
  std::vector<ReportEntry> candidates;
  for (size_t i = 0; i < count; ++i) {
    ReportEntry c;
    c.runs.assign(opt.candidates.begin() + ptrdiff_t(i * runs), opt.candidates.begin() + ptrdiff_t((i + 1) * runs));
    c.path = c.runs[0];
    c.sidecar = readSidecar(c.path);
    const std::string fileName = std::filesystem::path(c.path).filename().string();
    c.label = !opt.labels.empty()                           ? opt.labels[i]
              : c.sidecar && !c.sidecar->renderer.empty() ? c.sidecar->renderer + " · " + fileName
                                                            : fileName;
    // Each run's image (its layer with --layer); their mean is shown and measured, their spread is
    // the noise of the tests. The seconds: --seconds, else the runs' sidecars' or Lucent's own
    // records summed, where every run has one.
    std::vector<Image> runImages;
    std::optional<double> runSeconds = 0.0;
    bool candidateIsSrgb = false;  // any run's values sRGB-encoded (as lucent compare takes it)
    std::vector<StoredRounding> rounding;
    for (size_t k = 0; k < runs; ++k) {
      ImageMetadata metadata;
      Image run = readLinearImage(c.runs[k], &metadata);
      const bool srgb = isSrgbEncoded(c.runs[k], metadata);
      candidateIsSrgb = candidateIsSrgb || srgb;
      rounding.push_back(storedRoundingOf(headers[i * runs + k], srgb));
      if (!opt.layer.empty()) run = chosen(run, c.runs[k]).candidate;
      const std::optional<Sidecar> sidecar = k == 0 ? c.sidecar : readSidecar(c.runs[k]);
      const std::optional<double> seconds = sidecar && sidecar->seconds ? sidecar->seconds : renderSeconds(metadata);
      runSeconds = runSeconds && seconds ? std::optional<double>(*runSeconds + *seconds) : std::nullopt;
      if (k == 0) c.metadata = std::move(metadata);
      runImages.push_back(std::move(run));
    }
    c.seconds = !opt.seconds.empty() ? std::optional<double>(opt.seconds[i]) : runSeconds;
    Candidate candidate = runs == 1 ? Candidate(std::move(runImages[0]), halfVariance[i]) : Candidate(std::move(runImages));
    candidate.rounding = std::move(rounding);
    candidate.referenceRounding = storedRoundingOf(referenceHeader, referenceIsSrgb);
    const Image file = candidateImage(candidate);
    const Image image = rgbChannels(file);
    // An 8-bit candidate against the reference clipped to [0, 1] (--ldr), as lucent compare does.
    std::optional<Image> clippedFile, clipped;
    try {
      if (candidateIsSrgb && !referenceIsSrgb) {
        clippedFile = referenceFile;
        if (matchDisplayRange(candidateIsSrgb, referenceIsSrgb, *clippedFile, opt.ldr) > 0) clipped = rgbChannels(*clippedFile);
        else clippedFile.reset();
      }
      const Image& referenceFor = clipped ? *clipped : reference;
      const Image& referenceFileFor = clippedFile ? *clippedFile : referenceFile;
      if (tested) c.test = testWithinNoise(candidate, referenceFileFor, opt.alpha);
      if (tested && opt.within) c.equivalence = testEquivalence(candidate, referenceFileFor, *opt.within, opt.alpha);
      if (tested) c.surfaces = differenceBySurface(candidate, referenceFileFor, materialNames, opt.alpha);
      c.error = compareImages(image, referenceFor);
      // As lucent compare --metric flip: LDR-FLIP between 8-bit files, HDR-FLIP otherwise.
      c.flip = computeFlip(image, referenceFor, flipOptions(candidateIsSrgb, referenceIsSrgb, opt.pixelsPerDegree));
      c.errorUri = pngDataUri(errorHeatmap(image, referenceFor, ErrorMetric::RelMse, 0, &c.errorScale));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + c.path + "' vs '" + opt.reference + "': " + e.what());
    }
    c.imageUri = pngDataUri(exposed(image, opt.exposure));
    c.flipUri = pngDataUri(valueHeatmap(c.flip.map, 1));
    if (c.test) c.statisticUri = pngDataUri(valueHeatmap(c.test->statistic, 5));
    candidates.push_back(std::move(c));
  }
  const std::string page = reportPage(opt, referenceFile, referenceMetadata, candidates, tested);
  writeFileAtomically(opt.output, "report", [&page](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << page;
    out.close();
    if (!out) throw WriteFailure("write failed");
  });

  std::cout << reportLine(opt, candidates, tested) << std::endl;
  return 0;
}

}  // namespace

void addReportCommand(CLI::App& app, int& exitCode) {
  auto opt = std::make_shared<ReportOptions>();
  CLI::App* cmd = app.add_subcommand("report", "Write an HTML page comparing images with a reference");
  cmd->add_option("reference", opt->reference,
                  "Reference image (with variance layers, from --method pt --variance, for the noise test)")
      ->required();
  cmd->add_option("candidates", opt->candidates, "Images to compare with the reference")->required();
  cmd->add_option("-o,--output", opt->output, "The HTML page to write")->required();
  // --label and --seconds take every value up to the next option: --label a b names two candidates.
  cmd->add_option("--runs", opt->runs,
                  "Images per candidate (default 1): each candidate is that many consecutive images, independent "
                  "runs of one renderer whose mean is shown and whose spread is the noise of the tests");
  cmd->add_option("--label", opt->labels, "A name per candidate, in order (default: the file name)");
  cmd->add_option("--seconds", opt->seconds,
                  "Seconds per candidate, in order, for the speed-accuracy chart (default: the "
                  "lucent:render_seconds a Lucent render stores)");
  cmd->add_option("--alpha", opt->alpha, "Significance of the noise test and --within, in [1e-12, 0.25] (default 0.01)");
  cmd->add_option("--within", opt->within,
                  "Also show compare --within D's verdict: each region's relative difference with its interval");
  cmd->add_option("--exposure", opt->exposure, "Exposure of the shown images, in stops, in [-30, 30] (default 0)");
  addLayerOptions(cmd, opt->layer, opt->imageLayer, "each candidate");
  cmd->add_option("--ppd", opt->pixelsPerDegree, kPixelsPerDegreeHelp);
  cmd->add_flag("--ldr", opt->ldr,
                "8-bit candidates are display images: compare each with the reference clipped to [0, 1] (without "
                "it, an 8-bit candidate against a reference brighter than 1 is refused)");
  cmd->callback([opt, &exitCode] {
    try {
      exitCode = runReport(*opt);
    } catch (const std::exception& e) {
      std::cerr << "lucent report: error: " << printable(e.what()) << "\n";
      exitCode = 1;
    }
  });
}

}  // namespace lucent::cli
