// Writes the fuzz seed corpus from the real sample frames in examples/data (TUM RGB-D, ICL-NUIM,
// CAPE): each frame subsampled 4x (160x120) and cropped (64x48), as uint16 and as float depth,
// under several presets, plus a few degenerate frames.  Usage: edgeplane_fuzz_seeds DATA_DIR OUT_DIR
// The committed corpus in tests/fuzz/corpus was made by this program.
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

#include "fuzz_segmenter.hpp"

namespace {
struct frame {
  const char* file;
  float fx, fy, cx, cy, scale;
};

void write(const std::filesystem::path& dir, const std::string& name, const edgeplane_fuzz::input& in) {
  const auto b = in.bytes();
  std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}

edgeplane_fuzz::input from(const cv::Mat& m, int step, int x0, int y0, int w, int h, const frame& f, bool as_float,
                           std::uint8_t preset) {
  edgeplane_fuzz::input in;
  in.flags = as_float ? 1 : 0;
  in.preset = preset;
  in.width = w;
  in.height = h;
  // intrinsics of the subsampled crop: pixel (u, v) of the crop is (x0 + u*step, y0 + v*step)
  in.fx = f.fx / step;
  in.fy = f.fy / step;
  in.cx = (f.cx - x0) / step;
  in.cy = (f.cy - y0) / step;
  in.scale = f.scale;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const std::uint16_t d = m.at<std::uint16_t>(y0 + v * step, x0 + u * step);
      if (as_float) {
        const float z = d * f.scale;
        const auto* p = reinterpret_cast<const std::uint8_t*>(&z);
        in.samples.insert(in.samples.end(), p, p + 4);
      } else {
        in.samples.push_back(static_cast<std::uint8_t>(d));
        in.samples.push_back(static_cast<std::uint8_t>(d >> 8));
      }
    }
  return in;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: edgeplane_fuzz_seeds DATA_DIR OUT_DIR\n");
    return 2;
  }
  const std::filesystem::path data(argv[1]), out(argv[2]);
  std::filesystem::create_directories(out);
  const frame frames[] = {{"tum_fr3_long_office.png", 535.4f, 539.2f, 320.1f, 247.6f, 0.0002f},
                          {"icl_living_room.png", 481.2f, -480.0f, 319.5f, 239.5f, 0.0002f},
                          {"cape_depth_0.png", 575.93f, 576.41f, 315.15f, 230.59f, 0.001f}};
  int count = 0;
  for (const frame& f : frames) {
    const cv::Mat m = cv::imread((data / f.file).string(), cv::IMREAD_UNCHANGED);
    if (m.empty() || m.type() != CV_16UC1) {
      std::fprintf(stderr, "edgeplane_fuzz_seeds: cannot read %s\n", f.file);
      return 2;
    }
    const std::string stem = std::filesystem::path(f.file).stem().string();
    for (std::uint8_t preset = 0; preset < 6; ++preset) {
      write(out, stem + "_160x120_p" + std::to_string(preset), from(m, 4, 0, 0, 160, 120, f, false, preset));
      auto crop = from(m, 2, 200, 150, 64, 48, f, preset % 2, preset);
      if (preset == 0) crop.flags |= 64;  // and once more on the same segmenter
      write(out, stem + "_64x48_p" + std::to_string(preset), crop);
      count += 2;
    }
    auto par = from(m, 8, 0, 0, 80, 60, f, false, 3);
    par.flags |= 2 | 32 | 64;  // parallel, compared with the serial backend and with a second run
    write(out, stem + "_80x60_parallel", par);
    ++count;
  }
  // degenerate frames: 1x1, 1xN, Nx1, constant depth, all invalid
  edgeplane_fuzz::input one;
  one.width = one.height = 1;
  one.fx = one.fy = 500.f;
  one.samples = {0xe8, 0x03};
  write(out, "one_pixel", one);
  edgeplane_fuzz::input row = one;
  row.width = 200;
  row.samples.assign(400, 0x07);
  write(out, "one_row", row);
  edgeplane_fuzz::input col = row;
  col.width = 1;
  col.height = 200;
  write(out, "one_column", col);
  edgeplane_fuzz::input flat = one;
  flat.width = 64;
  flat.height = 48;
  for (int i = 0; i < 64 * 48; ++i) flat.samples.insert(flat.samples.end(), {0xd0, 0x07});
  write(out, "constant_2m", flat);
  flat.samples.assign(flat.samples.size(), 0);
  write(out, "all_invalid", flat);
  count += 5;
  std::printf("edgeplane_fuzz_seeds: %d seeds in %s\n", count, out.string().c_str());
  return 0;
}
