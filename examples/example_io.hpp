// edgeplane examples: file input and output shared by the example programs (edgeplane_segment, and
// later edgeplane_evaluate).  Examples-only code: it uses OpenCV and iostreams and may print; the
// library itself never does either.
//
// What is here:
//   - cli_error, arg_cursor, parse_float / parse_int: strict command-line parsing;
//   - load_depth_png: a 16-bit single-channel PNG, checked before it is decoded so that a missing,
//     empty, truncated, 8-bit or colour file gives one clear message instead of a decoder's noise;
//   - write_png, write_planes_json: outputs, each failure an exception with the path;
//   - render_overlay: depth as grey with one colour per plane id and darker plane boundaries;
//   - stage_fields, median: per-stage timing tables.
#pragma once
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <edgeplane/segmenter.hpp>

#if __has_include(<unistd.h>) && __has_include(<fcntl.h>)
#include <fcntl.h>
#include <unistd.h>
#define EDGEPLANE_EXAMPLES_POSIX 1
#else
#define EDGEPLANE_EXAMPLES_POSIX 0
#endif

namespace edgeplane_examples {

// ---- errors and argument parsing ---------------------------------------------------------------

/// A problem with the command line or an input or output file.  Programs print what() as one
/// line and exit with status 2.
class cli_error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] inline void fail(const std::string& what) { throw cli_error(what); }

/// `what` on one line: newlines and other control characters (from file names or library
/// messages) become spaces.
inline std::string one_line(std::string what) {
  for (char& c : what)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return what;
}

/// Walks argv.  Options are `--name value` or `--name=value`; any other argument that starts with
/// '-' is an option too (so `-x` is reported as unknown, not as a missing file); a bare `--` makes
/// every later argument positional.  A value is taken as it is, so `--fy -480` works.
class arg_cursor {
 public:
  arg_cursor(int argc, char** argv) : args_(argv + (argc > 0 ? 1 : 0), argv + std::max(argc, 1)) {}

  /// Moves to the next argument; false at the end.
  bool next() {
    if (pos_ >= args_.size()) return false;
    const std::string& a = args_[pos_++];
    inline_value_.reset();
    if (!only_positional_ && a == "--") {
      only_positional_ = true;
      return next();
    }
    is_option_ = !only_positional_ && a.size() > 1 && a.front() == '-';  // "-" alone is a file name
    name_ = a;
    if (is_option_ && a.starts_with("--")) {
      if (const auto eq = a.find('='); eq != std::string::npos) {
        name_ = a.substr(0, eq);
        inline_value_ = a.substr(eq + 1);
      }
    }
    return true;
  }
  /// The current argument is an option (`--name`, `--name=value`).
  bool is_option() const { return is_option_; }
  /// The option's name with its dashes ("--fx"), or the positional argument itself.
  const std::string& name() const { return name_; }
  /// The option's value: the part after '=' or the next argument.
  std::string value() {
    if (inline_value_) return *inline_value_;
    if (pos_ >= args_.size()) fail("option " + name_ + " needs a value");
    return args_[pos_++];
  }
  /// For options that take no value: rejects `--quiet=yes`.
  void no_value() const {
    if (inline_value_) fail("option " + name_ + " takes no value");
  }

 private:
  std::vector<std::string> args_;
  std::size_t pos_ = 0;
  bool only_positional_ = false;
  bool is_option_ = false;
  std::string name_;
  std::optional<std::string> inline_value_;
};

/// The whole of `text` as a float ("nan" and "inf" parse; the caller checks finiteness).
inline float parse_float(const std::string& text, std::string_view what) {
  float v = 0.f;
  const char* first = text.data();
  const char* last = first + text.size();
  if (first != last && *first == '+') ++first;  // from_chars rejects a leading '+'
  const auto [end, ec] = std::from_chars(first, last, v);
  if (text.empty() || ec != std::errc{} || end != last) fail(std::string(what) + ": '" + text + "' is not a number");
  return v;
}

