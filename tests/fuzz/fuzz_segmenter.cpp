// libFuzzer entry point (clang -fsanitize=fuzzer,address,undefined): see fuzz_segmenter.hpp for the
// input layout and the promises checked.  Built with -DEDGEPLANE_BUILD_FUZZERS=ON and clang.
#include "fuzz_segmenter.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  edgeplane_fuzz::run_one(data, size);
  return 0;
}
