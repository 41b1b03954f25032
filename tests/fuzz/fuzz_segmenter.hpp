// edgeplane fuzzing: one input of arbitrary bytes decoded into a segmenter call (image size and
// type, intrinsics, depth scale, a preset, any thresholds overridden with arbitrary values, a
// deliberately broken view), run, and checked against what the library promises:
//  - arguments it must reject (bad views, non-finite intrinsics, a bad scale, thresholds out of
//    range) throw edgeplane::error, and nothing else throws;
//  - arguments it accepts give a well-formed result: labels 0..N, plane ids 1..N, pixel counts
//    that match the label image, unit normals, finite offsets, boxes inside the image;
//  - the same segmenter run again on the same frame gives the same labels, and so does the serial
//    CPU backend.
// A violated promise aborts (libFuzzer, and the replayer in ctest, report it as a crash).
//
// Layout of an input (all little-endian):
//   0      flags: bit 0 float depth (else uint16), bit 1 parallel CPU backend (else serial: TBB
//          under the sanitizers and coverage instrumentation is about 10x slower), bits 2-4 view fault
//          (0 none, 1 labels narrower, 2 labels shorter, 3 pitch < width, 4 null depth,
//          5 null labels), bit 5 also compare a parallel run with the serial backend, bit 6 run
//          the same segmenter a second time on the frame and compare
//   1      preset index (modulo the number of presets)
//   2..3   width  (modulo 257)
//   4..5   height (modulo 257); width * height is capped at max_pixels by shrinking the height
//   6..21  fx, fy, cx, cy (float bits)
//   22..25 depth scale (float bits; metres per unit for uint16, ignored for float)
//   26     number of threshold overrides k (modulo 9), then k records of
//          1 byte field index (modulo the field count) + 4 bytes value
//   rest   depth samples, row-major; missing samples are 0 (invalid)
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <edgeplane/edgeplane.hpp>

