// edgeplane_evaluate: segments every image of a labelled dataset folder and scores the result with
// every figure of EVALUATION.md (edgeplane::metrics): D2MC, the thesis SSIM, SegComp at T = 0.8
// with the mean normal angle of correct detections, plane precision / recall / mean IoU / mean
// angle.  Prints a per-image table, the averages over the set and a final one-line JSON summary.
// Run with --help for the usage.
//
// Layouts (detected from the files present, or named with --layout):
//   synthetic  DIR/STEM_depth.png (uint16), STEM_gt.png, STEM_ignore.png (0 = scored) and
//              STEM.json (camera intrinsics, depth_scale_m_per_unit, GT plane equations);
//   abw        DIR/depth/NAME.png (uint16, 0.1 mm per unit), DIR/gt/NAME.png (8-bit, >= 10 = a
//              plane), DIR/intrinsics.json (calibrations and which image uses which).  ABW has
//              no plane equations: each GT plane is fitted to its pixels' back-projected points.
//
// Exit status: 0 on success, 2 on any error (bad command line, a folder that is not a dataset,
// a missing or unusable file, a parameter the library rejects); the error is one line on stderr,
// "edgeplane_evaluate: error: ...".
#include <edgeplane/edgeplane.hpp>
#include <edgeplane/metrics.hpp>
#ifdef EDGEPLANE_WITH_CUDA
#include <edgeplane/edgeplane.cuh>
#endif

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <variant>
#include <vector>

#include "example_io.hpp"
#ifdef EDGEPLANE_WITH_PCL
#include <chrono>

#include "pcl_peer.hpp"  // benchmarks/: the PCL peer (edgeplane_evaluate_pcl, built when PCL is found)
#endif
#ifdef EDGEPLANE_WITH_CAPE
#include <chrono>

#include "cape_peer.hpp"  // benchmarks/: the CAPE peer (edgeplane_evaluate_cape, built with EDGEPLANE_CAPE_DIR)
#endif

namespace {

namespace ex = edgeplane_examples;
namespace em = edgeplane::metrics;
namespace fs = std::filesystem;

constexpr const char* program = "edgeplane_evaluate";
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// ---- --set: every field of edgeplane::params by name ----------------------------------------------

using param_member = std::variant<int edgeplane::params::*, float edgeplane::params::*, bool edgeplane::params::*,
                                  float edgeplane::noise_model::*>;
struct param_field {
  const char* name;
  param_member member;
};

#define EDGEPLANE_PARAM(name) param_field{#name, &edgeplane::params::name}
#define EDGEPLANE_NOISE_PARAM(name) param_field{#name, &edgeplane::noise_model::name}
const std::vector<param_field>& param_fields() {
  static const std::vector<param_field> fields{
      EDGEPLANE_PARAM(depth_closing_radius), EDGEPLANE_PARAM(downscale), EDGEPLANE_PARAM(min_depth),
      EDGEPLANE_PARAM(max_depth), EDGEPLANE_NOISE_PARAM(sigma0), EDGEPLANE_NOISE_PARAM(sigma2),
      EDGEPLANE_PARAM(smooth_radius), EDGEPLANE_PARAM(smooth_k), EDGEPLANE_PARAM(use_jump), EDGEPLANE_PARAM(t_je),
      EDGEPLANE_PARAM(t_je_quad), EDGEPLANE_PARAM(t_je_ratio), EDGEPLANE_PARAM(adjacency_slope),
      EDGEPLANE_PARAM(use_extrema), EDGEPLANE_PARAM(t_ee), EDGEPLANE_PARAM(n_ee), EDGEPLANE_PARAM(use_corner),
      EDGEPLANE_PARAM(t_coe), EDGEPLANE_PARAM(t_coe_arm), EDGEPLANE_PARAM(n_coe), EDGEPLANE_PARAM(use_curved),
      EDGEPLANE_PARAM(t_cue1), EDGEPLANE_PARAM(t_cue2), EDGEPLANE_PARAM(n_cue), EDGEPLANE_PARAM(noise_k),
      EDGEPLANE_PARAM(edge_closing_radius), EDGEPLANE_PARAM(t_length), EDGEPLANE_PARAM(t_line),
      EDGEPLANE_PARAM(max_run_splits), EDGEPLANE_PARAM(t_size), EDGEPLANE_PARAM(t_cu), EDGEPLANE_PARAM(t_residual),
      EDGEPLANE_PARAM(split_rounds), EDGEPLANE_PARAM(split_erode), EDGEPLANE_PARAM(t_par), EDGEPLANE_PARAM(t_ps),
      EDGEPLANE_PARAM(grow_iterations), EDGEPLANE_PARAM(grow_sweeps), EDGEPLANE_PARAM(grow_k), EDGEPLANE_PARAM(label_closing_radius),
      EDGEPLANE_PARAM(split_regions), EDGEPLANE_PARAM(min_region_pixels),
  };
  return fields;
}
#undef EDGEPLANE_PARAM
#undef EDGEPLANE_NOISE_PARAM

// The table above must name every field: count the fields of the aggregates (a value convertible
// to anything initialises one member; brace elision never applies to it).
struct any_value {
  template <class T>
  operator T() const;  // never defined: only used in unevaluated requires-expressions
};
template <class T, class... A>
consteval std::size_t aggregate_fields() {
  if constexpr (requires { T{A{}..., any_value{}}; })
    return aggregate_fields<T, A..., any_value>();
  else
    return sizeof...(A);
}
static_assert(aggregate_fields<edgeplane::params>() == 41 && aggregate_fields<edgeplane::noise_model>() == 2,
              "edgeplane::params changed: add its new fields to param_fields() in edgeplane_evaluate.cpp (so that "
              "--set reaches every field) and update the counts here");

/// Looks a --set key up: the field name, or "noise.sigma0" / "noise.sigma2" for sigma0 / sigma2.
const param_field* find_param(std::string_view key) {
  if (key.starts_with("noise.")) key.remove_prefix(6);
  for (const param_field& f : param_fields())
    if (key == f.name) return &f;
  return nullptr;
}

std::string param_names() {
  std::string s;
  for (const param_field& f : param_fields()) s += (s.empty() ? "" : ", ") + std::string(f.name);
  return s;
}

/// Applies "key=value" to `p`: ints must be whole numbers, bools 0/1/true/false, floats any
/// number.  Ranges are checked afterwards by edgeplane::validate().
void apply_setting(edgeplane::params& p, const std::string& setting) {
  const auto eq = setting.find('=');
  if (eq == std::string::npos || eq == 0) ex::fail("--set expects key=value (got '" + setting + "')");
  const std::string key = setting.substr(0, eq), value = setting.substr(eq + 1);
  const param_field* f = find_param(key);
  if (f == nullptr) ex::fail("--set: unknown parameter '" + key + "' (known: " + param_names() + ")");
  const std::string what = "--set " + key;
  std::visit(
      [&](auto member) {
        using M = decltype(member);
        if constexpr (std::is_same_v<M, int edgeplane::params::*>) {
          p.*member = static_cast<int>(ex::parse_int(value, what, std::numeric_limits<int>::min(),
                                                     std::numeric_limits<int>::max()));
        } else if constexpr (std::is_same_v<M, float edgeplane::params::*>) {
          p.*member = ex::parse_float(value, what);
        } else if constexpr (std::is_same_v<M, bool edgeplane::params::*>) {
          if (value == "1" || value == "true") {
            p.*member = true;
          } else if (value == "0" || value == "false") {
            p.*member = false;
          } else {
            ex::fail(what + ": '" + value + "' is not a boolean (0, 1, true or false)");
          }
        } else {
          p.noise.*member = ex::parse_float(value, what);
        }
      },
      f->member);
}

std::string format_param(const edgeplane::params& p, const param_field& f) {
  char buf[64];
  std::visit(
      [&](auto member) {
        using M = decltype(member);
        if constexpr (std::is_same_v<M, int edgeplane::params::*>)
          std::snprintf(buf, sizeof buf, "%d", p.*member);
        else if constexpr (std::is_same_v<M, float edgeplane::params::*>)
          std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(p.*member));
        else if constexpr (std::is_same_v<M, bool edgeplane::params::*>)
          std::snprintf(buf, sizeof buf, "%d", p.*member ? 1 : 0);
        else
          std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(p.noise.*member));
      },
      f.member);
  return buf;
}

