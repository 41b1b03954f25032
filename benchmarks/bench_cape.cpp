// edgeplane against CAPE (Proença and Gao 2018), side by side in one run on the same frames
// (peer_ratio.hpp): the room scene at 640x480 (CAPE's 20-pixel cells divide it) and, with OpenCV,
// the three real sample frames.  Built only when CMake is given a CAPE checkout
// (EDGEPLANE_CAPE_DIR).  CAPE runs its run_cape_offline configuration without cylinders
// (cape_peer.hpp); its time includes the back-projection into its cell-ordered point cloud.  CAPE
// is single-threaded.
#include "cape_peer.hpp"
#include "peer_ratio.hpp"

int main(int argc, char** argv) {
  edgeplane::bench::register_ratios<edgeplane_peer::cape_segmenter>("cape", {{640, 480}});
  return edgeplane::bench::run_benchmarks(argc, argv);
}
