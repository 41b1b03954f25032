// edgeplane: a random-access counting iterator.  libstdc++'s parallel algorithms run serially on
// std::views::iota (not random access in their sense), so the CPU backend counts with this.
#pragma once
#include <cstddef>
#include <cstdint>
#include <iterator>

namespace edgeplane::detail {

class counting_iterator {
 public:
  using iterator_category = std::random_access_iterator_tag;
  using value_type = std::int64_t;
  using difference_type = std::int64_t;
  using pointer = const std::int64_t*;
  using reference = std::int64_t;

  counting_iterator() = default;
  explicit counting_iterator(std::int64_t i) : i_(i) {}
  reference operator*() const { return i_; }
  reference operator[](difference_type n) const { return i_ + n; }
  counting_iterator& operator++() { ++i_; return *this; }
  counting_iterator operator++(int) { auto t = *this; ++i_; return t; }
  counting_iterator& operator--() { --i_; return *this; }
  counting_iterator operator--(int) { auto t = *this; --i_; return t; }
  counting_iterator& operator+=(difference_type n) { i_ += n; return *this; }
  counting_iterator& operator-=(difference_type n) { i_ -= n; return *this; }
  friend counting_iterator operator+(counting_iterator a, difference_type n) { return counting_iterator(a.i_ + n); }
  friend counting_iterator operator+(difference_type n, counting_iterator a) { return counting_iterator(a.i_ + n); }
  friend counting_iterator operator-(counting_iterator a, difference_type n) { return counting_iterator(a.i_ - n); }
  friend difference_type operator-(counting_iterator a, counting_iterator b) { return a.i_ - b.i_; }
  friend bool operator==(counting_iterator a, counting_iterator b) { return a.i_ == b.i_; }
  friend auto operator<=>(counting_iterator a, counting_iterator b) { return a.i_ <=> b.i_; }

 private:
  std::int64_t i_ = 0;
};

}  // namespace edgeplane::detail