// ---- command line -----------------------------------------------------------------------------------

struct options {
  std::string dataset;
  std::string layout = "auto";
  std::string preset = "thesis_full";
  std::string backend = "cpu";
  std::vector<std::string> settings;
  long limit = 0;  // 0 = all
  std::string save_dir;
  bool quiet = false;
  bool list_params = false;
};

std::vector<std::string> compiled_backends() {
  std::vector<std::string> b{"cpu"};
#ifdef EDGEPLANE_WITH_CUDA
  b.push_back("cuda");
#endif
#ifdef EDGEPLANE_WITH_PCL
  b.push_back("pcl");  // the peer, PCL's organized multi-plane segmentation (presets do not apply)
#endif
#ifdef EDGEPLANE_WITH_CAPE
  b.push_back("cape");  // the peer CAPE (Proenca and Gao 2018), planes only (presets do not apply)
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
      "usage: %s DATASET_DIR [--layout auto|synthetic|abw] [--preset NAME] [--backend NAME]\n"
      "       [--set key=value ...] [--limit N] [--save-dir DIR] [--quiet] [--list-params]\n"
      "\n"
      "Segments every image of a labelled dataset folder and scores it as EVALUATION.md does:\n"
      "D2MC, SSIM, SegComp (T = 0.8: correct, over, under, missed, noise, and the mean normal\n"
      "angle of the correct detections), plane precision / recall / mean IoU at IoU >= 0.5.\n"
      "\n"
      "  DATASET_DIR             synthetic layout: STEM_depth.png, STEM_gt.png, STEM_ignore.png and\n"
      "                          STEM.json (intrinsics, depth scale, GT plane equations) per image;\n"
      "                          abw layout: depth/*.png (0.1 mm per unit), gt/*.png (>= 10 = plane)\n"
      "                          and intrinsics.json (per-image calibration)\n"
      "  --layout NAME           auto (default: from the files present), synthetic or abw\n"
      "  --preset NAME           thresholds: %s (default thesis_full)\n"
      "  --backend NAME          %s (default cpu)\n"
      "  --set key=value         override one field of edgeplane::params (repeatable); keys are the\n"
      "                          field names (sigma0, sigma2 or noise.sigma0, noise.sigma2 for the\n"
      "                          noise model); booleans take 0/1/true/false\n"
      "  --limit N               only the first N images (in natural name order)\n"
      "  --save-dir DIR          write each predicted label image as DIR/<name>_labels.png (16-bit;\n"
      "                          DIR is created)\n"
      "  --quiet                 print only the final JSON line (and errors)\n"
      "  --list-params           print every parameter of the preset (after --set) and exit\n"
      "  --help, -h              print this help\n"
      "\n"
      "Output: one table row per image, the averages over the set, then one JSON line with the\n"
      "averages.  Counts, D2MC and SSIM are means per image; the angles are pooled over all pairs\n"
      "of the set; precision, recall and mean IoU are pooled (sum of matches over sum of segments,\n"
      "of GT planes; IoU averaged over all matches).  ms_per_frame is the mean segmentation time\n"
      "(first frame included).  ABW GT plane equations are fitted to the GT pixels' points (they\n"
      "are not in the data set).  Progress goes to stderr.\n"
      "Exit status: 0 on success, 2 on any error.\n",
      program, joined(edgeplane::presets::preset_names()).c_str(), joined(compiled_backends()).c_str());
}

