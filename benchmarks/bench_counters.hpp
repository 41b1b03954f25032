// Counters shared by the CPU and CUDA benchmarks: pixels per second, time per pixel, and the mean
// of each pipeline stage (edgeplane::stage_times, milliseconds) over a benchmark's iterations.
#pragma once
#include <benchmark/benchmark.h>

#include "edgeplane/segmenter.hpp"

namespace edgeplane::bench {

inline void per_pixel_counters(benchmark::State& st, int w, int h) {
  const double px = static_cast<double>(w) * h;
  st.counters["pixels_per_second"] = benchmark::Counter(px, benchmark::Counter::kIsIterationInvariantRate);
  // seconds per pixel (printed with an SI prefix: 102n = 102 ns); the cost growth across sizes
  st.counters["time_per_pixel"] =
      benchmark::Counter(px, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// Sums the stage times of each iteration; report() sets their means as counters.
struct stage_sums {
  stage_times sum{};
  void add(const stage_times& t) {
    sum.preprocess += t.preprocess;
    sum.edges += t.edges;
    sum.segments += t.segments;
    sum.candidates += t.candidates;
    sum.validation += t.validation;
    sum.merge += t.merge;
    sum.finalize += t.finalize;
  }
  void report(benchmark::State& st) const {
    const double n = st.iterations() > 0 ? static_cast<double>(st.iterations()) : 1.0;
    st.counters["ms_pre"] = sum.preprocess / n;
    st.counters["ms_edges"] = sum.edges / n;
    st.counters["ms_segments"] = sum.segments / n;
    st.counters["ms_cand"] = sum.candidates / n;
    st.counters["ms_valid"] = sum.validation / n;
    st.counters["ms_merge"] = sum.merge / n;
    st.counters["ms_final"] = sum.finalize / n;
  }
};

}  // namespace edgeplane::bench
