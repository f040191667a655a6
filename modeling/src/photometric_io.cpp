// Photometric stereo input: lights files, image lists, images (OpenCV, plus a small TGA
// reader) and masks.

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/modeling/photometric.hpp"

namespace hapticlab::modeling {
namespace {

constexpr double kPi = std::numbers::pi;
// Lines a lights file or image list may hold: a little over kMaxLights (docs/formats.md).
constexpr std::size_t kMaxTextLines = kMaxLights + 2;

Eigen::Vector3d FromAngles(double elev_deg, double azim_deg) {
  const double e = elev_deg * kPi / 180, a = azim_deg * kPi / 180;
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

struct TextLine {
  int line = 0;
  std::vector<std::string> cells;
};

// Splits text into non-blank, non-comment lines of cells separated by commas and/or
// whitespace. An empty cell between two commas is an error.
std::vector<TextLine> SplitCells(const std::string& text, const std::string& path) {
  std::vector<TextLine> out;
  int number = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string s = text.substr(pos, end - pos);
    pos = end + 1;
    ++number;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    const auto first = s.find_first_not_of(" \t");
    if (first == std::string::npos || s[first] == '#') {
      if (end == text.size()) break;
      continue;
    }
    TextLine tl{number, {}};
    std::string cell;
    bool after_comma = false, have_cell = false;
    for (std::size_t i = first; i <= s.size(); ++i) {
      const bool at_end = i == s.size();  // the end of the line, not a NUL byte in it
      const char c = at_end ? ',' : s[i];
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t')
        throw InputError(path, number, "",
                         fmt::format("control character (byte 0x{:02x}) in a text file",
                                     static_cast<unsigned char>(c)));
      if (at_end || c == ',' || c == ' ' || c == '\t') {
        if (have_cell) {
          tl.cells.push_back(cell);
          cell.clear();
          have_cell = false;
          after_comma = false;
        }
        if (c == ',' && !at_end) {
          if (after_comma || tl.cells.empty())
            throw InputError(path, number, "", "empty cell between commas");
          after_comma = true;
        }
      } else {
        cell += c;
        have_cell = true;
      }
    }
    if (after_comma) throw InputError(path, number, "", "line ends with a comma");
    if (tl.cells.empty()) continue;  // only separators: nothing on the line
    if (out.size() >= kMaxTextLines)
      throw InputError(path, number, "", fmt::format("more than {} lines", kMaxTextLines));
    out.push_back(std::move(tl));
    if (end == text.size()) break;
  }
  return out;
}

std::optional<double> ParseNumber(const std::string& s) {
  double v = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, v);
  if (r.ec != std::errc() || r.ptr != e) return std::nullopt;
  return v;
}

bool IsCount(const TextLine& l) {
  if (l.cells.size() != 1) return false;
  const auto& s = l.cells[0];
  return !s.empty() &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

std::string Lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::vector<Light> DomePreset() {
  std::vector<Light> l;
  int k = 0;
  for (double e : {40.0, 55.0, 70.0})
    for (int a = 0; a < 10; ++a)
      l.push_back({fmt::format("light_{:02d}.png", k++), FromAngles(e, 36.0 * a), 0});
  return l;
}

namespace {

// The optional count line of a lights file (a lone integer, 3..kMaxLights) at lines[*k]: its
// value, with *k past it and *count_line its line.
std::optional<std::size_t> ReadCount(const std::vector<TextLine>& lines, const std::string& path,
                                     std::size_t* k, int* count_line) {
  if (!(*k < lines.size() && IsCount(lines[*k]))) return std::nullopt;
  const auto& digits = lines[*k].cells[0];
  std::size_t n = 0;
  const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), n);
  *count_line = lines[*k].line;
  if (r.ec != std::errc() || n < 3 || n > kMaxLights)
    throw InputError(path, *count_line, "count",
                     fmt::format("'{}' lights; expected 3..{}", digits, kMaxLights));
  ++*k;
  return n;
}

// The columns of a lights file at lines[*k]: from a header (every cell non-numeric; *k moves
// past it) or from the first row's shape.
std::vector<std::string> ReadColumns(const std::vector<TextLine>& lines, const std::string& path,
                                     std::size_t* k) {
  std::vector<std::string> cols;
  if (*k < lines.size() &&
      std::none_of(lines[*k].cells.begin(), lines[*k].cells.end(),
                   [](const std::string& c) { return ParseNumber(c).has_value(); }) &&
      lines[*k].cells.size() >= 3) {
    for (const auto& c : lines[*k].cells) cols.push_back(Lower(c));
    const std::vector<std::vector<std::string>> known = {
        {"file", "elevation_deg", "azimuth_deg"}, {"file", "lx", "ly", "lz"}, {"lx", "ly", "lz"}};
    if (std::find(known.begin(), known.end(), cols) == known.end())
      throw InputError(
          path, lines[*k].line, lines[*k].cells[0],
          "unknown header; expected file,elevation_deg,azimuth_deg or file,lx,ly,lz or lx,ly,lz");
    ++*k;
  } else if (*k < lines.size()) {
    const auto& c = lines[*k].cells;
    const bool named = !ParseNumber(c[0]).has_value();
    if (named && c.size() == 3)
      cols = {"file", "elevation_deg", "azimuth_deg"};
    else if (named && c.size() == 4)
      cols = {"file", "lx", "ly", "lz"};
    else if (!named && c.size() == 3)
      cols = {"lx", "ly", "lz"};
    else
      throw InputError(
          path, lines[*k].line, "",
          fmt::format(
              "{} cells; expected file elevation_deg azimuth_deg, file lx ly lz, or lx ly lz",
              c.size()));
  }
  return cols;
}

// One light of a lights file in the columns `cols`: its direction a unit vector above the
// sample plane.
Light ReadLight(const TextLine& l, const std::vector<std::string>& cols, const std::string& path) {
  const bool named = !cols.empty() && cols[0] == "file";
  const bool angles = cols.size() == 3 && named;
  if (l.cells.size() != cols.size())
    throw InputError(path, l.line, "",
                     fmt::format("{} cells, expected {} ({})", l.cells.size(), cols.size(),
                                 fmt::join(cols, ",")));
  Light light;
  light.line = l.line;
  light.source = path;
  const std::size_t first = named ? 1 : 0;
  if (named) light.file = l.cells[0];
  double v[3] = {0, 0, 0};
  for (std::size_t c = first; c < cols.size(); ++c) {
    const auto x = ParseNumber(l.cells[c]);
    if (!x || !std::isfinite(*x))
      throw InputError(path, l.line, cols[c],
                       fmt::format("'{}' is not a finite number", l.cells[c]));
    v[c - first] = *x;
  }
  if (angles) {
    light.direction = FromAngles(v[0], v[1]);
  } else {
    light.direction = Eigen::Vector3d(v[0], v[1], v[2]);
    if (!(light.direction.norm() > 0)) throw InputError(path, l.line, "lx", "zero light direction");
    light.direction.normalize();
  }
  if (!(light.direction.z() > 0))
    throw InputError(path, l.line, angles ? "elevation_deg" : "lz",
                     "light at or below the sample plane (z must be > 0)");
  return light;
}

// A lights file: an optional count line, an optional header, then one light a line.
std::vector<Light> ReadLightsFile(const std::string& path) {
  std::vector<Light> out;
  const auto lines = SplitCells(ReadTextFile(path, "lights file"), path);
  std::size_t k = 0;
  int count_line = 0;
  const std::optional<std::size_t> count = ReadCount(lines, path, &k, &count_line);
  const std::vector<std::string> cols = ReadColumns(lines, path, &k);
  for (; k < lines.size(); ++k) out.push_back(ReadLight(lines[k], cols, path));
  if (out.size() > kMaxLights)
    throw InputError(path, lines.back().line, "",
                     fmt::format("{} lights; at most {} are read", out.size(), kMaxLights));
  if (count && *count != out.size())
    throw InputError(
        path, count_line, "",
        fmt::format("the count line says {} lights, the file has {}", *count, out.size()));
  if (out.size() < 3) throw InputError(path, 0, "", "photometric stereo needs at least 3 lights");
  return out;
}

}  // namespace