bool wants_help(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--") return false;
    if (a == "--help" || a == "-h") return true;
  }
  return false;
}

void parse(int argc, char** argv, options& o) {
  ex::arg_cursor a(argc, argv);
  std::vector<std::string> positional;
  while (a.next()) {
    if (!a.is_option()) {
      positional.push_back(a.name());
      continue;
    }
    const std::string& n = a.name();
    if (n == "--layout") {
      o.layout = a.value();
    } else if (n == "--preset") {
      o.preset = a.value();
    } else if (n == "--backend") {
      o.backend = a.value();
    } else if (n == "--set") {
      o.settings.push_back(a.value());
    } else if (n == "--limit") {
      o.limit = ex::parse_int(a.value(), "--limit", 1, 1000000000);
    } else if (n == "--save-dir") {
      o.save_dir = a.value();
      if (o.save_dir.empty()) ex::fail("--save-dir needs a folder name");
    } else if (n == "--quiet") {
      a.no_value();
      o.quiet = true;
    } else if (n == "--list-params") {
      a.no_value();
      o.list_params = true;
    } else {
      ex::fail("unknown option '" + n + "' (see --help)");
    }
  }
  if (o.layout != "auto" && o.layout != "synthetic" && o.layout != "abw")
    ex::fail("unknown layout '" + o.layout + "' (known: auto, synthetic, abw)");
  (void)edgeplane::preset(o.preset);  // throws edgeplane::error listing the known names
  const auto backends = compiled_backends();
  if (std::find(backends.begin(), backends.end(), o.backend) == backends.end()) {
    if (o.backend == "cuda") ex::fail("this build has no CUDA backend (known: " + joined(backends) + ")");
    ex::fail("unknown backend '" + o.backend + "' (known: " + joined(backends) + ")");
  }
  if (o.list_params && positional.empty()) return;  // --list-params needs no data set
  if (positional.empty()) ex::fail("no DATASET_DIR given (see --help)");
  if (positional.size() > 1) ex::fail("one DATASET_DIR expected, got " + std::to_string(positional.size()));
  o.dataset = positional.front();
}

/// The preset with every --set applied, validated (edgeplane::error names a value out of range).
edgeplane::params make_params(const options& o) {
  edgeplane::params p = edgeplane::preset(o.preset);
  for (const std::string& s : o.settings) apply_setting(p, s);
  edgeplane::validate(p);
  return p;
}

// ---- data sets --------------------------------------------------------------------------------------

enum class layout_kind { synthetic, abw };

struct frame {
  std::string name;  // scene stem or ABW image name
  std::string depth, gt, ignore, json;
  edgeplane::intrinsics k{};  // abw: from intrinsics.json
};

struct dataset {
  layout_kind layout = layout_kind::synthetic;
  std::string dir;
  float abw_scale = 1e-4f;  // metres per depth unit
  std::vector<frame> frames;
};

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}
bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

/// File names in `dir` ending in `suffix`, with the suffix removed, in natural order.
std::vector<std::string> stems_with_suffix(const fs::path& dir, std::string_view suffix) {
  std::vector<std::string> stems;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string f = it->path().filename().string();
    if (f.size() > suffix.size() && f.ends_with(suffix) && is_file(it->path()))
      stems.push_back(f.substr(0, f.size() - suffix.size()));
  }
  if (ec) ex::fail("cannot list '" + dir.string() + "': " + ec.message());
  std::sort(stems.begin(), stems.end(), ex::natural_less);
  return stems;
}

bool looks_like_abw(const fs::path& d) {
  return is_file(d / "intrinsics.json") && is_dir(d / "depth") && is_dir(d / "gt");
}
bool looks_like_synthetic(const fs::path& d) { return !stems_with_suffix(d, "_depth.png").empty(); }

void scan_synthetic(dataset& ds) {
  const fs::path d(ds.dir);
  const std::vector<std::string> stems = stems_with_suffix(d, "_depth.png");
  if (stems.empty()) ex::fail("'" + ds.dir + "' has no *_depth.png files (synthetic layout)");
  for (const std::string& s : stems) {
    frame f;
    f.name = s;
    f.depth = (d / (s + "_depth.png")).string();
    f.gt = (d / (s + "_gt.png")).string();
    f.ignore = (d / (s + "_ignore.png")).string();
    f.json = (d / (s + ".json")).string();
    for (const std::string* p : {&f.gt, &f.ignore, &f.json})
      if (!is_file(*p)) ex::fail("'" + *p + "' is missing (needed for " + s + "_depth.png)");
    ds.frames.push_back(std::move(f));
  }
}

