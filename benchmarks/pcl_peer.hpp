// The PCL peer used by the comparisons (bench_pcl.cpp, edgeplane_evaluate_pcl): PCL's
// OrganizedMultiPlaneSegmentation on IntegralImageNormalEstimation normals, in the configuration
// of PCL's organized segmentation demo (average 3-D gradient normals, max depth change 0.02,
// smoothing 10; 1000 minimum inliers, 3 degrees, 2 cm; segmentAndRefine).  Single-threaded.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include <pcl/features/integral_image_normal.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/organized_multi_plane_segmentation.h>

#include "edgeplane/camera.hpp"
#include "peer_common.hpp"

namespace edgeplane_peer {

/// PCL's settings.  The defaults are its demo's; EDGEPLANE_PCL_CONFIG (for example
/// "covariance=1,smoothing=20,angular_deg=5,distance=0.03,min_inliers=300,depth_change=0.02")
/// overrides them, so the peer can be tried in other configurations with the same programs.
struct pcl_config {
  bool covariance = false;  // COVARIANCE_MATRIX normals instead of AVERAGE_3D_GRADIENT
  float depth_change = 0.02f, smoothing = 10.0f;
  unsigned min_inliers = 1000;
  double angular_deg = 3.0, distance = 0.02;
  static pcl_config from_env() {
    pcl_config c;
    for_each_setting("EDGEPLANE_PCL_CONFIG", [&](const std::string& k, double v) {
      if (k == "covariance") c.covariance = v != 0;
      if (k == "depth_change") c.depth_change = static_cast<float>(v);
      if (k == "smoothing") c.smoothing = static_cast<float>(v);
      if (k == "min_inliers") c.min_inliers = static_cast<unsigned>(v);
      if (k == "angular_deg") c.angular_deg = v;
      if (k == "distance") c.distance = v;
    });
    return c;
  }
};

class pcl_segmenter {
 public:
  explicit pcl_segmenter(const pcl_config& c = pcl_config::from_env()) {
    ne_.setNormalEstimationMethod(c.covariance ? ne_.COVARIANCE_MATRIX : ne_.AVERAGE_3D_GRADIENT);
    ne_.setMaxDepthChangeFactor(c.depth_change);
    ne_.setNormalSmoothingSize(c.smoothing);
    mps_.setMinInliers(c.min_inliers);
    mps_.setAngularThreshold(c.angular_deg * M_PI / 180.0);
    mps_.setDistanceThreshold(c.distance);
  }

  /// Segments a uint16 depth image (`scale` metres per unit, row pitch in elements); returns the
  /// number of planes.  With `labels` (row pitch `lpitch`), plane j's inliers get label j + 1 and 0
  /// elsewhere, and `planes` receives the equations.
  std::size_t run(const std::uint16_t* depth, int w, int h, std::ptrdiff_t pitch, float scale, const edgeplane::intrinsics& k,
                  std::uint16_t* labels = nullptr, std::ptrdiff_t lpitch = 0, std::vector<peer_plane>* planes = nullptr) {
    cloud_->width = static_cast<std::uint32_t>(w);
    cloud_->height = static_cast<std::uint32_t>(h);
    cloud_->is_dense = false;
    cloud_->points.resize(static_cast<std::size_t>(w) * h);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const float z = depth[static_cast<std::ptrdiff_t>(v) * pitch + u] * scale;
        pcl::PointXYZ& p = cloud_->points[static_cast<std::size_t>(v) * w + u];
        if (z > 0.f)
          p = pcl::PointXYZ((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z);
        else
          p = pcl::PointXYZ(nan, nan, nan);
      }
    ne_.setInputCloud(cloud_);
    ne_.compute(*normals_);
    mps_.setInputNormals(normals_);
    mps_.setInputCloud(cloud_);
    regions_.clear();
    coefficients_.clear();
    inliers_.clear();
    label_indices_.clear();
    boundaries_.clear();
    labels_.reset(new pcl::PointCloud<pcl::Label>);  // a fresh one per frame, as PCL's demo does (reuse crashes)
    mps_.segmentAndRefine(regions_, coefficients_, inliers_, labels_, label_indices_, boundaries_);
    if (labels) {
      for (int v = 0; v < h; ++v)
        for (int u = 0; u < w; ++u) labels[static_cast<std::ptrdiff_t>(v) * lpitch + u] = 0;
      for (std::size_t j = 0; j < inliers_.size() && j < 65535; ++j)
        for (const auto idx : inliers_[j].indices)
          labels[static_cast<std::ptrdiff_t>(idx / w) * lpitch + idx % w] = static_cast<std::uint16_t>(j + 1);
    }
    if (planes) {
      planes->clear();
      for (std::size_t j = 0; j < coefficients_.size() && j < 65535; ++j) {
        const auto& c = coefficients_[j].values;
        if (c.size() >= 4) push_plane(*planes, static_cast<std::uint16_t>(j + 1), c[0], c[1], c[2], c[3]);
      }
    }
    return inliers_.size();
  }

 private:
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::PointCloud<pcl::Normal>::Ptr normals_{new pcl::PointCloud<pcl::Normal>};
  pcl::PointCloud<pcl::Label>::Ptr labels_{new pcl::PointCloud<pcl::Label>};
  pcl::IntegralImageNormalEstimation<pcl::PointXYZ, pcl::Normal> ne_;
  pcl::OrganizedMultiPlaneSegmentation<pcl::PointXYZ, pcl::Normal, pcl::Label> mps_;
  std::vector<pcl::PlanarRegion<pcl::PointXYZ>, Eigen::aligned_allocator<pcl::PlanarRegion<pcl::PointXYZ>>> regions_;
  std::vector<pcl::ModelCoefficients> coefficients_;
  std::vector<pcl::PointIndices> inliers_, label_indices_, boundaries_;
};

}  // namespace edgeplane_peer