namespace edgeplane_fuzz {

inline constexpr int max_side = 256;
inline constexpr std::int64_t max_pixels = 160 * 128;

[[noreturn]] inline void violated(const char* what, const std::string& detail = {}) {
  std::fprintf(stderr, "edgeplane fuzz: promise violated: %s %s\n", what, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

/// Reads little-endian fields from the input; past its end every read is 0.
class reader {
 public:
  reader(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
  std::uint8_t u8() { return pos_ < n_ ? p_[pos_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() {
    std::uint32_t v = u16();
    return v | (static_cast<std::uint32_t>(u16()) << 16);
  }
  float f32() {
    const std::uint32_t bits = u32();
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
  std::size_t left() const { return pos_ < n_ ? n_ - pos_ : 0; }
  const std::uint8_t* here() const { return p_ + pos_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
};

/// Sets threshold number `field` from 4 raw bytes.  Floats take the raw bits (NaN, infinities,
/// denormals and huge values included) when the top byte is odd, else a moderate value; ints take
/// the raw int32 when its top bit is set, else a small value around the valid ranges.
inline void override_field(edgeplane::params& p, unsigned field, std::uint32_t raw) {
  float f;
  std::memcpy(&f, &raw, sizeof f);
  if (!((raw >> 24) & 1u)) f = static_cast<float>(raw % 200001u) / 10000.f - 2.f;  // [-2, 18]
  const int i = (raw & 0x80000000u) ? static_cast<int>(raw) : static_cast<int>(raw % 48u) - 4;  // [-4, 43]
  const bool b = raw & 1u;
  float* floats[] = {&p.min_depth, &p.max_depth, &p.noise.sigma0, &p.noise.sigma2, &p.smooth_k, &p.t_je,
                     &p.t_je_quad, &p.t_je_ratio, &p.adjacency_slope, &p.t_ee, &p.t_coe, &p.t_coe_arm,
                     &p.t_cue1, &p.t_cue2, &p.noise_k, &p.t_line, &p.t_cu, &p.t_residual, &p.t_par, &p.t_ps,
                     &p.grow_k};
  int* ints[] = {&p.depth_closing_radius, &p.smooth_radius, &p.n_ee, &p.n_coe, &p.n_cue,
                 &p.edge_closing_radius, &p.t_length, &p.max_run_splits, &p.t_size, &p.split_rounds,
                 &p.split_erode, &p.grow_iterations, &p.label_closing_radius, &p.min_region_pixels};
  bool* bools[] = {&p.downscale, &p.use_jump, &p.use_extrema, &p.use_corner, &p.use_curved, &p.grow_sweeps, &p.split_regions};
  constexpr unsigned nf = sizeof floats / sizeof *floats, ni = sizeof ints / sizeof *ints,
                     nb = sizeof bools / sizeof *bools;
  field %= nf + ni + nb;
  if (field < nf)
    *floats[field] = f;
  else if (field < nf + ni)
    *ints[field - nf] = i;
  else
    *bools[field - nf - ni] = b;
}

/// Checks the result of an accepted call against the label image (w x h, dense).
inline void check_result(const edgeplane::segmentation_result& r, const std::vector<std::uint16_t>& labels, int w,
                         int h) {
  const std::size_t n = r.planes.size();
  if (n > 65535) violated("more planes than a uint16 label can name");
  if (r.valid_candidates < 0 || r.candidates < r.valid_candidates) violated("candidate counts");
  std::vector<std::int64_t> count(n + 1, 0);
  for (std::uint16_t l : labels) {
    if (l > n) violated("label beyond the plane count", std::to_string(l) + " > " + std::to_string(n));
    ++count[l];
  }
  for (std::size_t j = 0; j < n; ++j) {
    const edgeplane::plane& p = r.planes[j];
    if (p.id != j + 1) violated("plane ids are not 1..N");
    if (p.pixels != count[j + 1])
      violated("plane pixel count", std::to_string(p.pixels) + " vs " + std::to_string(count[j + 1]));
    if (p.points < 0 || p.points > p.pixels) violated("plane point count");
    const double len = std::sqrt(double(p.normal[0]) * p.normal[0] + double(p.normal[1]) * p.normal[1] +
                                 double(p.normal[2]) * p.normal[2]);
    if (!(std::abs(len - 1.0) < 1e-3)) violated("normal is not unit", std::to_string(len));
    if (!std::isfinite(p.d)) violated("plane offset is not finite");
    if (p.pixels > 0 && !(p.bbox[0] >= 0 && p.bbox[1] >= 0 && p.bbox[0] <= p.bbox[2] && p.bbox[1] <= p.bbox[3] &&
                          p.bbox[2] < w && p.bbox[3] < h))
      violated("bounding box outside the image");
  }
}

/// Decodes one input and runs it; aborts when a promise is broken.  Returns the number of planes
/// found, or -1 when the library (rightly) rejected the call.
inline int run_one(const std::uint8_t* data, std::size_t size) {
  reader in(data, size);
  const std::uint8_t flags = in.u8();
  const bool is_float = flags & 1u, serial = !(flags & 2u), compare_serial = flags & 32u, rerun = flags & 64u;
  const int fault = (flags >> 2) & 7;
  const auto names = edgeplane::presets::preset_names();
  const std::string preset = names[in.u8() % names.size()];
  int w = in.u16() % (max_side + 1), h = in.u16() % (max_side + 1);
  if (static_cast<std::int64_t>(w) * h > max_pixels) h = static_cast<int>(max_pixels / w);
  edgeplane::intrinsics k;
  k.fx = in.f32();
  k.fy = in.f32();
  k.cx = in.f32();
  k.cy = in.f32();
  const float scale = in.f32();
  edgeplane::params p = edgeplane::preset(preset);
  const int overrides = in.u8() % 9;
  for (int j = 0; j < overrides; ++j) {
    const unsigned field = in.u8();
    override_field(p, field, in.u32());
  }
  const std::size_t n = static_cast<std::size_t>(w) * h;
  std::vector<std::uint16_t> d16(is_float ? 0 : n, 0);
  std::vector<float> d32(is_float ? n : 0, 0.f);
  const std::size_t sample = is_float ? sizeof(float) : sizeof(std::uint16_t);
  const std::size_t have = std::min(n, in.left() / sample);
  if (have > 0) std::memcpy(is_float ? static_cast<void*>(d32.data()) : d16.data(), in.here(), have * sample);

  // What the library must accept.
  bool params_ok = true;
  try {
    edgeplane::validate(p);
  } catch (const edgeplane::error&) {
    params_ok = false;
  }
  const auto bad = [](float f) { return !std::isfinite(f) || f == 0.f; };
  const bool k_ok = !bad(k.fx) && !bad(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy);
  const bool scale_ok = is_float || (std::isfinite(scale) && scale > 0.f);
  // A broken view is only broken when it describes pixels (an empty image with null data is fine).
  const bool fault_real = fault >= 1 && fault <= 5 && !(fault == 1 && w == 0) && !(fault == 2 && h == 0) &&
                          !(fault == 3 && w == 0) && !(fault >= 4 && n == 0);
  const bool expect_ok = params_ok && k_ok && scale_ok && !fault_real;

  int lw = w, lh = h;
  std::ptrdiff_t dpitch = w;
  if (fault == 1 && w > 0) lw = w - 1;
  if (fault == 2 && h > 0) lh = h - 1;
  if (fault == 3 && w > 0) dpitch = w - 1;
  std::vector<std::uint16_t> labels(n, 0xffff), again(n, 0xffff), ref(n, 0xffff);
  std::uint16_t* lptr = (fault == 5 && fault_real) ? nullptr : labels.data();
  const auto lview = edgeplane::make_view(lptr, lw, lh);
  const bool null_depth = fault == 4 && fault_real;

  auto segment_with = [&](edgeplane::segmenter<>& s, edgeplane::image_view<std::uint16_t> out) {
    if (is_float)
      return s.segment(edgeplane::make_view<const float>(null_depth ? nullptr : d32.data(), w, h, dpitch), k, out);
    return s.segment(edgeplane::make_view<const std::uint16_t>(null_depth ? nullptr : d16.data(), w, h, dpitch),
                     scale, k, out);
  };

  edgeplane::segmentation_result r;
  try {
    edgeplane::segmenter<> seg(p, edgeplane::cpu{serial ? edgeplane::cpu::mode::serial : edgeplane::cpu::mode::parallel});
    r = segment_with(seg, lview);
    if (!expect_ok) violated("an unusable argument was accepted", "preset " + preset + " fault " + std::to_string(fault));
    check_result(r, labels, w, h);
    if (rerun) {
      const auto r2 = segment_with(seg, edgeplane::make_view(again.data(), w, h));
      if (again != labels || r2.planes.size() != r.planes.size()) violated("a second run on the same frame differs");
    }
    if (compare_serial && !serial) {
      edgeplane::segmenter<> s1(p, edgeplane::cpu{edgeplane::cpu::mode::serial});
      segment_with(s1, edgeplane::make_view(ref.data(), w, h));
      if (ref != labels) violated("serial and parallel labels differ");
    }
  } catch (const edgeplane::error& e) {
    if (expect_ok) violated("a usable call threw", e.what());
    return -1;
  }
  return static_cast<int>(r.planes.size());
}

/// Encodes an input in the layout above (for the seed corpus and the regression tests).
struct input {
  std::uint8_t flags = 0, preset = 0;
  int width = 0, height = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0, scale = 0.001f;
  std::vector<std::pair<std::uint8_t, std::uint32_t>> overrides;
  std::vector<std::uint8_t> samples;  // raw depth bytes
  std::vector<std::uint8_t> bytes() const {
    std::vector<std::uint8_t> b;
    auto put = [&](std::uint32_t v, int n) {
      for (int i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    };
    auto putf = [&](float f) {
      std::uint32_t u;
      std::memcpy(&u, &f, sizeof u);
      put(u, 4);
    };
    put(flags, 1);
    put(preset, 1);
    put(static_cast<std::uint32_t>(width), 2);
    put(static_cast<std::uint32_t>(height), 2);
    putf(fx);
    putf(fy);
    putf(cx);
    putf(cy);
    putf(scale);
    put(static_cast<std::uint32_t>(overrides.size()), 1);
    for (const auto& [field, value] : overrides) {
      put(field, 1);
      put(value, 4);
    }
    b.insert(b.end(), samples.begin(), samples.end());
    return b;
  }
};

}  // namespace edgeplane_fuzz