/// The whole of `text` as an integer within [lo, hi].
inline long parse_int(const std::string& text, std::string_view what, long lo, long hi) {
  long v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc{} || end != text.data() + text.size())
    fail(std::string(what) + ": '" + text + "' is not an integer");
  if (v < lo || v > hi)
    fail(std::string(what) + " must be between " + std::to_string(lo) + " and " + std::to_string(hi) + " (got " + text +
         ")");
  return v;
}

// ---- depth input -------------------------------------------------------------------------------

namespace detail {
inline std::uint32_t read_be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
}

/// CRC-32 as PNG uses it (ISO 3309, polynomial 0xedb88320), over `n` bytes.
inline std::uint32_t png_crc(const unsigned char* p, std::size_t n) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xffffffffu;
  for (std::size_t i = 0; i < n; ++i) c = table[(c ^ p[i]) & 0xffu] ^ (c >> 8);
  return c ^ 0xffffffffu;
}

inline const char* png_colour_name(int colour_type) {
  switch (colour_type) {
    case 0:
      return "greyscale";
    case 2:
      return "RGB colour";
    case 3:
      return "palette colour";
    case 4:
      return "greyscale+alpha";
    case 6:
      return "RGBA colour";
    default:
      return "unknown colour type";
  }
}

/// Checks the chunk structure of a PNG held in memory (signature, every chunk inside the file with
/// a correct CRC, IHDR first, IEND present) and that it is 16-bit greyscale.  Throws cli_error
/// naming the problem.
inline void check_png_structure(const std::vector<unsigned char>& b, const std::string& name) {
  static constexpr unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (b.size() < 8 || !std::equal(std::begin(signature), std::end(signature), b.begin()))
    fail("'" + name + "' is not a PNG file");
  std::size_t pos = 8;
  bool first = true, end_seen = false;
  int bit_depth = 0, colour_type = -1;
  std::uint32_t width = 0, height = 0;
  while (pos + 8 <= b.size()) {
    const std::uint32_t len = read_be32(&b[pos]);
    std::string type(reinterpret_cast<const char*>(&b[pos + 4]), 4);
    for (char& c : type)  // printable in messages even when corrupt
      if (c < 0x21 || c > 0x7e) c = '?';
    if (len > 0x7fffffffu || len > b.size() - pos - 8 || b.size() - pos - 8 - len < 4)
      fail("'" + name + "' is truncated or corrupt (chunk '" + type + "' runs past the end of the file)");
    if (read_be32(&b[pos + 8 + len]) != png_crc(&b[pos + 4], len + 4))
      fail("'" + name + "' is corrupt (bad checksum in chunk '" + type + "')");
    if (first) {
      if (type != "IHDR" || len != 13) fail("'" + name + "' is corrupt (does not start with an IHDR chunk)");
      width = read_be32(&b[pos + 8]);
      height = read_be32(&b[pos + 12]);
      bit_depth = b[pos + 16];
      colour_type = b[pos + 17];
      first = false;
    }
    pos += 12 + static_cast<std::size_t>(len);
    if (type == "IEND") {
      end_seen = true;
      break;
    }
  }
  if (first) fail("'" + name + "' is truncated (no IHDR chunk)");
  if (!end_seen) fail("'" + name + "' is truncated (no IEND chunk)");
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu)
    fail("'" + name + "' has an invalid size " + std::to_string(width) + "x" + std::to_string(height));
  const std::string a_bits = (bit_depth == 8 ? "an " : "a ") + std::to_string(bit_depth) + "-bit ";
  if (colour_type != 0)
    fail("'" + name + "' is " + a_bits + png_colour_name(colour_type) +
         " image; expected a 16-bit single-channel depth image");
  if (bit_depth != 16)
    fail("'" + name + "' is " + a_bits + "greyscale image; expected a 16-bit single-channel depth image");
}
}  // namespace detail

