// edgeplane_segment: segments 16-bit depth PNGs into planes and writes a label image, the planes as
// JSON and a colour overlay; prints per-stage timings.  Run with --help for the usage.
//
// Exit status: 0 on success, 2 on any error (bad command line, unreadable or unsuitable input,
// an output that cannot be written, an argument the library rejects); the error is one line on
// stderr, "edgeplane_segment: error: ...".
#include <edgeplane/edgeplane.hpp>
#ifdef EDGEPLANE_WITH_CUDA
// The CUDA backend (edgeplane::cuda): a build that defines EDGEPLANE_WITH_CUDA compiles this file
// as CUDA and links edgeplane::cuda; compiled_backends() and run() below then offer "cuda".
#include <edgeplane/edgeplane.cuh>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <new>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "example_io.hpp"

namespace {

namespace ex = edgeplane_examples;
namespace fs = std::filesystem;

constexpr const char* program = "edgeplane_segment";

struct options {
  std::vector<std::string> inputs;
  float fx = std::numeric_limits<float>::quiet_NaN(), fy = fx, cx = fx, cy = fx, depth_scale = fx;
  bool have_fx = false, have_fy = false, have_cx = false, have_cy = false, have_scale = false;
  std::string preset = "thesis_full";
  std::string backend = "cpu";
  std::string labels_out, planes_out, overlay_out, out_dir;
  long repeat = 0;
  bool quiet = false;
};

/// Backends this build can run; `--backend` accepts these.
std::vector<std::string> compiled_backends() {
  std::vector<std::string> b{"cpu"};
#ifdef EDGEPLANE_WITH_CUDA
  b.push_back("cuda");
#endif
  return b;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

void print_usage() {
  std::printf(
      "usage: %s DEPTH.png [DEPTH2.png ...] --fx F --fy F --cx C --cy C --depth-scale M_PER_UNIT\n"
      "       [--preset NAME] [--backend NAME] [--labels-out L.png] [--planes-out P.json]\n"
      "       [--overlay-out O.png] [--out-dir DIR] [--repeat N] [--quiet]\n"
      "\n"
      "Segments 16-bit single-channel depth PNGs (0 = no depth) into planes.\n"
      "\n"
      "  --fx, --fy, --cx, --cy  pinhole intrinsics in pixels (fx, fy non-zero; fy may be negative)\n"
      "  --depth-scale M         metres per depth unit: 0.001 for millimetres, 0.0002 for TUM/ICL-NUIM\n"
      "  --preset NAME           thresholds: %s (default thesis_full)\n"
      "  --backend NAME          %s (default cpu)\n"
      "  --labels-out L.png      16-bit label image: 0 = no plane, k = plane id k   (one input only)\n"
      "  --planes-out P.json     the planes: id, normal, d, centroid, pixels, points,\n"
      "                          eigenvalues, bbox (metres, camera frame)           (one input only)\n"
      "  --overlay-out O.png     colour picture: depth as grey, planes in colour    (one input only)\n"
      "  --out-dir DIR           write DIR/<stem>_labels.png, DIR/<stem>_planes.json and\n"
      "                          DIR/<stem>_overlay.png for every input (DIR is created)\n"
      "  --repeat N              after the first call, segment each input N more times (file I/O\n"
      "                          excluded) and print the median/min/max of the total and the\n"
      "                          median of each stage, in milliseconds per frame\n"
      "  --quiet                 print only errors and the --repeat summaries\n"
      "  --help, -h              print this help\n"
      "\n"
      "Options may also be written --name=value.  Without output options nothing is written; the\n"
      "per-stage timings are printed.  Exit status: 0 on success, 2 on any error.\n",
      program, joined(edgeplane::presets::preset_names()).c_str(), joined(compiled_backends()).c_str());
}

void require_focal(float v, bool given, const char* name) {
  if (!given) ex::fail(std::string("missing ") + name + " (intrinsics in pixels are required)");
  if (!std::isfinite(v) || v == 0.f) ex::fail(std::string(name) + " must be finite and non-zero");
}
void require_centre(float v, bool given, const char* name) {
  if (!given) ex::fail(std::string("missing ") + name + " (intrinsics in pixels are required)");
  if (!std::isfinite(v)) ex::fail(std::string(name) + " must be finite");
}

/// --help (or -h) anywhere before a bare "--".
bool wants_help(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--") return false;
    if (a == "--help" || a == "-h") return true;
  }
  return false;
}

/// Parses and checks the command line.
void parse(int argc, char** argv, options& o) {
  ex::arg_cursor a(argc, argv);
  auto number = [&](float& dst, bool& given) {
    const std::string name = a.name();
    dst = ex::parse_float(a.value(), name);
    given = true;
  };
  while (a.next()) {
    if (!a.is_option()) {
      o.inputs.push_back(a.name());
      continue;
    }
    const std::string& n = a.name();
    if (n == "--fx") {
      number(o.fx, o.have_fx);
    } else if (n == "--fy") {
      number(o.fy, o.have_fy);
    } else if (n == "--cx") {
      number(o.cx, o.have_cx);
    } else if (n == "--cy") {
      number(o.cy, o.have_cy);
    } else if (n == "--depth-scale") {
      number(o.depth_scale, o.have_scale);
    } else if (n == "--preset") {
      o.preset = a.value();
    } else if (n == "--backend") {
      o.backend = a.value();
    } else if (n == "--labels-out") {
      o.labels_out = a.value();
    } else if (n == "--planes-out") {
      o.planes_out = a.value();
    } else if (n == "--overlay-out") {
      o.overlay_out = a.value();
    } else if (n == "--out-dir") {
      o.out_dir = a.value();
    } else if (n == "--repeat") {
      o.repeat = ex::parse_int(a.value(), "--repeat", 1, 1000000);
    } else if (n == "--quiet") {
      a.no_value();
      o.quiet = true;
    } else {
      ex::fail("unknown option '" + n + "' (see --help)");
    }
  }

  if (o.inputs.empty()) ex::fail("no input depth PNG given (see --help)");
  for (const auto& in : o.inputs) {  // before any work; the contents are checked when each is read
    std::error_code ec;
    if (!fs::exists(in, ec)) ex::fail("cannot read '" + in + "': no such file");
  }
  require_focal(o.fx, o.have_fx, "--fx");
  require_focal(o.fy, o.have_fy, "--fy");
  require_centre(o.cx, o.have_cx, "--cx");
  require_centre(o.cy, o.have_cy, "--cy");
  if (!o.have_scale) ex::fail("missing --depth-scale (metres per depth unit, e.g. 0.001 for millimetres)");
  if (!std::isfinite(o.depth_scale) || o.depth_scale <= 0.f)
    ex::fail("--depth-scale must be positive and finite (metres per depth unit)");

  (void)edgeplane::preset(o.preset);  // throws edgeplane::error listing the known names
  const auto backends = compiled_backends();
  if (std::find(backends.begin(), backends.end(), o.backend) == backends.end()) {
    if (o.backend == "cuda") ex::fail("this build has no CUDA backend (known: " + joined(backends) + ")");
    ex::fail("unknown backend '" + o.backend + "' (known: " + joined(backends) + ")");
  }

  const bool named = !o.labels_out.empty() || !o.planes_out.empty() || !o.overlay_out.empty();
  if (named && o.inputs.size() > 1)
    ex::fail("--labels-out, --planes-out and --overlay-out name one file each; with several inputs use --out-dir");
  if (!o.out_dir.empty() && o.inputs.size() > 1) {
    std::set<std::string> stems;
    for (const auto& in : o.inputs)
      if (!stems.insert(fs::path(in).stem().string()).second)
        ex::fail("two inputs have the file name stem '" + fs::path(in).stem().string() +
                 "': their outputs in --out-dir would overwrite each other");
  }
}

struct output_paths {
  std::string labels, planes, overlay;
};

/// Explicit names win (one input only); --out-dir fills in the rest as DIR/<stem>_*.
output_paths outputs_for(const options& o, const std::string& input) {
  output_paths p{o.labels_out, o.planes_out, o.overlay_out};
  if (!o.out_dir.empty()) {
    const std::string stem = fs::path(input).stem().string();
    const fs::path dir(o.out_dir);
    if (p.labels.empty()) p.labels = (dir / (stem + "_labels.png")).string();
    if (p.planes.empty()) p.planes = (dir / (stem + "_planes.json")).string();
    if (p.overlay.empty()) p.overlay = (dir / (stem + "_overlay.png")).string();
  }
  return p;
}

void print_repeat_summary(const std::string& what, const std::vector<edgeplane::stage_times>& runs) {
  std::vector<double> total;
  for (const auto& t : runs) total.push_back(t.total);
  std::printf("  %s: %zu runs, total median %.2f ms, min %.2f ms, max %.2f ms per frame\n", what.c_str(), runs.size(),
              ex::median(total), *std::min_element(total.begin(), total.end()),
              *std::max_element(total.begin(), total.end()));
  std::string medians;
  for (const ex::stage_field& f : ex::stage_fields) {
    std::vector<double> v;
    for (const auto& t : runs) v.push_back(t.*f.member);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%s %.2f", medians.empty() ? "" : "  ", f.name, ex::median(v));
    medians += buf;
  }
  std::printf("    stage medians (ms): %s\n", medians.c_str());
}

/// Segments every input with one segmenter on `backend`.  Depth and labels stay in host memory:
/// the segmenter copies to and from its backend.
template <class Backend>
int run_backend(const options& o, Backend backend) {
  const edgeplane::intrinsics k{o.fx, o.fy, o.cx, o.cy};
  edgeplane::segmenter<Backend> seg(edgeplane::preset(o.preset), backend);
  edgeplane::segmentation_result result;  // reused: no allocation per frame in steady state
  const bool progress = o.inputs.size() > 1 || !o.out_dir.empty();
  std::vector<edgeplane::stage_times> all_runs;

  if (!o.out_dir.empty()) {
    std::error_code ec;
    fs::create_directories(o.out_dir, ec);
    if (ec || !fs::is_directory(o.out_dir))
      ex::fail("cannot create output directory '" + o.out_dir + "'" + (ec ? ": " + ec.message() : ""));
  }

  for (std::size_t i = 0; i < o.inputs.size(); ++i) {
    const std::string& input = o.inputs[i];
    const cv::Mat depth = ex::load_depth_png(input);
    cv::Mat labels(depth.rows, depth.cols, CV_16UC1);
    const auto depth_view =
        edgeplane::make_view(depth.ptr<const std::uint16_t>(), depth.cols, depth.rows, depth.step1());
    const auto labels_view =
        edgeplane::make_view(labels.ptr<std::uint16_t>(), labels.cols, labels.rows, labels.step1());

    seg.segment(depth_view, o.depth_scale, k, labels_view, result);

    const output_paths out = outputs_for(o, input);
    if (!out.labels.empty()) ex::write_png(out.labels, labels);
    if (!out.planes.empty()) ex::write_planes_json(out.planes, result.planes);
    if (!out.overlay.empty()) ex::write_png(out.overlay, ex::render_overlay(depth, labels));

    const std::string name = fs::path(input).filename().string();
    if (!o.quiet) {
      if (progress) std::printf("[%zu/%zu] ", i + 1, o.inputs.size());
      std::printf("%s: %zu plane%s, %.1f ms\n", name.c_str(), result.planes.size(),
                  result.planes.size() == 1 ? "" : "s", result.times.total);
      std::printf("  %dx%d, preset %s, backend %s: %d candidates, %d valid candidates, %zu planes\n", depth.cols,
                  depth.rows, o.preset.c_str(), o.backend.c_str(), result.candidates, result.valid_candidates,
                  result.planes.size());
      std::printf("  stages (ms): %s\n", ex::format_stage_times(result.times).c_str());
      for (const std::string* f : {&out.labels, &out.planes, &out.overlay})
        if (!f->empty()) std::printf("  wrote %s\n", f->c_str());
    }

    if (o.repeat > 0) {
      // The call above was the warm-up (scratch memory sized, caches and thread pool warm).
      std::vector<edgeplane::stage_times> runs;
      runs.reserve(static_cast<std::size_t>(o.repeat));
      for (long r = 0; r < o.repeat; ++r) {
        seg.segment(depth_view, o.depth_scale, k, labels_view, result);
        runs.push_back(result.times);
      }
      if (o.quiet && progress) std::printf("[%zu/%zu] ", i + 1, o.inputs.size());
      if (o.quiet) std::printf("%s\n", name.c_str());
      print_repeat_summary("repeat", runs);
      all_runs.insert(all_runs.end(), runs.begin(), runs.end());
    }
    std::fflush(stdout);
  }

  if (o.repeat > 0 && o.inputs.size() > 1) {
    std::printf("all %zu inputs\n", o.inputs.size());
    print_repeat_summary("repeat", all_runs);
  }
  return 0;
}

int run(const options& o) {
  if (o.backend == "cpu") return run_backend(o, edgeplane::cpu{});
#ifdef EDGEPLANE_WITH_CUDA
  if (o.backend == "cuda") return run_backend(o, edgeplane::cuda{});
#endif
  ex::fail("unknown backend '" + o.backend + "'");  // parse() already checked
}

}  // namespace

int main(int argc, char** argv) {
  return ex::guarded_main(program, [&] {
    if (wants_help(argc, argv)) {
      print_usage();
      return 0;
    }
    options o;
    parse(argc, argv, o);
    return run(o);
  });
}