/// The calibration `index` of intrinsics.json: the member of "calibrations" named "cal<index>" or
/// "cal<index> (...)".
const ex::json_value* find_calibration(const ex::json_value& cals, long index) {
  const std::string want = "cal" + std::to_string(index);
  for (std::size_t i = 0; i < cals.keys.size(); ++i) {
    const std::string& key = cals.keys[i];
    if (key == want || (key.starts_with(want) && (key[want.size()] < '0' || key[want.size()] > '9')))
      return &cals.items[i];
  }
  return nullptr;
}

void scan_abw(dataset& ds) {
  const fs::path d(ds.dir);
  const std::string json_path = (d / "intrinsics.json").string();
  if (!is_file(json_path)) ex::fail("'" + json_path + "' is missing (abw layout)");
  if (!is_dir(d / "depth")) ex::fail("'" + (d / "depth").string() + "' is missing (abw layout)");
  if (!is_dir(d / "gt")) ex::fail("'" + (d / "gt").string() + "' is missing (abw layout)");
  const ex::json_value j = ex::load_json_file(json_path);
  if (!j.is_object()) ex::fail("'" + json_path + "': expected a JSON object");
  // The depth scale: metres per unit if given so; the ABW file gives units per metre.
  if (j.find("depth_scale_m_per_unit") != nullptr) {
    ds.abw_scale = static_cast<float>(ex::json_number_at(j, "depth_scale_m_per_unit", json_path));
  } else if (j.find("depth_scale_per_unit") != nullptr) {
    const double units_per_metre = ex::json_number_at(j, "depth_scale_per_unit", json_path);
    if (!(units_per_metre > 0)) ex::fail("'" + json_path + "': depth_scale_per_unit must be positive");
    ds.abw_scale = static_cast<float>(1.0 / units_per_metre);
  }
  if (!(ds.abw_scale > 0.f) || !std::isfinite(ds.abw_scale)) ex::fail("'" + json_path + "': bad depth scale");
  const ex::json_value* cals = j.find("calibrations");
  if (cals == nullptr || !cals->is_object() || cals->items.empty())
    ex::fail("'" + json_path + "': missing \"calibrations\" object");
  const ex::json_value* per_image = j.find("per_image_calibration");
  // Images not listed use the calibration whose name says "all other images", if there is one.
  const ex::json_value* fallback = nullptr;
  for (std::size_t i = 0; i < cals->keys.size(); ++i)
    if (cals->keys[i].find("all other images") != std::string::npos) fallback = &cals->items[i];

  const std::vector<std::string> stems = stems_with_suffix(d / "depth", ".png");
  if (stems.empty()) ex::fail("'" + (d / "depth").string() + "' has no .png files (abw layout)");
  for (const std::string& s : stems) {
    frame f;
    f.name = s;
    f.depth = (d / "depth" / (s + ".png")).string();
    f.gt = (d / "gt" / (s + ".png")).string();
    if (!is_file(f.gt)) ex::fail("'" + f.gt + "' is missing (needed for " + f.depth + ")");
    const ex::json_value* cal = fallback;
    if (const ex::json_value* idx = per_image != nullptr ? per_image->find(s) : nullptr) {
      if (!idx->is_number() || idx->number != std::floor(idx->number))
        ex::fail("'" + json_path + "': per_image_calibration of " + s + " is not an integer");
      cal = find_calibration(*cals, static_cast<long>(idx->number));
      if (cal == nullptr)
        ex::fail("'" + json_path + "': calibration " + std::to_string(static_cast<long>(idx->number)) + " of " + s +
                 " is not in \"calibrations\"");
    }
    if (cal == nullptr) ex::fail("'" + json_path + "' names no calibration for " + s);
    if (!cal->is_object()) ex::fail("'" + json_path + "': a calibration is not an object");
    f.k = {static_cast<float>(ex::json_number_at(*cal, "fx", json_path)),
           static_cast<float>(ex::json_number_at(*cal, "fy", json_path)),
           static_cast<float>(ex::json_number_at(*cal, "cx", json_path)),
           static_cast<float>(ex::json_number_at(*cal, "cy", json_path))};
    ds.frames.push_back(std::move(f));
  }
}

dataset scan_dataset(const options& o) {
  dataset ds;
  ds.dir = o.dataset;
  std::error_code ec;
  if (!fs::exists(o.dataset, ec)) ex::fail("cannot read '" + o.dataset + "': no such folder");
  if (!is_dir(o.dataset)) ex::fail("'" + o.dataset + "' is not a folder");
  const fs::path d(o.dataset);
  if (o.layout == "abw") {
    ds.layout = layout_kind::abw;
  } else if (o.layout == "synthetic") {
    ds.layout = layout_kind::synthetic;
  } else if (looks_like_abw(d)) {
    ds.layout = layout_kind::abw;
  } else if (looks_like_synthetic(d)) {
    ds.layout = layout_kind::synthetic;
  } else {
    ex::fail("'" + o.dataset +
             "' is not a dataset folder: expected STEM_depth.png files (synthetic layout) or "
             "intrinsics.json, depth/ and gt/ (abw layout)");
  }
  if (ds.layout == layout_kind::abw)
    scan_abw(ds);
  else
    scan_synthetic(ds);
  if (o.limit > 0 && static_cast<long>(ds.frames.size()) > o.limit) ds.frames.resize(static_cast<std::size_t>(o.limit));
  return ds;
}