std::vector<Light> LoadLights(const std::string& path, bool y_up) {
  std::vector<Light> out = path == "dome" ? DomePreset() : ReadLightsFile(path);
  if (y_up)
    for (auto& l : out) l.direction.y() = -l.direction.y();
  return out;
}

void ApplyImageList(const std::string& list_path, std::vector<Light>& lights) {
  const auto lines = SplitCells(ReadTextFile(list_path, "image list"), list_path);
  for (const auto& l : lines)
    if (l.cells.size() != 1)
      throw InputError(list_path, l.line, "",
                       "one file name per line expected (names without spaces or commas)");
  if (lines.size() != lights.size())
    throw InputError(list_path, lines.empty() ? 0 : lines.back().line, "",
                     fmt::format("{} image names for {} lights", lines.size(), lights.size()));
  for (std::size_t i = 0; i < lights.size(); ++i) lights[i].file = lines[i].cells[0];
}

namespace {

// OpenCV 4.6's imgcodecs has no TGA (Truevision Targa) decoder, so this small reader covers
// the common cases: image types 2/3 (uncompressed colour/grey) and 10/11 (RLE), grey 8-bit,
// colour 16 (5-5-5), 24 and 32-bit; bottom-left or top-left origin. Returns BGR(A) or grey
// 8-bit, the same layout cv::imread gives.
cv::Mat ReadTga(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path, 0, "", "cannot open TGA file");
  const std::vector<unsigned char> d((std::istreambuf_iterator<char>(f)),
                                     std::istreambuf_iterator<char>());
  auto bad = [&](const std::string& what) { return InputError(path, 0, "", "TGA: " + what); };
  if (d.size() < 18) throw bad("file shorter than its 18-byte header");
  const int id_len = d[0], cmap_type = d[1], type = d[2];
  const int cmap_len = d[5] | (d[6] << 8), cmap_bits = d[7];
  const int w = d[12] | (d[13] << 8), h = d[14] | (d[15] << 8), bpp = d[16], desc = d[17];
  if (type != 2 && type != 3 && type != 10 && type != 11)
    throw bad(fmt::format(
        "image type {} not supported (2, 3, 10, 11: uncompressed or RLE colour/grey)", type));
  const bool grey = type == 3 || type == 11;
  if (grey ? bpp != 8 : (bpp != 16 && bpp != 24 && bpp != 32))
    throw bad(fmt::format("{} bits per pixel not supported for {} images", bpp,
                          grey ? "grey" : "colour"));
  if (w <= 0 || h <= 0) throw bad("zero width or height");
  std::size_t at = 18 + static_cast<std::size_t>(id_len) +
                   (cmap_type ? static_cast<std::size_t>(cmap_len) *
                                    static_cast<std::size_t>((cmap_bits + 7) / 8)
                              : 0);
  const std::size_t bytes = static_cast<std::size_t>(bpp / 8),
                    n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  // The header's size is checked against the bytes present before anything is allocated: raw
  // data holds `bytes` per pixel, an RLE packet (1 header byte + at least `bytes`) at most 128.
  if (at > d.size()) throw bad("header, id and colour map run past the end of the file");
  const std::size_t present = d.size() - at;
  if ((type == 2 || type == 3) && present < n * bytes)
    throw bad(fmt::format("pixel data truncated ({}x{} pixels need {} bytes, {} present)", w, h,
                          n * bytes, present));
  if ((type == 10 || type == 11) && n > 128 * (present / (1 + bytes)))
    throw bad(fmt::format("RLE data truncated ({} bytes cannot hold {}x{} pixels)", present, w, h));
  std::vector<unsigned char> px(n * bytes);
  if (type == 2 || type == 3) {
    std::copy(d.begin() + static_cast<std::ptrdiff_t>(at),
              d.begin() + static_cast<std::ptrdiff_t>(at + px.size()), px.begin());
  } else {
    std::size_t o = 0;
    while (o < n) {
      if (at >= d.size()) throw bad("RLE data truncated");
      const int hdr = d[at++];
      const std::size_t run = static_cast<std::size_t>(hdr & 0x7f) + 1;
      if (o + run > n) throw bad("RLE packet runs past the image");
      if (hdr & 0x80) {
        if (at + bytes > d.size()) throw bad("RLE data truncated");
        for (std::size_t r = 0; r < run; ++r, ++o) std::copy_n(&d[at], bytes, &px[o * bytes]);
        at += bytes;
      } else {
        if (at + run * bytes > d.size()) throw bad("RLE data truncated");
        std::copy_n(&d[at], run * bytes, &px[o * bytes]);
        at += run * bytes;
        o += run;
      }
    }
  }
  const bool top = (desc & 0x20) != 0, right_to_left = (desc & 0x10) != 0;
  cv::Mat m(h, w, grey ? CV_8UC1 : (bpp == 32 ? CV_8UC4 : CV_8UC3));
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const std::size_t src =
          (static_cast<std::size_t>(top ? i : h - 1 - i) * static_cast<std::size_t>(w) +
           static_cast<std::size_t>(right_to_left ? w - 1 - j : j)) *
          bytes;
      unsigned char* dst = m.ptr<unsigned char>(i) +
                           static_cast<std::size_t>(j) * static_cast<std::size_t>(m.channels());
      if (bpp == 16) {  // A RRRRR GGGGG BBBBB, little endian
        const int v = px[src] | (px[src + 1] << 8);
        dst[0] = static_cast<unsigned char>(((v & 31) * 255 + 15) / 31);
        dst[1] = static_cast<unsigned char>((((v >> 5) & 31) * 255 + 15) / 31);
        dst[2] = static_cast<unsigned char>((((v >> 10) & 31) * 255 + 15) / 31);
      } else {
        std::copy_n(&px[src], bytes, dst);  // TGA stores B, G, R(, A) like OpenCV
      }
    }
  return m;
}

