// edgeplane_compare_backends: the CPU and CUDA segmenters on the same real frames.  For each line
// of a manifest it segments one depth image with segmenter<cpu> and segmenter<edgeplane::cuda>,
// checks that the labels are equal up to renumbering and that the planes agree (same pixel
// counts and boxes; normal, d and centroid within 1e-4), and reports the median time of each
// backend (host depth in, host labels out, as an application calls segment()), of the CUDA
// segmenter on device-resident depth and labels (segment_on_backend), and its median per stage.
// Then the frames of the largest group go through an edgeplane::pipeline<cuda> of 1, 2 and 4
// lanes (one stream each) for throughput.  Exit status 1 when any frame disagrees, 2 on bad
// input, 77 without a CUDA device.
//
// Frames are 16-bit binary PGM (P5, maxval > 255, big-endian, as netpbm writes them), so the
// program needs no image library and runs where OpenCV is not installed.  Manifest lines:
//   NAME  PATH  fx fy cx cy  metres_per_unit  preset
// (PATH relative to the manifest's folder; '#' starts a comment).  Usage:
//   edgeplane_compare_backends MANIFEST [--repeat N] [--cpu-repeat N] [--pipeline-frames N]
//                              [--set NAME=VALUE]...
// --set changes one threshold of every frame's preset (grow_sweeps, split_regions, grow_iterations,
// label_closing_radius, smooth_radius), to find which stage two backends disagree in.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "edgeplane/edgeplane.cuh"
#include "support/labels_equal.hpp"