namespace detail {
/// Sends the process's stderr to /dev/null while it lives (POSIX; elsewhere it does nothing).
/// libpng, under OpenCV, writes "libpng error: ..." to stderr itself when compressed data are
/// corrupt; the program reports the failure once, in its own words.
class stderr_silencer {
 public:
  stderr_silencer() {
#if EDGEPLANE_EXAMPLES_POSIX
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
#endif
  }
  ~stderr_silencer() {
#if EDGEPLANE_EXAMPLES_POSIX
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
    }
#endif
  }
  stderr_silencer(const stderr_silencer&) = delete;
  stderr_silencer& operator=(const stderr_silencer&) = delete;

 private:
  int saved_ = -1;
};
}  // namespace detail

/// Reads a 16-bit single-channel PNG depth image (CV_16UC1, 0 = no depth).  The file's chunk
/// structure is checked before it is decoded; every problem (missing, a directory, empty,
/// truncated, corrupt, not 16-bit, colour) throws cli_error with a one-line message.
inline cv::Mat load_depth_png(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) fail("cannot read '" + path + "': no such file");
  if (fs::is_directory(st)) fail("cannot read '" + path + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot open '" + path + "' for reading");
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail("error while reading '" + path + "'");
  if (bytes.empty()) fail("'" + path + "' is empty");
  detail::check_png_structure(bytes, path);
  cv::Mat m;
  try {
    const detail::stderr_silencer quiet;  // libpng prints its own complaint about corrupt data
    m = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    fail("'" + path + "' could not be decoded: " + e.msg);
  }
  if (m.empty()) fail("'" + path + "' could not be decoded as a PNG image");
  if (m.type() != CV_16UC1)
    fail("'" + path + "' decoded to " + std::to_string(m.elemSize1() * 8) + "-bit data with " +
         std::to_string(m.channels()) + " channel(s); expected a 16-bit single-channel depth image");
  return m;
}

/// Keeps OpenCV's own logging quiet, so that a failure is reported once, by the program.
inline void quiet_opencv_logging() { cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT); }

// ---- outputs -----------------------------------------------------------------------------------

/// Writes `image` as a PNG (CV_16UC1 gives a 16-bit PNG).  Throws cli_error on failure.
inline void write_png(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image);
  } catch (const cv::Exception& e) {
    fail("cannot write '" + path + "': " + e.msg);
  }
  if (!ok) fail("cannot write '" + path + "'");
}

namespace detail {
inline void json_number(std::string& s, double v, const char* fmt = "%.9g") {
  if (!std::isfinite(v)) {  // JSON has no NaN or infinity
    s += "null";
    return;
  }
  char buf[40];
  std::snprintf(buf, sizeof buf, fmt, v);
  s += buf;
}
template <class T, std::size_t N>
void json_array(std::string& s, const std::array<T, N>& a) {
  s += '[';
  for (std::size_t i = 0; i < N; ++i) {
    if (i) s += ',';
    if constexpr (std::is_floating_point_v<T>)
      json_number(s, a[i]);
    else
      s += std::to_string(a[i]);
  }
  s += ']';
}
}  // namespace detail

/// The planes as a JSON array, one object per line:
/// [{"id":1,"normal":[x,y,z],"d":..,"centroid":[x,y,z],"pixels":N,"points":N,
///   "eigenvalues":[l1,l2,l3],"bbox":[x0,y0,x1,y1]}, ...]
/// Metres and square metres as in edgeplane::plane; floats with 9 significant digits (exact for
/// float); a non-finite value is written as null.
inline std::string planes_json(const std::vector<edgeplane::plane>& planes) {
  std::string s = "[";
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const edgeplane::plane& p = planes[i];
    s += i ? ",\n " : "\n ";
    s += "{\"id\":" + std::to_string(p.id) + ",\"normal\":";
    detail::json_array(s, p.normal);
    s += ",\"d\":";
    detail::json_number(s, p.d);
    s += ",\"centroid\":";
    detail::json_array(s, p.centroid);
    s += ",\"pixels\":" + std::to_string(p.pixels) + ",\"points\":" + std::to_string(p.points) + ",\"eigenvalues\":";
    detail::json_array(s, p.eigenvalues);
    s += ",\"bbox\":";
    detail::json_array(s, p.bbox);
    s += '}';
  }
  s += planes.empty() ? "]\n" : "\n]\n";
  return s;
}

