// edgeplane: the one exception type thrown for bad arguments, and the one for backend failures.
#pragma once
#include <stdexcept>
#include <string>

namespace edgeplane {

/// Thrown by every public entry point when an argument is unusable (sizes that disagree, null
/// data, non-finite intrinsics, thresholds out of range).  The message names the argument and
/// its value.  Data problems (all-invalid frames, NaN depth) are not errors: they give results.
class error : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Thrown when a backend call fails (a CUDA call returned an error: the message carries its name).
class backend_error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
[[noreturn]] inline void fail(const std::string& what) { throw error("edgeplane: " + what); }
inline void require(bool ok, const std::string& what) {
  if (!ok) fail(what);
}
}  // namespace detail
}  // namespace edgeplane