namespace {
namespace ep = edgeplane;
using clk = std::chrono::steady_clock;

struct frame {
  std::string name, preset;
  int w = 0, h = 0;
  std::vector<std::uint16_t> depth;
  ep::intrinsics k;
  float scale = 0.001f;
};

/// Reads a 16-bit binary PGM; throws std::runtime_error naming the file on anything else.
std::vector<std::uint16_t> read_pgm16(const std::string& path, int& w, int& h) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot open " + path);
  auto token = [&]() {
    std::string t;
    char c;
    while (f.get(c)) {
      if (c == '#') {
        std::string skip;
        std::getline(f, skip);
        continue;
      }
      if (std::isspace(static_cast<unsigned char>(c))) {
        if (!t.empty()) break;
        continue;
      }
      t += c;
    }
    return t;
  };
  if (token() != "P5") throw std::runtime_error(path + ": not a binary PGM (P5)");
  w = std::stoi(token());
  h = std::stoi(token());
  const int maxval = std::stoi(token());
  if (w <= 0 || h <= 0 || maxval < 256 || maxval > 65535)
    throw std::runtime_error(path + ": want a 16-bit PGM, got " + std::to_string(w) + "x" + std::to_string(h) +
                             " maxval " + std::to_string(maxval));
  std::vector<unsigned char> bytes(static_cast<std::size_t>(w) * h * 2);
  if (!f.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
    throw std::runtime_error(path + ": truncated");
  std::vector<std::uint16_t> out(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = static_cast<std::uint16_t>((bytes[2 * i] << 8) | bytes[2 * i + 1]);
  return out;
}

std::vector<frame> read_manifest(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open " + path);
  const auto slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  std::vector<frame> out;
  std::string line;
  while (std::getline(f, line)) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream in(line);
    frame fr;
    std::string file;
    if (!(in >> fr.name)) continue;
    if (!(in >> file >> fr.k.fx >> fr.k.fy >> fr.k.cx >> fr.k.cy >> fr.scale >> fr.preset))
      throw std::runtime_error(path + ": bad line: " + line);
    fr.depth = read_pgm16(file.front() == '/' ? file : dir + "/" + file, fr.w, fr.h);
    out.push_back(std::move(fr));
  }
  return out;
}

/// Applies "NAME=VALUE" to p; false for a name it does not know.
bool apply_setting(ep::params& p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) return false;
  const std::string name = kv.substr(0, eq);
  const int v = std::atoi(kv.c_str() + eq + 1);
  if (name == "grow_sweeps") p.grow_sweeps = v != 0;
  else if (name == "split_regions") p.split_regions = v != 0;
  else if (name == "grow_iterations") p.grow_iterations = v;
  else if (name == "label_closing_radius") p.label_closing_radius = v;
  else if (name == "smooth_radius") p.smooth_radius = v;
  else return false;
  return true;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double ms_between(clk::time_point a, clk::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// Largest difference between matched planes (labels matched through `corr`, g id -> c id);
/// `count_mismatch` counts planes whose pixel count or box differ or that have no partner.
double plane_difference(const ep::segmentation_result& c, const ep::segmentation_result& g,
                        const edgeplane_test::label_correspondence& corr, int& count_mismatch) {
  double worst = 0.0;
  count_mismatch = static_cast<int>(c.planes.size() > g.planes.size() ? c.planes.size() - g.planes.size()
                                                                      : g.planes.size() - c.planes.size());
  for (const ep::plane& gp : g.planes) {
    const auto it = corr.a_to_b.find(gp.id);
    const std::int64_t cid = it != corr.a_to_b.end() ? it->second : gp.id;
    const auto cp = std::find_if(c.planes.begin(), c.planes.end(), [&](const ep::plane& q) { return q.id == cid; });
    if (cp == c.planes.end()) {
      ++count_mismatch;
      continue;
    }
    if (gp.pixels != cp->pixels || gp.points != cp->points || !(gp.bbox == cp->bbox)) ++count_mismatch;
    worst = std::max(worst, static_cast<double>(std::abs(gp.d - cp->d)));
    for (int j = 0; j < 3; ++j) {
      worst = std::max(worst, static_cast<double>(std::abs(gp.normal[j] - cp->normal[j])));
      worst = std::max(worst, static_cast<double>(std::abs(gp.centroid[j] - cp->centroid[j])));
    }
  }
  return worst;
}

struct stage_medians {
  std::vector<double> pre, edges, seg, cand, val, merge, fin;
  void add(const ep::stage_times& t) {
    pre.push_back(t.preprocess);
    edges.push_back(t.edges);
    seg.push_back(t.segments);
    cand.push_back(t.candidates);
    val.push_back(t.validation);
    merge.push_back(t.merge);
    fin.push_back(t.finalize);
  }
  /// Each stage's median; total = their sum.
  ep::stage_times medians() const {
    ep::stage_times m;
    m.preprocess = median(pre);
    m.edges = median(edges);
    m.segments = median(seg);
    m.candidates = median(cand);
    m.validation = median(val);
    m.merge = median(merge);
    m.finalize = median(fin);
    m.total = m.preprocess + m.edges + m.segments + m.candidates + m.validation + m.merge + m.finalize;
    return m;
  }
};

/// The group a frame's figures are summarised in: its size and preset.
std::string group_of(const frame& f) { return std::to_string(f.w) + "x" + std::to_string(f.h) + " " + f.preset; }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::printf("usage: %s MANIFEST [--repeat N] [--cpu-repeat N] [--pipeline-frames N]\n", argv[0]);
    return argc < 2 ? 2 : 0;
  }
  int repeat = 50, cpu_repeat = 5, pipeline_frames = 240;
  std::vector<std::string> settings;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const int v = std::atoi(argv[i + 1]);
    if (a == "--set") {
      ep::params probe;
      if (!apply_setting(probe, argv[i + 1])) {
        std::fprintf(stderr, "--set %s: want NAME=VALUE with NAME one of grow_sweeps, split_regions, "
                     "grow_iterations, label_closing_radius, smooth_radius\n", argv[i + 1]);
        return 2;
      }
      settings.push_back(argv[i + 1]);
    } else if (a == "--repeat") repeat = std::max(1, v);
    else if (a == "--cpu-repeat") cpu_repeat = std::max(1, v);
    else if (a == "--pipeline-frames") pipeline_frames = std::max(0, v);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  int devices = 0;
  if (cudaGetDeviceCount(&devices) != cudaSuccess || devices == 0) {
    std::printf("edgeplane_compare_backends: no CUDA device: skipped\n");
    return 77;
  }
  cudaDeviceProp prop{};
  ep::detail::cuda_check(cudaGetDeviceProperties(&prop, 0), "cudaGetDeviceProperties");
  std::vector<frame> frames;
  try {
    frames = read_manifest(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "edgeplane_compare_backends: %s\n", e.what());
    return 2;
  }
  std::printf("device: %s (sm_%d%d, %d SMs); host threads: %u; %zu frames; %d CUDA and %d CPU repeats\n",
              prop.name, prop.major, prop.minor, prop.multiProcessorCount, std::thread::hardware_concurrency(),
              frames.size(), repeat, cpu_repeat);
  std::printf("%-28s %9s %-11s %6s %6s %8s %9s %9s %9s %9s %8s\n", "frame", "size", "preset", "planes", "equal",
              "plane_d", "cpu_ms", "cuda_ms", "dev_ms", "cpu/cuda", "kernels");
  cudaStream_t stream = nullptr;
  ep::detail::cuda_check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "cudaStreamCreate");
  int disagree = 0;
  std::map<std::string, std::vector<double>> group_cuda, group_dev, group_cpu;  // by "WxH preset"
  std::map<std::string, stage_medians> group_stages;
  const auto params_of = [&](const frame& f) {
    ep::params p = ep::preset(f.preset);
    for (const std::string& kv : settings) apply_setting(p, kv);
    ep::validate(p);
    return p;
  };
  for (const frame& f : frames) {
    const ep::params p = params_of(f);
    ep::segmenter<ep::cpu> cs(p);
    ep::segmenter<ep::cuda> gs(p, ep::cuda{stream});
    std::vector<std::uint16_t> lc(f.depth.size()), lg(f.depth.size(), 0xbeef);
    const auto depth = ep::make_view(f.depth.data(), f.w, f.h);
    ep::segmentation_result rc, rg;
    cs.segment(depth, f.scale, f.k, ep::make_view(lc.data(), f.w, f.h), rc);
    gs.segment(depth, f.scale, f.k, ep::make_view(lg.data(), f.w, f.h), rg);
    const auto corr = edgeplane_test::correspond(lg, lc);
    int plane_mismatch = 0;
    const double pd = plane_difference(rc, rg, corr, plane_mismatch);
    const bool same = corr.equal && plane_mismatch == 0 && pd <= 1e-4 && rc.candidates == rg.candidates &&
                      rc.valid_candidates == rg.valid_candidates;
    disagree += !same;

    std::vector<double> tc, tg, td;
    stage_medians st;
    for (int i = 0; i < cpu_repeat; ++i) {
      const auto t0 = clk::now();
      cs.segment(depth, f.scale, f.k, ep::make_view(lc.data(), f.w, f.h), rc);
      tc.push_back(ms_between(t0, clk::now()));
    }
    for (int i = 0; i < repeat; ++i) {
      const auto t0 = clk::now();
      gs.segment(depth, f.scale, f.k, ep::make_view(lg.data(), f.w, f.h), rg);
      tg.push_back(ms_between(t0, clk::now()));
      st.add(rg.times);
    }
    // device-resident depth and labels: no frame crosses the bus
    const std::size_t n = f.depth.size();
    const ep::cuda dev{stream};
    ep::buffer<std::uint16_t, ep::cuda> dd(dev), dl(dev);
    dd.resize(n);
    dl.resize(n);
    dev.copy_from_host(dd.data(), f.depth.data(), n * sizeof(std::uint16_t));
    const auto ddv = ep::make_view<const std::uint16_t>(dd.data(), f.w, f.h);
    const auto dlv = ep::make_view(dl.data(), f.w, f.h);
    gs.segment_on_backend(ddv, f.scale, f.k, dlv, rg);  // warm-up
    for (int i = 0; i < repeat; ++i) {
      const auto t0 = clk::now();
      gs.segment_on_backend(ddv, f.scale, f.k, dlv, rg);
      td.push_back(ms_between(t0, clk::now()));
    }
    std::vector<std::uint16_t> ld(n);
    dev.copy_to_host(ld.data(), dl.data(), n * sizeof(std::uint16_t));
    const bool dev_same = edgeplane_test::labels_equal(ld, lc);
    disagree += !dev_same;

    const double mc = median(tc), mg = median(tg), md = median(td);
    const ep::stage_times sm = st.medians();
    const double kernels = sm.total;
    std::printf("%-28s %4dx%-4d %-11s %3zu/%-2zu %6s %8.1e %9.3f %9.3f %9.3f %8.1fx %8.3f\n", f.name.c_str(), f.w, f.h,
                f.preset.c_str(), rg.planes.size(), rc.planes.size(),
                same && dev_same ? "yes" : (corr.equal ? "planes" : std::to_string(corr.conflicts).c_str()), pd, mc,
                mg, md, mc / mg, kernels);
    const std::string g = group_of(f);
    group_cuda[g].push_back(mg);
    group_dev[g].push_back(md);
    group_cpu[g].push_back(mc);
    group_stages[g].add(sm);
  }

  std::printf("\nper group (median over its frames of each frame's median, ms)\n");
  std::printf("%-22s %3s %8s %8s %8s %8s | %7s %7s %7s %7s %7s %7s %7s\n", "group", "n", "cpu", "cuda", "dev", "cpu/cuda",
              "pre", "edges", "segs", "cands", "valid", "merge", "final");
  for (const auto& [g, v] : group_cuda) {
    const ep::stage_times s = group_stages[g].medians();
    const double c = median(group_cpu[g]), m = median(v);
    std::printf("%-22s %3zu %8.3f %8.3f %8.3f %7.1fx | %7.3f %7.3f %7.3f %7.3f %7.3f %7.3f %7.3f\n", g.c_str(), v.size(),
                c, m, median(group_dev[g]), c / m, s.preprocess, s.edges, s.segments, s.candidates,
                s.validation, s.merge, s.finalize);
  }

  // Throughput through edgeplane::pipeline<cuda>: the frames of the largest group, cycled.
  if (pipeline_frames > 0 && !frames.empty()) {
    std::string best;
    for (const auto& [g, v] : group_cuda)
      if (best.empty() || v.size() > group_cuda[best].size()) best = g;
    std::vector<const frame*> set;
    for (const frame& f : frames)
      if (group_of(f) == best) set.push_back(&f);
    // the CPU's labels of the set's frames, once, for the checked warm-up of every lane count
    std::vector<std::vector<std::uint16_t>> cpu_labels;
    for (const frame* f : set) {
      ep::segmenter<ep::cpu> cs(params_of(*f));
      cpu_labels.emplace_back(f->depth.size());
      cs.segment(ep::make_view(f->depth.data(), f->w, f->h), f->scale, f->k,
                 ep::make_view(cpu_labels.back().data(), f->w, f->h));
    }
    std::printf("\npipeline<cuda> throughput on group %s (%zu distinct frames, %d frames per run)\n", best.c_str(),
                set.size(), pipeline_frames);
    std::vector<std::uint16_t> labels(set.front()->depth.size());
    for (const int lanes : {1, 2, 4}) {
      std::vector<cudaStream_t> ss(static_cast<std::size_t>(lanes));
      std::vector<ep::cuda> bs;
      for (auto& s : ss) {
        ep::detail::cuda_check(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking), "cudaStreamCreate");
        bs.push_back(ep::cuda{s});
      }
      {
        ep::pipeline<ep::cuda> pipe(params_of(*set.front()), bs);
        ep::segmentation_result r;
        int bad = 0;
        auto run = [&](int count, bool check) {
          int submitted = 0, retrieved = 0;
          while (retrieved < count) {
            if (submitted < count && !pipe.full()) {
              const frame& f = *set[static_cast<std::size_t>(submitted) % set.size()];
              pipe.submit(ep::make_view(f.depth.data(), f.w, f.h), f.scale, f.k);
              ++submitted;
            } else {
              const std::size_t j = static_cast<std::size_t>(retrieved) % set.size();
              pipe.retrieve(ep::make_view(labels.data(), set[j]->w, set[j]->h), r);
              if (check) bad += !edgeplane_test::labels_equal(labels, cpu_labels[j]);
              ++retrieved;
            }
          }
        };
        run(static_cast<int>(set.size()), true);  // warm-up, checked against the CPU
        const auto t0 = clk::now();
        run(pipeline_frames, false);
        const double ms = ms_between(t0, clk::now());
        std::printf("  %d lane(s): %8.3f ms per frame, %8.0f frames/s; warm-up frames equal to the CPU's: %s\n", lanes,
                    ms / pipeline_frames, 1000.0 * pipeline_frames / ms, bad == 0 ? "yes" : "NO");
        disagree += bad;
      }
      for (auto& s : ss) (void)cudaStreamDestroy(s);
    }
  }
  (void)cudaStreamDestroy(stream);
  std::printf("\n%s: %d disagreement(s)\n", disagree == 0 ? "PASS" : "FAIL", disagree);
  return disagree == 0 ? 0 : 1;
}
