// edgeplane against PCL's OrganizedMultiPlaneSegmentation (with its IntegralImageNormalEstimation
// normals), side by side in one run on the same frames (peer_ratio.hpp): the room scene at
// 256x212, 512x424 and 640x480 and, with OpenCV, the three real sample frames.  Built only when
// PCL is found.  PCL runs the configuration of its organized segmentation demo (pcl_peer.hpp):
// average 3-D gradient normals (max depth change 0.02, smoothing 10), 1000 minimum inliers, 3
// degrees, 2 cm, with refinement; its time includes building its organized point cloud.  PCL's
// normal estimation and segmentation are single-threaded.
#include "pcl_peer.hpp"
#include "peer_ratio.hpp"

int main(int argc, char** argv) {
  edgeplane::bench::register_ratios<edgeplane_peer::pcl_segmenter>("pcl", {{256, 212}, {512, 424}, {640, 480}});
  return edgeplane::bench::run_benchmarks(argc, argv);
}