/// Synthetic STEM.json: intrinsics, depth scale and the GT plane equations.
void read_scene_json(const std::string& path, edgeplane::intrinsics& k, float& scale,
                     std::vector<em::plane_equation>& planes) {
  const ex::json_value j = ex::load_json_file(path);
  if (!j.is_object()) ex::fail("'" + path + "': expected a JSON object");
  const ex::json_value* cam = j.find("camera");
  if (cam == nullptr || !cam->is_object()) ex::fail("'" + path + "': missing \"camera\" object");
  k = {static_cast<float>(ex::json_number_at(*cam, "fx", path)), static_cast<float>(ex::json_number_at(*cam, "fy", path)),
       static_cast<float>(ex::json_number_at(*cam, "cx", path)), static_cast<float>(ex::json_number_at(*cam, "cy", path))};
  scale = static_cast<float>(ex::json_number_at(j, "depth_scale_m_per_unit", path));
  if (!(scale > 0.f) || !std::isfinite(scale)) ex::fail("'" + path + "': depth_scale_m_per_unit must be positive");
  planes.clear();
  const ex::json_value* list = j.find("planes");
  if (list == nullptr || !list->is_array()) ex::fail("'" + path + "': missing \"planes\" array");
  for (const ex::json_value& p : list->items) {
    if (!p.is_object()) ex::fail("'" + path + "': a plane is not an object");
    const double id = ex::json_number_at(p, "id", path);
    if (id < 1 || id > 65535 || id != std::floor(id)) ex::fail("'" + path + "': a plane id is not in 1..65535");
    const ex::json_value* n = p.find("normal");
    if (n == nullptr || !n->is_array() || n->items.size() != 3 ||
        !std::all_of(n->items.begin(), n->items.end(), [](const ex::json_value& v) { return v.is_number(); }))
      ex::fail("'" + path + "': plane " + std::to_string(static_cast<int>(id)) + " has no 3-number \"normal\"");
    em::plane_equation e;
    e.id = static_cast<std::uint16_t>(id);
    e.normal = {n->items[0].number, n->items[1].number, n->items[2].number};
    e.d = ex::json_number_at(p, "d", path);
    planes.push_back(e);
  }
}

/// ABW: the plane of each GT region (value >= 10) fitted to its pixels' points (total least
/// squares), then refitted without points farther than 3 robust sigmas (at least 0.5 mm) from the
/// first fit.  Normals point toward the camera (d >= 0).
std::vector<em::plane_equation> fit_abw_gt_planes(const cv::Mat& depth, const cv::Mat& gt, float scale,
                                                  const edgeplane::intrinsics& k) {
  std::vector<std::vector<Eigen::Vector3d>> points(65536);
  for (int y = 0; y < depth.rows; ++y) {
    const std::uint16_t* d = depth.ptr<std::uint16_t>(y);
    const std::uint16_t* g = gt.ptr<std::uint16_t>(y);
    for (int x = 0; x < depth.cols; ++x) {
      if (g[x] < em::abw_first_plane_label || d[x] == 0) continue;
      const double z = static_cast<double>(d[x]) * scale;
      points[g[x]].emplace_back((x - k.cx) * z / k.fx, (y - k.cy) * z / k.fy, z);
    }
  }
  auto fit = [](const std::vector<Eigen::Vector3d>& pts, const std::vector<char>* keep, Eigen::Vector3d& n,
                double& dd) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (keep == nullptr || (*keep)[i]) {
        c += pts[i];
        ++count;
      }
    if (count < 3) return false;
    c /= static_cast<double>(count);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (keep == nullptr || (*keep)[i]) {
        const Eigen::Vector3d q = pts[i] - c;
        cov += q * q.transpose();
      }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    n = es.eigenvectors().col(0);  // smallest eigenvalue first
    dd = -n.dot(c);
    if (dd < 0) {
      n = -n;
      dd = -dd;
    }
    return n.allFinite() && std::isfinite(dd);
  };
  std::vector<em::plane_equation> planes;
  std::vector<double> residual;
  std::vector<char> keep;
  for (std::size_t id = em::abw_first_plane_label; id < points.size(); ++id) {
    const auto& pts = points[id];
    Eigen::Vector3d n;
    double d = 0;
    if (!fit(pts, nullptr, n, d)) continue;
    residual.resize(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) residual[i] = std::fabs(n.dot(pts[i]) + d);
    std::vector<double> sorted = residual;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double limit = std::max(3.0 * 1.4826 * sorted[sorted.size() / 2], 5e-4);
    keep.assign(pts.size(), 0);
    for (std::size_t i = 0; i < pts.size(); ++i) keep[i] = residual[i] <= limit ? 1 : 0;
    Eigen::Vector3d n2;
    double d2 = 0;
    if (fit(pts, &keep, n2, d2)) n = n2, d = d2;
    planes.push_back({static_cast<std::uint16_t>(id), {n.x(), n.y(), n.z()}, d});
  }
  return planes;
}

/// The largest label value that `gt` does not use (a placeholder for unscored pixels).
std::uint16_t unused_label(const cv::Mat& gt) {
  std::vector<char> used(65536, 0);
  for (int y = 0; y < gt.rows; ++y) {
    const std::uint16_t* g = gt.ptr<std::uint16_t>(y);
    for (int x = 0; x < gt.cols; ++x) used[g[x]] = 1;
  }
  for (int v = 65535; v > 0; --v)
    if (!used[static_cast<std::size_t>(v)]) return static_cast<std::uint16_t>(v);
  ex::fail("ground truth uses every label value");
}

