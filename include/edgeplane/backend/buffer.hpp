// edgeplane: an owning array in a backend's memory.  Grows only; never shrinks, so a segmenter
// reused on frames of one size allocates nothing after the first frame.
#pragma once
#include <cstddef>
#include <utility>

namespace edgeplane {

template <class T, class Backend>
class buffer {
 public:
  buffer() = default;
  explicit buffer(Backend b) : b_(std::move(b)) {}
  buffer(const buffer&) = delete;
  buffer& operator=(const buffer&) = delete;
  buffer(buffer&& o) noexcept : b_(o.b_), p_(std::exchange(o.p_, nullptr)), n_(std::exchange(o.n_, 0)),
                                cap_(std::exchange(o.cap_, 0)) {}
  buffer& operator=(buffer&& o) noexcept {
    if (this != &o) {
      release();
      b_ = o.b_;
      p_ = std::exchange(o.p_, nullptr);
      n_ = std::exchange(o.n_, 0);
      cap_ = std::exchange(o.cap_, 0);
    }
    return *this;
  }
  ~buffer() { release(); }

  /// Makes room for n elements (contents are unspecified after a reallocation).
  void resize(std::size_t n) {
    if (n > cap_) {
      release();
      p_ = static_cast<T*>(b_.allocate(n * sizeof(T)));
      cap_ = n;
    }
    n_ = n;
  }
  T* data() const { return p_; }
  std::size_t size() const { return n_; }
  std::size_t capacity_bytes() const { return cap_ * sizeof(T); }
  const Backend& backend() const { return b_; }
  void set_backend(const Backend& b) {
    release();
    b_ = b;
  }

 private:
  void release() noexcept {
    if (p_) b_.deallocate(p_);
    p_ = nullptr;
    n_ = cap_ = 0;
  }
  Backend b_{};
  T* p_ = nullptr;
  std::size_t n_ = 0, cap_ = 0;
};

}  // namespace edgeplane