bool IsTga(const std::string& path) {
  return Lower(std::filesystem::path(path).extension().string()) == ".tga";
}

cv::Mat ReadAny(const std::string& path) {
  std::error_code ec;  // a name too long to look up is "not found", not a filesystem_error
  if (IsTga(path) && !cv::haveImageReader(path)) {
    if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, "", "image not found");
    return ReadTga(path);
  }
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty())
    throw InputError(path, 0, "",
                     std::filesystem::exists(path, ec)
                         ? "cannot read image (a format OpenCV reads, or TGA)"
                         : "image not found");
  return m;
}

}  // namespace

std::vector<float> ReadGreyImage(const std::string& path, int* width, int* height) {
  cv::Mat m = ReadAny(path);
  double scale = 1;
  switch (m.depth()) {
    case CV_8U:
      scale = 1.0 / 255;
      break;
    case CV_16U:
      scale = 1.0 / 65535;
      break;
    case CV_8S:
      scale = 1.0 / 127;
      break;
    case CV_16S:
      scale = 1.0 / 32767;
      break;
    default:
      break;  // float (and 32-bit integer) values as stored
  }
  cv::Mat f;
  m.convertTo(f, CV_MAKETYPE(CV_32F, m.channels()), scale);
  cv::Mat g;
  if (f.channels() == 1)
    g = f;
  else if (f.channels() == 3)
    cv::cvtColor(f, g, cv::COLOR_BGR2GRAY);
  else if (f.channels() == 4)
    cv::cvtColor(f, g, cv::COLOR_BGRA2GRAY);
  else if (f.channels() == 2)
    cv::extractChannel(f, g, 0);  // grey + alpha
  else
    throw InputError(path, 0, "", fmt::format("{} channels not supported", f.channels()));
  if (!g.isContinuous()) g = g.clone();
  *width = g.cols;
  *height = g.rows;
  return {g.ptr<float>(),
          g.ptr<float>() + static_cast<std::size_t>(g.cols) * static_cast<std::size_t>(g.rows)};
}

