// edgeplane: the four directions along which a pixel's neighbours are read.  A direction is a
// policy: the step (dx, dy) to the "right" side; the "left" side walks (-dx, -dy).
#pragma once

namespace edgeplane::direction {
struct horizontal {
  static constexpr int dx = 1, dy = 0;
};
struct vertical {
  static constexpr int dx = 0, dy = 1;
};
/// Top-left to bottom-right.
struct left_diagonal {
  static constexpr int dx = 1, dy = 1;
};
/// Top-right to bottom-left.
struct right_diagonal {
  static constexpr int dx = -1, dy = 1;
};
}  // namespace edgeplane::direction
