// edgeplane: frames in flight on several segmenters at once, for throughput on a camera stream or a
// recorded sequence.
//
// A pipeline owns `lanes` segmenters, each with its own backend instance (for edgeplane::cuda:
// its own stream) and a host thread that drives it.  submit() copies a frame in and returns at
// once; the next free lane segments it while the caller goes on; retrieve() hands the results
// back in submission order.  On a GPU, the upload, kernels and download of one frame then overlap
// with those of the frames on the other lanes' streams (the thesis's "dual layer" idea); on a
// multi-core CPU, lanes of edgeplane::cpu{cpu::mode::serial} segment whole frames side by side,
// which keeps every core busy without the per-kernel fork and join of one parallel segmenter.
//
// Every frame's result is exactly what segmenter<Backend>::segment() gives for it (the segmenter
// is deterministic, and a lane keeps nothing of one frame for the next but its scratch memory).
#pragma once
#include <algorithm>
#include <concepts>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "edgeplane/backend/cpu.hpp"
#include "edgeplane/camera.hpp"
#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/params.hpp"
#include "edgeplane/segmenter.hpp"

namespace edgeplane {
namespace detail {

/// Host memory for frames in flight: the backend's page-locked host memory where it has some
/// (allocate_host / deallocate_host: edgeplane::cuda, so that uploads and downloads run
/// asynchronously), plain memory otherwise.  Grows only.
template <class Backend>
class host_block {
 public:
  host_block() = default;
  host_block(const host_block&) = delete;
  host_block& operator=(const host_block&) = delete;
  ~host_block() { release(); }
  void reserve(const Backend& b, std::size_t bytes) {
    if (bytes <= cap_) return;
    release();
    b_ = b;
    if constexpr (pinned) {
      p_ = b_.allocate_host(bytes);
    } else {
      p_ = ::operator new(bytes, std::align_val_t{64});
    }
    cap_ = bytes;
  }
  void* data() const { return p_; }

 private:
  static constexpr bool pinned = requires(const Backend& b, void* p) {
    { b.allocate_host(std::size_t{}) } -> std::same_as<void*>;
    b.deallocate_host(p);
  };
  void release() noexcept {
    if (!p_) return;
    if constexpr (pinned) {
      b_.deallocate_host(p_);
    } else {
      ::operator delete(p_, std::align_val_t{64});
    }
    p_ = nullptr;
    cap_ = 0;
  }
  Backend b_{};
  void* p_ = nullptr;
  std::size_t cap_ = 0;
};

/// What a backend needs its driving thread to be (edgeplane::cuda: the current device): captured
/// on the thread that builds the pipeline, applied on each lane's thread.
template <class Backend>
inline constexpr bool has_thread_binding = requires(const Backend& b) { b.bind_thread(b.thread_binding()); };

}  // namespace detail

template <class Backend = cpu>
class pipeline {
 public:
  /// One lane per backend instance (at least one): each gets a segmenter with thresholds `p` and
  /// a host thread.  `capacity`: frames that may be in flight (submitted, not yet retrieved);
  /// 0 = twice the lanes, so that every lane has a frame queued behind the one it runs.
  /// Throws edgeplane::error for invalid thresholds, no lanes, or a capacity below the lanes.
  pipeline(const params& p, const std::vector<Backend>& lanes, std::size_t capacity = 0)
      : slots_(std::min(capacity == 0 ? 2 * lanes.size() : capacity, max_capacity + 1)) {
    // (a capacity above the limit is refused below without allocating its slots)
    validate(p);
    detail::require(!lanes.empty() && lanes.size() <= max_lanes,
                    "pipeline: " + std::to_string(lanes.size()) + " lanes (1 to " + std::to_string(max_lanes) +
                        " allowed)");
    const std::size_t want = capacity == 0 ? 2 * lanes.size() : capacity;
    detail::require(want >= lanes.size() && want <= max_capacity,
                    "pipeline: capacity " + std::to_string(want) + " (from the " +
                        std::to_string(lanes.size()) + " lanes to " + std::to_string(max_capacity) + " allowed)");
    for (const Backend& b : lanes) lanes_.push_back(std::make_unique<segmenter<Backend>>(p, b));
    start();
  }
  /// `lanes` lanes, each with a copy of `b` (for edgeplane::cuda give each lane its own stream
  /// through the other constructor, or the lanes share one stream and do not overlap).
  pipeline(const params& p, int lanes, const Backend& b = Backend{}, std::size_t capacity = 0)
      : pipeline(p, std::vector<Backend>(lanes > 0 ? static_cast<std::size_t>(lanes) : 0, b), capacity) {}