ImageStack ReadImages(const std::string& dir, const std::vector<Light>& lights) {
  ImageStack s;
  for (const auto& l : lights) {
    if (l.file.empty())
      throw InputError(l.source.empty() ? dir : l.source, l.line, "file",
                       "a light has no image name (give an image list)");
    const std::string path = (std::filesystem::path(dir) / l.file).string();
    int w = 0, h = 0;
    auto img = ReadGreyImage(path, &w, &h);
    if (s.images.empty()) {
      s.width = w;
      s.height = h;
      const double stack_bytes = static_cast<double>(lights.size()) * w * h * sizeof(float);
      if (stack_bytes > static_cast<double>(kMaxImageStackBytes))
        throw InputError(
            path, 0, "",
            fmt::format("{} images of {}x{} pixels need {:.1f} GiB, more than the "
                        "{} GiB allowed",
                        lights.size(), w, h, stack_bytes / (1 << 30), kMaxImageStackBytes >> 30));
    } else if (w != s.width || h != s.height) {
      throw InputError(path, 0, "",
                       fmt::format("image is {}x{}, the first was {}x{}", w, h, s.width, s.height));
    }
    s.images.push_back(std::move(img));
  }
  return s;
}

std::vector<std::uint8_t> ReadMask(const std::string& path, int width, int height) {
  const cv::Mat m = ReadAny(path);
  if (m.cols != width || m.rows != height)
    throw InputError(
        path, 0, "",
        fmt::format("mask is {}x{}, the images are {}x{}", m.cols, m.rows, width, height));
  cv::Mat f;
  m.convertTo(f, CV_MAKETYPE(CV_32F, m.channels()));
  const int colour = m.channels() == 4 ? 3 : m.channels() == 2 ? 1 : m.channels();  // alpha ignored
  std::vector<std::uint8_t> out(static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
                                0);
  for (int i = 0; i < height; ++i) {
    const float* row = f.ptr<float>(i);
    for (int j = 0; j < width; ++j)
      for (int c = 0; c < colour; ++c)
        if (row[j * f.channels() + c] != 0)
          out[static_cast<std::size_t>(i) * static_cast<std::size_t>(width) +
              static_cast<std::size_t>(j)] = 1;
  }
  return out;
}

}  // namespace hapticlab::modeling
