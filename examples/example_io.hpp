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
//   - stage_fields, median: per-stage timing tables;
//   - load_label_png: an 8- or 16-bit single-channel label / mask PNG, checked like load_depth_png;
//   - json_value, parse_json, load_json_file: a small strict JSON reader for dataset metadata;
//   - read_file_bytes, natural_less, json_string: file reading, "scene_2 < scene_10" name ordering,
//     JSON string literals.
#pragma once
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <new>
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

/// Prints "PROGRAM: error: WHAT" on one line of stderr and returns the exit code 2.
inline int error_exit(const char* program, const std::string& what) {
  std::fflush(stdout);
  std::fprintf(stderr, "%s: error: %s\n", program, one_line(what).c_str());
  return 2;
}

/// Runs an example program's body: OpenCV's own logging silenced, and every exception turned into
/// one line on stderr with exit code 2 (never a crash).
template <class Body>
int guarded_main(const char* program, Body&& body) {
  try {
    quiet_opencv_logging();
    return body();
  } catch (const cli_error& e) {
    return error_exit(program, e.what());
  } catch (const edgeplane::error& e) {
    return error_exit(program, e.what());
  } catch (const edgeplane::backend_error& e) {
    return error_exit(program, e.what());
  } catch (const cv::Exception& e) {
    return error_exit(program, "OpenCV: " + e.msg);
  } catch (const std::bad_alloc&) {
    return error_exit(program, "out of memory");
  } catch (const std::exception& e) {
    return error_exit(program, e.what());
  } catch (...) {
    return error_exit(program, "unexpected exception");
  }
}

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

// ---- label and mask input ----------------------------------------------------------------------

/// The whole of a regular file as bytes; cli_error (naming `path`) when it is missing, a
/// directory, unreadable or empty.
inline std::vector<unsigned char> read_file_bytes(const std::string& path) {
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
  return bytes;
}

namespace detail {
/// What the IHDR chunk of a PNG says.
struct png_header {
  std::uint32_t width = 0, height = 0;
  int bit_depth = 0, colour_type = -1;
};

/// Checks the chunk structure of a PNG held in memory (signature, every chunk inside the file with
/// a correct CRC, IHDR first, IEND present, a usable size) and returns its header; any bit depth
/// and colour type.  Throws cli_error naming the problem.
inline png_header check_png_chunks(const std::vector<unsigned char>& b, const std::string& name) {
  static constexpr unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (b.size() < 8 || !std::equal(std::begin(signature), std::end(signature), b.begin()))
    fail("'" + name + "' is not a PNG file");
  std::size_t pos = 8;
  bool first = true, end_seen = false;
  png_header h;
  while (pos + 8 <= b.size()) {
    const std::uint32_t len = read_be32(&b[pos]);
    std::string type(reinterpret_cast<const char*>(&b[pos + 4]), 4);
    for (char& c : type)
      if (c < 0x21 || c > 0x7e) c = '?';
    if (len > 0x7fffffffu || len > b.size() - pos - 8 || b.size() - pos - 8 - len < 4)
      fail("'" + name + "' is truncated or corrupt (chunk '" + type + "' runs past the end of the file)");
    if (read_be32(&b[pos + 8 + len]) != png_crc(&b[pos + 4], len + 4))
      fail("'" + name + "' is corrupt (bad checksum in chunk '" + type + "')");
    if (first) {
      if (type != "IHDR" || len != 13) fail("'" + name + "' is corrupt (does not start with an IHDR chunk)");
      h.width = read_be32(&b[pos + 8]);
      h.height = read_be32(&b[pos + 12]);
      h.bit_depth = b[pos + 16];
      h.colour_type = b[pos + 17];
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
  if (h.width == 0 || h.height == 0 || h.width > 0x7fffffffu || h.height > 0x7fffffffu)
    fail("'" + name + "' has an invalid size " + std::to_string(h.width) + "x" + std::to_string(h.height));
  return h;
}
}  // namespace detail

/// Reads an 8- or 16-bit single-channel (greyscale) PNG of labels or mask codes and returns it as
/// CV_16UC1 (8-bit values are widened unchanged).  `what` names the image in messages ("ground
/// truth", "ignore mask").  Checked before it is decoded like load_depth_png; every problem throws
/// cli_error with a one-line message.
inline cv::Mat load_label_png(const std::string& path, const std::string& what = "label image") {
  const std::vector<unsigned char> bytes = read_file_bytes(path);
  const detail::png_header h = detail::check_png_chunks(bytes, path);
  if (h.colour_type != 0 || (h.bit_depth != 8 && h.bit_depth != 16))
    fail("'" + path + "' is a " + std::to_string(h.bit_depth) + "-bit " + detail::png_colour_name(h.colour_type) +
         " image; expected an 8- or 16-bit single-channel " + what);
  cv::Mat m;
  try {
    const detail::stderr_silencer quiet;
    m = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    fail("'" + path + "' could not be decoded: " + e.msg);
  }
  if (m.empty()) fail("'" + path + "' could not be decoded as a PNG image");
  if (m.channels() != 1 || (m.depth() != CV_8U && m.depth() != CV_16U))
    fail("'" + path + "' decoded to " + std::to_string(m.elemSize1() * 8) + "-bit data with " +
         std::to_string(m.channels()) + " channel(s); expected an 8- or 16-bit single-channel " + what);
  if (m.depth() == CV_8U) {
    cv::Mat wide;
    m.convertTo(wide, CV_16U);
    return wide;
  }
  return m;
}

// ---- JSON input --------------------------------------------------------------------------------

/// A parsed JSON value (RFC 8259).  Objects keep their members in file order; a repeated key is
/// an error.  Numbers are doubles.
struct json_value {
  enum class kind { null, boolean, number, string, array, object };
  kind type = kind::null;
  bool boolean = false;
  double number = 0;
  std::string text;                 ///< a string's value
  std::vector<json_value> items;    ///< an array's elements, or an object's member values
  std::vector<std::string> keys;    ///< an object's member names (parallel to items)

  bool is_object() const { return type == kind::object; }
  bool is_array() const { return type == kind::array; }
  bool is_number() const { return type == kind::number; }
  bool is_string() const { return type == kind::string; }
  /// The member `key` of an object, or nullptr (also when this is not an object).
  const json_value* find(std::string_view key) const {
    if (type != kind::object) return nullptr;
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] == key) return &items[i];
    return nullptr;
  }
};

