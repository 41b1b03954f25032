// Replays fuzz inputs through the same checks as the fuzzer, with any compiler (ctest runs it over
// tests/fuzz/corpus and tests/fuzz/regressions).  Usage: edgeplane_fuzz_replay FILE_OR_DIR...
// -v prints each input's plane count (-1: rightly rejected).  Exit 0 when every input kept every
// promise; a broken promise aborts.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "fuzz_segmenter.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  bool verbose = false;
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "-v") {
      verbose = true;
      continue;
    }
    const fs::path p(argv[a]);
    if (fs::is_directory(p)) {
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
    } else if (fs::is_regular_file(p)) {
      files.push_back(p);
    } else {
      std::fprintf(stderr, "edgeplane_fuzz_replay: '%s' is not a file or directory\n", argv[a]);
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "edgeplane_fuzz_replay: no inputs\n");
    return 2;
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const int planes = edgeplane_fuzz::run_one(bytes.data(), bytes.size());
    if (verbose) std::printf("%s: %d\n", f.filename().string().c_str(), planes);
  }
  std::printf("edgeplane_fuzz_replay: %zu inputs, every promise kept\n", files.size());
  return 0;
}