/// One image's inputs to the metrics: the GT label image as the metrics should see it and the
/// scored mask.  EVALUATION.md: labelling a pixel that is don't-care only because its depth is
/// invalid is never punished, and the metrics count only unscored pixels whose GT is 0 as the
/// don't-care pixels of the small-fragment rule; so invalid-depth pixels get a placeholder GT id
/// (one not used on scored pixels, hence no GT plane).  Synthetic: ignore code 2 = no valid depth;
/// ABW: GT 0 = no range data, and GT 1 (speckle) and 2 (region borders) become GT 0.
struct scoring_input {
  cv::Mat gt;      // CV_16UC1
  cv::Mat scored;  // CV_8UC1, 1 = scored
};

scoring_input synthetic_scoring(const cv::Mat& gt, const cv::Mat& ignore) {
  scoring_input s;
  s.gt = gt.clone();
  s.scored.create(gt.rows, gt.cols, CV_8UC1);
  const std::uint16_t placeholder = unused_label(gt);
  for (int y = 0; y < gt.rows; ++y) {
    const std::uint16_t* ig = ignore.ptr<std::uint16_t>(y);
    std::uint16_t* g = s.gt.ptr<std::uint16_t>(y);
    std::uint8_t* sc = s.scored.ptr<std::uint8_t>(y);
    for (int x = 0; x < gt.cols; ++x) {
      sc[x] = ig[x] == 0 ? 1 : 0;
      if (ig[x] == 2 && g[x] == 0) g[x] = placeholder;
    }
  }
  return s;
}

scoring_input abw_scoring(const cv::Mat& gt) {
  scoring_input s;
  s.gt = gt.clone();
  s.scored.create(gt.rows, gt.cols, CV_8UC1);
  const std::uint16_t placeholder = unused_label(gt);
  for (int y = 0; y < gt.rows; ++y) {
    std::uint16_t* g = s.gt.ptr<std::uint16_t>(y);
    std::uint8_t* sc = s.scored.ptr<std::uint8_t>(y);
    for (int x = 0; x < gt.cols; ++x) {
      sc[x] = g[x] >= em::abw_first_plane_label ? 1 : 0;
      if (g[x] == 0)
        g[x] = placeholder;
      else if (g[x] < em::abw_first_plane_label)
        g[x] = 0;
    }
  }
  return s;
}

template <class T>
edgeplane::image_view<const T> const_view(const cv::Mat& m) {
  return edgeplane::make_view(m.ptr<const T>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step1()));
}

void require_same_size(const cv::Mat& a, const cv::Mat& b, const std::string& a_path, const std::string& b_path) {
  if (a.size() != b.size())
    ex::fail("'" + b_path + "' is " + std::to_string(b.cols) + "x" + std::to_string(b.rows) + " but '" + a_path +
             "' is " + std::to_string(a.cols) + "x" + std::to_string(a.rows));
}

// ---- results ----------------------------------------------------------------------------------------

struct totals {
  int images = 0;
  double d2mc_sum = 0, ssim_sum = 0;
  int d2mc_n = 0, ssim_n = 0;
  long correct = 0, over = 0, under = 0, missed = 0, noise = 0, gt_planes = 0, segments = 0;
  double angle_sum = 0;  // SegComp correct detections
  long angle_pairs = 0;
  long matches = 0, pr_segments = 0, pr_gt = 0;
  double iou_sum = 0, plane_angle_sum = 0;
  long plane_angle_pairs = 0;
  double ms_sum = 0;

  void add(const em::report& r, double ms) {
    ++images;
    if (std::isfinite(r.d2mc)) d2mc_sum += r.d2mc, ++d2mc_n;
    if (std::isfinite(r.ssim)) ssim_sum += r.ssim, ++ssim_n;
    const em::segcomp_counts& s = r.segcomp;
    correct += s.correct;
    over += s.over;
    under += s.under;
    missed += s.missed;
    noise += s.noise;
    gt_planes += s.gt_planes;
    segments += s.segments;
    if (s.angle_pairs > 0) angle_sum += s.mean_angle_deg * s.angle_pairs, angle_pairs += s.angle_pairs;
    const em::plane_match_result& p = r.planes;
    matches += p.matches;
    pr_segments += p.segments;
    pr_gt += p.gt_planes;
    if (p.matches > 0) iou_sum += p.mean_iou * p.matches;
    if (p.angle_pairs > 0) plane_angle_sum += p.mean_angle_deg * p.angle_pairs, plane_angle_pairs += p.angle_pairs;
    ms_sum += ms;
  }
  static double ratio(double a, double b) { return b > 0 ? a / b : nan; }
  double per_image(double v) const { return ratio(v, images); }
  double d2mc() const { return ratio(d2mc_sum, d2mc_n); }
  double ssim() const { return ratio(ssim_sum, ssim_n); }
  double mean_angle() const { return ratio(angle_sum, static_cast<double>(angle_pairs)); }
  double precision() const { return ratio(static_cast<double>(matches), static_cast<double>(pr_segments)); }
  double recall() const { return ratio(static_cast<double>(matches), static_cast<double>(pr_gt)); }
  double mean_iou() const { return ratio(iou_sum, static_cast<double>(matches)); }
  double plane_angle() const { return ratio(plane_angle_sum, static_cast<double>(plane_angle_pairs)); }
  double ms() const { return per_image(ms_sum); }
};