namespace detail {
class json_parser {
 public:
  json_parser(std::string_view text, const std::string& name) : s_(text), name_(name) {}
  json_value parse_document() {
    json_value v = parse_value(0);
    skip_space();
    if (p_ != s_.size()) error("unexpected text after the JSON value");
    return v;
  }

 private:
  [[noreturn]] void error(const std::string& what) const {
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i < p_ && i < s_.size(); ++i) {
      if (s_[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    fail("'" + name_ + "' is not valid JSON: " + what + " at line " + std::to_string(line) + ", column " +
         std::to_string(col));
  }
  void skip_space() {
    while (p_ < s_.size() && (s_[p_] == ' ' || s_[p_] == '\t' || s_[p_] == '\n' || s_[p_] == '\r')) ++p_;
  }
  bool literal(std::string_view word) {
    if (s_.substr(p_, word.size()) != word) return false;
    p_ += word.size();
    return true;
  }
  static void append_utf8(std::string& out, std::uint32_t c) {
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if (c < 0x800) {
      out += static_cast<char>(0xc0 | (c >> 6));
      out += static_cast<char>(0x80 | (c & 0x3f));
    } else if (c < 0x10000) {
      out += static_cast<char>(0xe0 | (c >> 12));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3f));
      out += static_cast<char>(0x80 | (c & 0x3f));
    } else {
      out += static_cast<char>(0xf0 | (c >> 18));
      out += static_cast<char>(0x80 | ((c >> 12) & 0x3f));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3f));
      out += static_cast<char>(0x80 | (c & 0x3f));
    }
  }
  std::uint32_t hex4() {
    if (p_ + 4 > s_.size()) error("truncated \\u escape");
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) {
      const char c = s_[p_++];
      v <<= 4;
      if (c >= '0' && c <= '9') v |= static_cast<std::uint32_t>(c - '0');
      else if (c >= 'a' && c <= 'f') v |= static_cast<std::uint32_t>(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F') v |= static_cast<std::uint32_t>(c - 'A' + 10);
      else error("bad \\u escape");
    }
    return v;
  }
  std::string parse_string() {
    ++p_;  // the opening quote
    std::string out;
    while (true) {
      if (p_ >= s_.size()) error("unterminated string");
      const char c = s_[p_++];
      if (c == '"') return out;
      if (static_cast<unsigned char>(c) < 0x20) error("control character in a string");
      if (c != '\\') {
        out += c;
        continue;
      }
      if (p_ >= s_.size()) error("unterminated string");
      const char e = s_[p_++];
      switch (e) {
        case '"': out += '"'; break;
        case '\\': out += '\\'; break;
        case '/': out += '/'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          std::uint32_t cp = hex4();
          if (cp >= 0xd800 && cp < 0xdc00 && p_ + 1 < s_.size() && s_[p_] == '\\' && s_[p_ + 1] == 'u') {
            p_ += 2;
            const std::uint32_t lo = hex4();
            if (lo < 0xdc00 || lo >= 0xe000) error("bad surrogate pair");
            cp = 0x10000 + ((cp - 0xd800) << 10) + (lo - 0xdc00);
          }
          append_utf8(out, cp);
          break;
        }
        default: error("bad escape in a string");
      }
    }
  }
  double parse_number() {
    const std::size_t start = p_;
    if (p_ < s_.size() && s_[p_] == '-') ++p_;
    auto digits = [&] {
      const std::size_t d = p_;
      while (p_ < s_.size() && s_[p_] >= '0' && s_[p_] <= '9') ++p_;
      return p_ > d;
    };
    if (!digits()) error("bad number");
    if (p_ < s_.size() && s_[p_] == '.') {
      ++p_;
      if (!digits()) error("bad number");
    }
    if (p_ < s_.size() && (s_[p_] == 'e' || s_[p_] == 'E')) {
      ++p_;
      if (p_ < s_.size() && (s_[p_] == '+' || s_[p_] == '-')) ++p_;
      if (!digits()) error("bad number");
    }
    double v = 0;
    const auto [end, ec] = std::from_chars(s_.data() + start, s_.data() + p_, v);
    if (ec != std::errc{} || end != s_.data() + p_) error("number out of range");
    return v;
  }
  json_value parse_value(int depth) {
    if (depth > 256) error("nesting too deep");
    skip_space();
    if (p_ >= s_.size()) error("unexpected end of file");
    json_value v;
    const char c = s_[p_];
    if (c == '{') {
      v.type = json_value::kind::object;
      ++p_;
      skip_space();
      if (p_ < s_.size() && s_[p_] == '}') {
        ++p_;
        return v;
      }
      while (true) {
        skip_space();
        if (p_ >= s_.size() || s_[p_] != '"') error("expected a member name");
        std::string key = parse_string();
        if (v.find(key) != nullptr) error("member \"" + key + "\" given twice");
        skip_space();
        if (p_ >= s_.size() || s_[p_] != ':') error("expected ':'");
        ++p_;
        v.items.push_back(parse_value(depth + 1));
        v.keys.push_back(std::move(key));
        skip_space();
        if (p_ < s_.size() && s_[p_] == ',') {
          ++p_;
          continue;
        }
        if (p_ < s_.size() && s_[p_] == '}') {
          ++p_;
          return v;
        }
        error("expected ',' or '}'");
      }
    }
    if (c == '[') {
      v.type = json_value::kind::array;
      ++p_;
      skip_space();
      if (p_ < s_.size() && s_[p_] == ']') {
        ++p_;
        return v;
      }
      while (true) {
        v.items.push_back(parse_value(depth + 1));
        skip_space();
        if (p_ < s_.size() && s_[p_] == ',') {
          ++p_;
          continue;
        }
        if (p_ < s_.size() && s_[p_] == ']') {
          ++p_;
          return v;
        }
        error("expected ',' or ']'");
      }
    }
    if (c == '"') {
      v.type = json_value::kind::string;
      v.text = parse_string();
      return v;
    }
    if (literal("true")) {
      v.type = json_value::kind::boolean;
      v.boolean = true;
      return v;
    }
    if (literal("false")) {
      v.type = json_value::kind::boolean;
      return v;
    }
    if (literal("null")) return v;
    if (c == '-' || (c >= '0' && c <= '9')) {
      v.type = json_value::kind::number;
      v.number = parse_number();
      return v;
    }
    error("unexpected character");
  }

  std::string_view s_;
  std::string name_;
  std::size_t p_ = 0;
};
}  // namespace detail