/// Writes planes_json(planes) to `path`.  Throws cli_error on failure.
inline void write_planes_json(const std::string& path, const std::vector<edgeplane::plane>& planes) {
  const std::string text = planes_json(planes);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) fail("cannot open '" + path + "' for writing");
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) fail("error while writing '" + path + "'");
}

// ---- overlay -----------------------------------------------------------------------------------

/// A distinct colour for plane id k (BGR): hues step by the golden ratio, so neighbouring ids are
/// far apart on the colour wheel.
inline cv::Vec3b plane_colour(int k) {
  const double h = std::fmod(0.11 + 0.6180339887498949 * k, 1.0) * 6.0;
  const double s = (k % 2) ? 0.85 : 0.65, v = (k % 3 == 2) ? 0.8 : 1.0;
  const int i = static_cast<int>(h);
  const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  const double rgb[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
  const double r = rgb[i % 6][0], g = rgb[i % 6][1], b = rgb[i % 6][2];
  return {cv::saturate_cast<std::uint8_t>(b * 255), cv::saturate_cast<std::uint8_t>(g * 255),
          cv::saturate_cast<std::uint8_t>(r * 255)};
}

/// A picture for people (8-bit BGR): the depth as grey (near bright, far dark, histogram-equalised
/// over the non-zero depths so that every depth range gets contrast; no depth is black, or mid
/// grey under a plane's colour), each
/// plane id blended in its own colour, plane boundaries in a dark shade of that colour, and each
/// plane's id written at the point of the plane farthest from its boundary.
/// depth: CV_16UC1; labels: CV_16UC1 of the same size (0 = no plane).
inline cv::Mat render_overlay(const cv::Mat& depth, const cv::Mat& labels) {
  CV_Assert(depth.type() == CV_16UC1 && labels.type() == CV_16UC1 && depth.size() == labels.size());
  const int w = depth.cols, h = depth.rows;
  // grey level of each raw depth value: 255 - 200 * (fraction of valid pixels nearer than it)
  std::vector<double> grey(65536, 0.0);
  {
    std::vector<std::int64_t> hist(65536, 0);
    std::int64_t valid = 0;
    for (int y = 0; y < h; ++y) {
      const std::uint16_t* d = depth.ptr<std::uint16_t>(y);
      for (int x = 0; x < w; ++x)
        if (d[x]) ++hist[d[x]], ++valid;
    }
    std::int64_t below = 0;
    for (int v = 1; v < 65536; ++v) {
      if (hist[v] == 0) continue;
      grey[v] = 255.0 -
                200.0 * (static_cast<double>(below) + 0.5 * static_cast<double>(hist[v])) / static_cast<double>(valid);
      below += hist[v];
    }
  }

  std::uint16_t max_id = 0;
  for (int y = 0; y < h; ++y) {
    const std::uint16_t* l = labels.ptr<std::uint16_t>(y);
    max_id = std::max(max_id, *std::max_element(l, l + w));
  }
  std::vector<cv::Vec3b> colour(static_cast<std::size_t>(max_id) + 1);
  for (int k = 1; k <= max_id; ++k) colour[k] = plane_colour(k);

  cv::Mat out(h, w, CV_8UC3);
  cv::Mat interior(h, w, CV_8UC1, cv::Scalar(0));  // labelled and not on a boundary
  for (int y = 0; y < h; ++y) {
    const std::uint16_t* d = depth.ptr<std::uint16_t>(y);
    const std::uint16_t* l = labels.ptr<std::uint16_t>(y);
    const std::uint16_t* up = y > 0 ? labels.ptr<std::uint16_t>(y - 1) : nullptr;
    const std::uint16_t* down = y + 1 < h ? labels.ptr<std::uint16_t>(y + 1) : nullptr;
    cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < w; ++x) {
      const int k = l[x];
      const double g = (d[x] || k == 0) ? grey[d[x]] : 128.0;  // a plane pixel without depth: mid grey
      if (k == 0) {
        o[x] = cv::Vec3b::all(static_cast<std::uint8_t>(g));
        continue;
      }
      const bool boundary =
          (x > 0 && l[x - 1] != k) || (x + 1 < w && l[x + 1] != k) || (up && up[x] != k) || (down && down[x] != k);
      if (!boundary) interior.at<std::uint8_t>(y, x) = 255;
      for (int c = 0; c < 3; ++c)
        o[x][c] = boundary ? static_cast<std::uint8_t>(0.4 * colour[k][c])
                           : cv::saturate_cast<std::uint8_t>(0.45 * g + 0.55 * colour[k][c]);
    }
  }

  // each id at its pixel farthest from any boundary or image border (a point inside even a split
  // or bent plane), its text kept inside the image
  interior.row(0).setTo(0);
  interior.row(h - 1).setTo(0);
  interior.col(0).setTo(0);
  interior.col(w - 1).setTo(0);
  cv::Mat dist;
  cv::distanceTransform(interior, dist, cv::DIST_L2, 3);
  std::vector<float> best(colour.size(), -1.f);
  std::vector<cv::Point> where(colour.size());
  for (int y = 0; y < h; ++y) {
    const std::uint16_t* l = labels.ptr<std::uint16_t>(y);
    const float* dd = dist.ptr<float>(y);
    for (int x = 0; x < w; ++x)
      if (l[x] && dd[x] > best[l[x]]) best[l[x]] = dd[x], where[l[x]] = {x, y};
  }
  const double font = std::clamp(std::min(w, h) / 1000.0, 0.35, 1.5);
  for (int k = 1; k <= max_id; ++k) {
    if (best[k] < 0.f) continue;
    const std::string text = std::to_string(k);
    int base = 0;
    const cv::Size sz = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, font, 1, &base);
    const cv::Point at(std::clamp(where[k].x - sz.width / 2, 1, std::max(1, w - sz.width - 1)),
                       std::clamp(where[k].y + sz.height / 2, sz.height + 1, std::max(sz.height + 1, h - 2)));
    cv::putText(out, text, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar::all(0), 3, cv::LINE_AA);
    cv::putText(out, text, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar::all(255), 1, cv::LINE_AA);
  }
  return out;
}