  static constexpr std::size_t max_lanes = 256, max_capacity = 4096;

  pipeline(const pipeline&) = delete;
  pipeline& operator=(const pipeline&) = delete;

  /// Waits for the frames the lanes are running, drops those not started, joins the threads.
  ~pipeline() {
    {
      std::lock_guard<std::mutex> lock(m_);
      stop_ = true;
    }
    work_.notify_all();
    for (std::thread& t : threads_) t.join();
  }

  std::size_t lanes() const { return lanes_.size(); }
  std::size_t capacity() const { return slots_.size(); }
  /// Frames submitted and not yet retrieved.
  std::size_t in_flight() const {
    std::lock_guard<std::mutex> lock(m_);
    return static_cast<std::size_t>(submitted_ - retrieved_);
  }
  /// No room for another frame: retrieve() one first.
  bool full() const { return in_flight() == capacity(); }

  /// submit() and retrieve() may be called from two threads (a camera callback submitting, a
  /// consumer retrieving), but each from one thread at a time.
  ///
  /// Queues a frame (host memory, any pitch; uint16 units times `metres_per_unit`, or float
  /// metres with scale 1).  The frame is copied before submit returns, so its buffer may be reused
  /// at once.  Returns the frame's sequence number (0, 1, 2, ... in submission order).  Throws
  /// edgeplane::error for an unusable frame (as segment() would) and when the pipeline is full.
  template <class In>
  std::uint64_t submit(image_view<const In> depth, float metres_per_unit, const intrinsics& k) {
    static_assert(std::is_same_v<In, std::uint16_t> || std::is_same_v<In, float>, "uint16 or float depth");
    detail::check_frame(depth, metres_per_unit, k);
    std::uint64_t seq;
    {
      std::lock_guard<std::mutex> lock(m_);
      detail::require(submitted_ - retrieved_ < slots_.size(),
                      "pipeline: full (" + std::to_string(slots_.size()) + " frames in flight): retrieve one first");
      seq = submitted_;
    }
    // The slot is free (its last frame was retrieved) and no lane touches it until it is queued.
    slot& s = slots_[seq % slots_.size()];
    const std::size_t row = sizeof(In) * static_cast<std::size_t>(depth.width);
    const std::size_t bytes = row * static_cast<std::size_t>(depth.height);
    s.depth.reserve(lanes_.front()->backend(), bytes);
    s.labels.reserve(lanes_.front()->backend(), bytes / sizeof(In) * sizeof(std::uint16_t));
    auto* dst = static_cast<unsigned char*>(s.depth.data());
    if (bytes > 0)
      for (int y = 0; y < depth.height; ++y) std::memcpy(dst + y * row, &depth(0, y), row);
    s.is_float = std::is_same_v<In, float>;
    s.scale = metres_per_unit;
    s.k = k;
    s.width = depth.width;
    s.height = depth.height;
    s.error = nullptr;
    {
      std::lock_guard<std::mutex> lock(m_);
      s.state = slot_state::queued;
      ++submitted_;
    }
    work_.notify_one();
    return seq;
  }

  /// Waits for the oldest frame in flight and hands it back: its labels into `labels` (host
  /// memory of the frame's size, any pitch) and its planes and stage times into `out`.  Returns
  /// the frame's sequence number.  Throws edgeplane::error when nothing is in flight or `labels`
  /// has the wrong size (the frame stays in flight), and rethrows what segmenting the frame threw
  /// (the frame is then retrieved).
  std::uint64_t retrieve(image_view<std::uint16_t> labels, segmentation_result& out) {
    detail::check_view(labels, "labels");
    std::uint64_t seq;
    slot* s;
    {
      std::unique_lock<std::mutex> lock(m_);
      detail::require(retrieved_ < submitted_, "pipeline: no frame in flight");
      seq = retrieved_;
      s = &slots_[seq % slots_.size()];
      detail::require(labels.width == s->width && labels.height == s->height,
                      "pipeline: frame " + std::to_string(seq) + " is " + std::to_string(s->width) + "x" +
                          std::to_string(s->height) + " but labels is " + std::to_string(labels.width) + "x" +
                          std::to_string(labels.height));
      done_.wait(lock, [&] { return s->state == slot_state::done; });
    }
    std::exception_ptr error = s->error;
    if (!error) {
      const auto* src = static_cast<const std::uint16_t*>(s->labels.data());
      if (s->width > 0)
        for (int y = 0; y < s->height; ++y)
          std::memcpy(&labels(0, y), src + static_cast<std::size_t>(y) * s->width, sizeof(std::uint16_t) * s->width);
      out.planes.assign(s->result.planes.begin(), s->result.planes.end());
      out.times = s->result.times;
      out.candidates = s->result.candidates;
      out.valid_candidates = s->result.valid_candidates;
    }
    {
      std::lock_guard<std::mutex> lock(m_);
      s->state = slot_state::free;
      ++retrieved_;
    }
    if (error) std::rethrow_exception(error);
    return seq;
  }