/// Parses JSON text; `name` (a file name) appears in messages.  Throws cli_error with the line and
/// column of the first problem.
inline json_value parse_json(std::string_view text, const std::string& name) {
  return detail::json_parser(text, name).parse_document();
}

/// Reads and parses a JSON file; every problem throws cli_error naming `path`.
inline json_value load_json_file(const std::string& path) {
  const std::vector<unsigned char> bytes = read_file_bytes(path);
  return parse_json(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
}

/// The number at `key` of `object`, finite; cli_error naming `source` and `key` otherwise.
inline double json_number_at(const json_value& object, std::string_view key, const std::string& source) {
  const json_value* v = object.find(key);
  if (v == nullptr) fail("'" + source + "': missing \"" + std::string(key) + "\"");
  if (!v->is_number() || !std::isfinite(v->number))
    fail("'" + source + "': \"" + std::string(key) + "\" is not a finite number");
  return v->number;
}

// ---- names -------------------------------------------------------------------------------------

/// Orders names with their digit runs compared as numbers: "abw.test.3" < "abw.test.12".
inline bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      std::size_t i0 = i, j0 = j;
      while (i0 < a.size() && a[i0] == '0') ++i0;  // leading zeros do not make a number larger
      while (j0 < b.size() && b[j0] == '0') ++j0;
      std::size_t i1 = i0, j1 = j0;
      while (i1 < a.size() && digit(a[i1])) ++i1;
      while (j1 < b.size() && digit(b[j1])) ++j1;
      if (i1 - i0 != j1 - j0) return i1 - i0 < j1 - j0;
      const int c = a.compare(i0, i1 - i0, b, j0, j1 - j0);
      if (c != 0) return c < 0;
      if (i1 - i != j1 - j) return i1 - i < j1 - j;  // "01" after "1"
      i = i1;
      j = j1;
      continue;
    }
    if (a[i] != b[j]) return a[i] < b[j];
    ++i;
    ++j;
  }
  return a.size() - i < b.size() - j;
}

/// `text` as a JSON string literal, quotes included (control characters escaped).
inline std::string json_string(std::string_view text) {
  std::string s = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': s += "\\\""; break;
      case '\\': s += "\\\\"; break;
      case '\n': s += "\\n"; break;
      case '\r': s += "\\r"; break;
      case '\t': s += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          s += buf;
        } else {
          s += c;
        }
    }
  }
  return s + '"';
}

}  // namespace edgeplane_examples