// ---- timing tables -----------------------------------------------------------------------------

struct stage_field {
  const char* name;
  double edgeplane::stage_times::*member;
};
/// The stages of edgeplane::stage_times in pipeline order, total last.
inline constexpr std::array<stage_field, 8> stage_fields{{
    {"preprocess", &edgeplane::stage_times::preprocess},
    {"edges", &edgeplane::stage_times::edges},
    {"segments", &edgeplane::stage_times::segments},
    {"candidates", &edgeplane::stage_times::candidates},
    {"validation", &edgeplane::stage_times::validation},
    {"merge", &edgeplane::stage_times::merge},
    {"finalize", &edgeplane::stage_times::finalize},
    {"total", &edgeplane::stage_times::total},
}};

/// "preprocess 1.23  edges 4.56 ... total 12.34" (milliseconds).
inline std::string format_stage_times(const edgeplane::stage_times& t) {
  std::string s;
  char buf[64];
  for (const stage_field& f : stage_fields) {
    std::snprintf(buf, sizeof buf, "%s%s %.2f", s.empty() ? "" : "  ", f.name, t.*f.member);
    s += buf;
  }
  return s;
}

/// The median of `v` (the mean of the two middle values for an even count); 0 when empty.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  const double hi = v[m];
  if (v.size() % 2) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m)));
}

}  // namespace edgeplane_examples