  /// Offline throughput: frames[i] (one camera: intrinsics k for all) into labels[i], results[i]
  /// receiving each frame's planes and times, through the lanes.  The pipeline must be empty.
  /// Throws edgeplane::error before any work when the counts differ or a frame is unusable.
  template <class In>
  void segment_batch(const std::vector<image_view<const In>>& frames, float scale, const intrinsics& k,
                     const std::vector<image_view<std::uint16_t>>& labels, std::vector<segmentation_result>& results) {
    detail::check_batch_counts(frames.size(), labels.size());
    detail::require(in_flight() == 0, "segment_batch: the pipeline has frames in flight");
    for (std::size_t i = 0; i < frames.size(); ++i) {
      detail::check_frame(frames[i], scale, k);
      detail::check_view(labels[i], "labels");
      detail::check_same_size(frames[i], labels[i], "depth", "labels");
    }
    results.resize(frames.size());
    std::size_t next_out = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (full()) {
        retrieve(labels[next_out], results[next_out]);
        ++next_out;
      }
      submit(frames[i], scale, k);
    }
    for (; next_out < frames.size(); ++next_out) retrieve(labels[next_out], results[next_out]);
  }

 private:
  enum class slot_state { free, queued, running, done };
  struct slot {
    detail::host_block<Backend> depth, labels;
    bool is_float = false;
    float scale = 1.f;
    intrinsics k{};
    int width = 0, height = 0;
    segmentation_result result;
    std::exception_ptr error;
    slot_state state = slot_state::free;
  };

  void start() {
    try {
      if constexpr (detail::has_thread_binding<Backend>) {
        const auto binding = lanes_.front()->backend().thread_binding();
        for (std::size_t i = 0; i < lanes_.size(); ++i)
          threads_.emplace_back([this, i, binding] {
            std::exception_ptr bind_error;
            try {
              lanes_[i]->backend().bind_thread(binding);
            } catch (...) {
              bind_error = std::current_exception();
            }
            lane(*lanes_[i], bind_error);
          });
      } else {
        for (std::size_t i = 0; i < lanes_.size(); ++i) threads_.emplace_back([this, i] { lane(*lanes_[i], nullptr); });
      }
    } catch (...) {  // a thread could not be started: stop those that were
      {
        std::lock_guard<std::mutex> lock(m_);
        stop_ = true;
      }
      work_.notify_all();
      for (std::thread& t : threads_) t.join();
      throw;
    }
  }

  // A lane's thread: takes the oldest queued frame, segments it, marks it done.  A lane whose
  // thread could not be bound to its backend fails every frame it takes with that error.
  void lane(segmenter<Backend>& seg, std::exception_ptr bind_error) {
    for (;;) {
      slot* s;
      {
        std::unique_lock<std::mutex> lock(m_);
        work_.wait(lock, [&] { return stop_ || started_ < submitted_; });
        if (stop_) return;
        s = &slots_[started_ % slots_.size()];
        s->state = slot_state::running;
        ++started_;
      }
      try {
        if (bind_error) std::rethrow_exception(bind_error);
        const auto labels = make_view(static_cast<std::uint16_t*>(s->labels.data()), s->width, s->height);
        if (s->is_float)
          seg.segment(make_view(static_cast<const float*>(s->depth.data()), s->width, s->height), s->scale, s->k,
                      labels, s->result);
        else
          seg.segment(make_view(static_cast<const std::uint16_t*>(s->depth.data()), s->width, s->height), s->scale,
                      s->k, labels, s->result);
      } catch (...) {
        s->error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(m_);
        s->state = slot_state::done;
      }
      done_.notify_all();
    }
  }

  std::vector<std::unique_ptr<segmenter<Backend>>> lanes_;
  std::vector<slot> slots_;
  std::vector<std::thread> threads_;
  mutable std::mutex m_;
  std::condition_variable work_, done_;
  std::uint64_t submitted_ = 0, started_ = 0, retrieved_ = 0;
  bool stop_ = false;
};

}  // namespace edgeplane