std::string fmt(double v, const char* f) {
  if (!std::isfinite(v)) return "-";
  char buf[40];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

constexpr const char* table_format = "%-16s %4s %4s %5s %4s %5s %5s %5s %6s %6s %6s %5s %5s %5s %6s %7s\n";

void print_header() {
  std::printf(table_format, "image", "gt", "seg", "corr", "over", "under", "miss", "noise", "angle", "d2mc", "ssim",
              "prec", "rec", "iou", "p_ang", "ms");
}

void print_row(const std::string& name, double gt, double seg, double corr, double over, double under, double miss,
               double noise, double angle, double d2mc, double ssim, double prec, double rec, double iou,
               double p_angle, double ms, bool averages) {
  const char* count = averages ? "%.2f" : "%.0f";
  std::printf(table_format, name.c_str(), fmt(gt, averages ? "%.1f" : "%.0f").c_str(),
              fmt(seg, averages ? "%.1f" : "%.0f").c_str(), fmt(corr, count).c_str(), fmt(over, count).c_str(),
              fmt(under, count).c_str(), fmt(miss, count).c_str(), fmt(noise, count).c_str(),
              fmt(angle, "%.2f").c_str(), fmt(d2mc, "%.4f").c_str(), fmt(ssim, "%.4f").c_str(),
              fmt(prec, "%.3f").c_str(), fmt(rec, "%.3f").c_str(), fmt(iou, "%.3f").c_str(),
              fmt(p_angle, "%.2f").c_str(), fmt(ms, "%.1f").c_str());
}

std::string json_summary(const options& o, const dataset& ds, const totals& t) {
  std::string s = "{\"dataset\":" + ex::json_string(ds.dir) +
                  ",\"layout\":" + ex::json_string(ds.layout == layout_kind::abw ? "abw" : "synthetic") +
                  ",\"preset\":" + ex::json_string(o.preset) + ",\"set\":[";
  for (std::size_t i = 0; i < o.settings.size(); ++i) {
    if (i) s += ',';
    s += ex::json_string(o.settings[i]);
  }
  s += "],\"images\":" + std::to_string(t.images);
  auto num = [&](const char* key, double v, const char* f) {
    s += ",\"";
    s += key;
    s += "\":";
    ex::detail::json_number(s, v, f);
  };
  num("d2mc", t.d2mc(), "%.6f");
  num("ssim", t.ssim(), "%.6f");
  num("correct", t.per_image(static_cast<double>(t.correct)), "%.4f");
  num("over", t.per_image(static_cast<double>(t.over)), "%.4f");
  num("under", t.per_image(static_cast<double>(t.under)), "%.4f");
  num("missed", t.per_image(static_cast<double>(t.missed)), "%.4f");
  num("noise", t.per_image(static_cast<double>(t.noise)), "%.4f");
  num("gt_planes", t.per_image(static_cast<double>(t.gt_planes)), "%.4f");
  num("mean_angle_deg", t.mean_angle(), "%.4f");
  num("precision", t.precision(), "%.6f");
  num("recall", t.recall(), "%.6f");
  num("mean_iou", t.mean_iou(), "%.6f");
  num("ms_per_frame", t.ms(), "%.3f");
  num("segments", t.per_image(static_cast<double>(t.segments)), "%.4f");
  num("plane_angle_deg", t.plane_angle(), "%.4f");
  s += ",\"gt_plane_equations\":";
  s += ex::json_string(ds.layout == layout_kind::abw ? "fitted to GT pixels" : "from STEM.json");
  s += "}";
  return s;
}

/// Runs `segment_frame(depth, scale, k, labels, planes)` (which labels a CV_16UC1 image, fills the
/// segments' plane equations and returns its milliseconds) over the data set and prints the scores.
template <class SegmentFrame>
int run_with(const options& o, const dataset& ds, SegmentFrame&& segment_frame) {
  if (!o.save_dir.empty()) {
    std::error_code ec;
    fs::create_directories(o.save_dir, ec);
    if (ec || !fs::is_directory(o.save_dir))
      ex::fail("cannot create output directory '" + o.save_dir + "'" + (ec ? ": " + ec.message() : ""));
  }
  if (!o.quiet) {
    std::printf("dataset %s (%s layout, %zu images), preset %s, backend %s", ds.dir.c_str(),
                ds.layout == layout_kind::abw ? "abw" : "synthetic", ds.frames.size(), o.preset.c_str(),
                o.backend.c_str());
    for (const std::string& s : o.settings) std::printf(" --set %s", s.c_str());
    std::printf("\n");
    print_header();
    std::fflush(stdout);
  }

  totals t;
  std::vector<em::plane_equation> gt_planes, pred_planes;
  for (std::size_t i = 0; i < ds.frames.size(); ++i) {
    const frame& f = ds.frames[i];
    if (!o.quiet) {
      std::fprintf(stderr, "[%zu/%zu] %s ...\n", i + 1, ds.frames.size(), f.name.c_str());
      std::fflush(stderr);
    }
    const cv::Mat depth = ex::load_depth_png(f.depth);
    const cv::Mat gt = ex::load_label_png(f.gt, "ground-truth image");
    require_same_size(depth, gt, f.depth, f.gt);
    edgeplane::intrinsics k = f.k;
    float scale = ds.abw_scale;
    scoring_input in;
    if (ds.layout == layout_kind::synthetic) {
      const cv::Mat ignore = ex::load_label_png(f.ignore, "ignore mask");
      require_same_size(depth, ignore, f.depth, f.ignore);
      read_scene_json(f.json, k, scale, gt_planes);
      in = synthetic_scoring(gt, ignore);
    } else {
      gt_planes = fit_abw_gt_planes(depth, gt, scale, k);
      in = abw_scoring(gt);
    }

    cv::Mat labels(depth.rows, depth.cols, CV_16UC1);
    pred_planes.clear();
    const double ms = segment_frame(depth, scale, k, labels, pred_planes);
    if (!o.save_dir.empty()) ex::write_png((fs::path(o.save_dir) / (f.name + "_labels.png")).string(), labels);

    const em::report r = em::evaluate(const_view<std::uint16_t>(labels), const_view<std::uint16_t>(in.gt),
                                      const_view<std::uint8_t>(in.scored), pred_planes, gt_planes);
    t.add(r, ms);
    if (!o.quiet) {
      const em::segcomp_counts& s = r.segcomp;
      print_row(f.name, s.gt_planes, s.segments, s.correct, s.over, s.under, s.missed, s.noise, s.mean_angle_deg,
                r.d2mc, r.ssim, r.planes.precision, r.planes.recall, r.planes.mean_iou, r.planes.mean_angle_deg,
                ms, false);
      std::fflush(stdout);
    }
  }

  if (!o.quiet) {
    std::printf("\naverages over %d images (counts per image; angles pooled over pairs; precision, recall, IoU "
                "pooled):\n",
                t.images);
    print_header();
    auto per = [&](long v) { return t.per_image(static_cast<double>(v)); };
    print_row("mean", per(t.gt_planes), per(t.segments), per(t.correct), per(t.over), per(t.under), per(t.missed),
              per(t.noise), t.mean_angle(), t.d2mc(), t.ssim(), t.precision(), t.recall(), t.mean_iou(),
              t.plane_angle(), t.ms(), true);
    if (ds.layout == layout_kind::abw)
      std::printf("(ABW GT plane equations fitted to the GT pixels' points; angles measured against those fits)\n");
  }
  std::printf("%s\n", json_summary(o, ds, t).c_str());
  std::fflush(stdout);
  return 0;
}

template <class Backend>
int run_backend(const options& o, const edgeplane::params& params, const dataset& ds, Backend backend) {
  edgeplane::segmenter<Backend> seg(params, backend);
  edgeplane::segmentation_result result;
  return run_with(o, ds, [&](const cv::Mat& depth, float scale, const edgeplane::intrinsics& k, cv::Mat& labels,
                             std::vector<em::plane_equation>& planes) {
    seg.segment(const_view<std::uint16_t>(depth), scale, k,
                edgeplane::make_view(labels.ptr<std::uint16_t>(), labels.cols, labels.rows,
                                     static_cast<std::ptrdiff_t>(labels.step1())),
                result);
    for (const edgeplane::plane& p : result.planes) planes.push_back({p.id, {p.normal[0], p.normal[1], p.normal[2]}, p.d});
    return result.times.total;
  });
}

#if defined(EDGEPLANE_WITH_PCL) || defined(EDGEPLANE_WITH_CAPE)
/// A peer (benchmarks/pcl_peer.hpp: PCL's OrganizedMultiPlaneSegmentation with
/// IntegralImageNormalEstimation, in its organized segmentation demo's configuration;
/// benchmarks/cape_peer.hpp: CAPE in run_cape_offline's, planes only) through the same scoring.
/// Its plane j labels the pixels it gives that plane j; its plane equations are its own fits.
template <class Peer>
int run_peer(const options& o, const dataset& ds) {
  Peer peer;
  return run_with(o, ds, [&](const cv::Mat& depth, float scale, const edgeplane::intrinsics& k, cv::Mat& labels,
                             std::vector<em::plane_equation>& planes) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<edgeplane_peer::peer_plane> found;
    peer.run(depth.ptr<std::uint16_t>(), depth.cols, depth.rows, static_cast<std::ptrdiff_t>(depth.step1()), scale, k,
             labels.ptr<std::uint16_t>(), static_cast<std::ptrdiff_t>(labels.step1()), &found);
    for (const auto& p : found) planes.push_back({p.id, {p.n[0], p.n[1], p.n[2]}, p.d});
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  });
}
#endif

int run(const options& o) {
  const edgeplane::params params = make_params(o);
  if (o.list_params) {
    for (const param_field& f : param_fields()) std::printf("%s=%s\n", f.name, format_param(params, f).c_str());
    return 0;
  }
  const dataset ds = scan_dataset(o);
  if (o.backend == "cpu") return run_backend(o, params, ds, edgeplane::cpu{});
#ifdef EDGEPLANE_WITH_PCL
  if (o.backend == "pcl") return run_peer<edgeplane_peer::pcl_segmenter>(o, ds);
#endif
#ifdef EDGEPLANE_WITH_CAPE
  if (o.backend == "cape") return run_peer<edgeplane_peer::cape_segmenter>(o, ds);
#endif
#ifdef EDGEPLANE_WITH_CUDA
  if (o.backend == "cuda") return run_backend(o, params, ds, edgeplane::cuda{});
#endif
  ex::fail("unknown backend '" + o.backend + "'");
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
