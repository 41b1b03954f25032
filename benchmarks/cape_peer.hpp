// The CAPE peer used by the comparisons (bench_cape.cpp, edgeplane_evaluate_cape): CAPE, the
// plane and cylinder extractor of P. F. Proença and Y. Gao ("Fast Cylinder and Plane Extraction
// from Depth Cameras for Visual Odometry", IROS 2018), in the configuration of its
// run_cape_offline program (20x20-pixel cells, merge angle cos(pi/12), merge distance 50 mm) with
// cylinder detection off: edgeplane segments planes only.  Single-threaded.
//
// CAPE is not a Debian package; the programs that use this header are built only when CMake is
// given a checkout of https://github.com/pedropro/CAPE (EDGEPLANE_CAPE_DIR, see
// benchmarks/CMakeLists.txt).  None of CAPE's code is part of edgeplane.
//
// What is timed is what a CAPE user pays per frame: the back-projection of the uint16 depth image
// into CAPE's cell-ordered point cloud (millimetres) and CAPE::process.  CAPE needs the image's
// sides to be multiples of the cell size; other frames are padded with invalid (zero) depth on the
// right and bottom, and the labels cropped back.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/core.hpp>

#include "CAPE.h"
#include "edgeplane/camera.hpp"
#include "peer_common.hpp"

namespace edgeplane_peer {

/// CAPE's settings.  The defaults are run_cape_offline's; EDGEPLANE_CAPE_CONFIG (for example
/// "cell=10,cos_angle=0.97814,merge_dist=50") overrides them, as EDGEPLANE_PCL_CONFIG does PCL's.
struct cape_config {
  int cell = 20;                                              // run_cape_offline's PATCH_SIZE
  float cos_angle = static_cast<float>(0.96592582628906831);  // cos(pi / 12), its COS_ANGLE_MAX
  float merge_dist = 50.f;                                    // its MAX_MERGE_DIST (mm)
  static cape_config from_env() {
    cape_config c;
    for_each_setting("EDGEPLANE_CAPE_CONFIG", [&](const std::string& k, double v) {
      if (k == "cell" && v >= 2 && v <= 256) c.cell = static_cast<int>(v);
      if (k == "cos_angle") c.cos_angle = static_cast<float>(v);
      if (k == "merge_dist") c.merge_dist = static_cast<float>(v);
    });
    return c;
  }
};

class cape_segmenter {
 public:
  explicit cape_segmenter(const cape_config& c = cape_config::from_env()) : c_(c) {}

  /// Segments a uint16 depth image (`scale` metres per unit, row pitch in elements); returns the
  /// number of planes.  With `labels` (row pitch `lpitch`), CAPE's plane j gets label j and 0
  /// elsewhere, and `planes` receives the equations.
  std::size_t run(const std::uint16_t* depth, int w, int h, std::ptrdiff_t pitch, float scale, const edgeplane::intrinsics& k,
                  std::uint16_t* labels = nullptr, std::ptrdiff_t lpitch = 0, std::vector<peer_plane>* planes = nullptr) {
    const int cs = c_.cell, pw = (w + cs - 1) / cs * cs, ph = (h + cs - 1) / cs * cs;
    if (pw != pw_ || ph != ph_) reshape(pw, ph, k);
    if (k.fx != k_.fx || k.fy != k_.fy || k.cx != k_.cx || k.cy != k_.cy) set_intrinsics(k);
    // Back-projection straight into CAPE's layout: cell by cell (row-major cells), each cell's
    // cs x cs pixels row-major, as three columns X, Y, Z in millimetres (0 where depth is missing).
    const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(pw) * ph;
    float* X = cloud_.data();
    float* Y = X + n;
    float* Z = Y + n;
    const float to_mm = scale * 1000.f;
    const int cells_x = pw / cs;
    for (int v = 0; v < ph; ++v) {
      const int cr = v / cs, lr = v % cs;
      const float yv = ys_[static_cast<std::size_t>(v)];
      for (int cc = 0; cc < cells_x; ++cc) {
        const std::ptrdiff_t o = (static_cast<std::ptrdiff_t>(cr) * cells_x + cc) * cs * cs + lr * cs;
        for (int lc = 0; lc < cs; ++lc) {
          const int u = cc * cs + lc;
          const float z = (u < w && v < h) ? depth[static_cast<std::ptrdiff_t>(v) * pitch + u] * to_mm : 0.f;
          X[o + lc] = xs_[static_cast<std::size_t>(u)] * z;
          Y[o + lc] = yv * z;
          Z[o + lc] = z;
        }
      }
    }
    seg_.setTo(0);  // CAPE writes only the pixels it assigns (run_cape_offline makes a new image per frame)
    found_.clear();
    cylinders_.clear();
    int nr_planes = 0, nr_cylinders = 0;
    cape_->process(cloud_, nr_planes, nr_cylinders, seg_, found_, cylinders_);
    if (labels) {
      for (int v = 0; v < h; ++v) {
        const std::uint8_t* s = seg_.ptr<std::uint8_t>(v);
        std::uint16_t* l = labels + static_cast<std::ptrdiff_t>(v) * lpitch;
        for (int u = 0; u < w; ++u) l[u] = s[u];
      }
    }
    if (planes) {
      planes->clear();
      for (std::size_t j = 0; j < found_.size(); ++j) {  // (CAPE's d is in millimetres)
        const PlaneSeg& p = found_[j];
        push_plane(*planes, static_cast<std::uint16_t>(j + 1), p.normal[0], p.normal[1], p.normal[2], p.d / 1000.0);
      }
    }
    return found_.size();
  }

 private:
  void reshape(int pw, int ph, const edgeplane::intrinsics& k) {
    pw_ = pw;
    ph_ = ph;
    cloud_.resize(static_cast<Eigen::Index>(pw) * ph, 3);
    seg_ = cv::Mat(ph, pw, CV_8UC1, cv::Scalar(0));
    cape_ = std::make_unique<CAPE>(ph, pw, c_.cell, c_.cell, false, c_.cos_angle, c_.merge_dist);
    set_intrinsics(k);
  }
  void set_intrinsics(const edgeplane::intrinsics& k) {
    k_ = k;
    xs_.resize(static_cast<std::size_t>(pw_));
    ys_.resize(static_cast<std::size_t>(ph_));
    for (int u = 0; u < pw_; ++u) xs_[static_cast<std::size_t>(u)] = (static_cast<float>(u) - k.cx) / k.fx;
    for (int v = 0; v < ph_; ++v) ys_[static_cast<std::size_t>(v)] = (static_cast<float>(v) - k.cy) / k.fy;
  }

  cape_config c_;
  int pw_ = 0, ph_ = 0;
  edgeplane::intrinsics k_{};
  std::vector<float> xs_, ys_;
  Eigen::MatrixXf cloud_;
  cv::Mat seg_;
  std::unique_ptr<CAPE> cape_;
  std::vector<PlaneSeg> found_;
  std::vector<CylinderSeg> cylinders_;
};

}  // namespace edgeplane_peer
