// A battery of malformed inputs for the edgeplane_segment command line: every bad file or argument
// must end in exit status 2 with exactly one line on stderr ("edgeplane_segment: error: ..."),
// never a signal, a core dump or a second message (libpng's own complaints included); good inputs,
// however small, must succeed.  The PNG files are written here by a minimal encoder (stored
// deflate blocks), so the battery needs nothing but the program.
//   Usage: edgeplane_cli_tests PATH/TO/edgeplane_segment WORK_DIR
// Prints one line per case and "N passed, N failed"; exit 0 when all passed.
#include <sys/wait.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using bytes = std::vector<unsigned char>;

std::uint32_t crc32(const unsigned char* p, std::size_t n) {
  std::uint32_t c = 0xffffffffu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xffffffffu;
}
void put32(bytes& b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<unsigned char>(v >> s));
}
void chunk(bytes& png, const char* type, const bytes& data) {
  put32(png, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = png.size();
  png.insert(png.end(), type, type + 4);
  png.insert(png.end(), data.begin(), data.end());
  put32(png, crc32(&png[start], png.size() - start));
}
/// zlib stream of stored (uncompressed) deflate blocks.
bytes zlib_stored(const bytes& raw) {
  bytes z{0x78, 0x01};
  std::size_t pos = 0;
  do {
    const std::size_t len = std::min<std::size_t>(65535, raw.size() - pos);
    const bool last = pos + len == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<unsigned char>(len));
    z.push_back(static_cast<unsigned char>(len >> 8));
    z.push_back(static_cast<unsigned char>(~len));
    z.push_back(static_cast<unsigned char>((~len) >> 8));
    z.insert(z.end(), raw.begin() + static_cast<std::ptrdiff_t>(pos), raw.begin() + static_cast<std::ptrdiff_t>(pos + len));
    pos += len;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  put32(z, (b << 16) | a);
  return z;
}
/// A PNG of w x h with the given bit depth and colour type; `value` fills every sample.
bytes make_png(std::uint32_t w, std::uint32_t h, int bit_depth, int colour_type, std::uint16_t value = 1000,
               bool with_data = true) {
  bytes png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  bytes ihdr;
  put32(ihdr, w);
  put32(ihdr, h);
  ihdr.insert(ihdr.end(), {static_cast<unsigned char>(bit_depth), static_cast<unsigned char>(colour_type), 0, 0, 0});
  chunk(png, "IHDR", ihdr);
  if (colour_type == 3) chunk(png, "PLTE", bytes{0, 0, 0, 255, 255, 255});
  if (with_data) {
    const int channels = colour_type == 2 ? 3 : colour_type == 4 ? 2 : colour_type == 6 ? 4 : 1;
    const std::size_t row = static_cast<std::size_t>(w) * channels * (bit_depth / 8);
    bytes raw;
    for (std::uint32_t y = 0; y < h; ++y) {
      raw.push_back(0);  // filter: none
      for (std::size_t x = 0; x < row; x += bit_depth / 8) {
        if (bit_depth == 16) {
          raw.push_back(static_cast<unsigned char>(value >> 8));
          raw.push_back(static_cast<unsigned char>(value));
        } else {
          raw.push_back(colour_type == 3 ? 1 : static_cast<unsigned char>(value));
        }
      }
    }
    chunk(png, "IDAT", zlib_stored(raw));
  } else {
    chunk(png, "IDAT", bytes{0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0, 0, 0, 1});
  }
  chunk(png, "IEND", {});
  return png;
}
void write_file(const fs::path& p, const bytes& b) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}
std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct runner {
  std::string program;
  fs::path work;
  int passed = 0, failed = 0;

  /// Runs the program with `args`; expects exit status `want` (2: one error line on stderr).
  void expect(const std::string& name, const std::vector<std::string>& args, int want) {
    std::string cmd = "exec " + quote(program);
    for (const auto& a : args) cmd += " " + quote(a);
    const fs::path err = work / "stderr.txt", out = work / "stdout.txt";
    cmd += " >" + quote(out.string()) + " 2>" + quote(err.string()) + " </dev/null";
    const int status = std::system(cmd.c_str());
    std::string why;
    if (status == -1 || !WIFEXITED(status)) {
      why = WIFSIGNALED(status) ? "killed by signal " + std::to_string(WTERMSIG(status)) : "did not run";
    } else if (WEXITSTATUS(status) != want) {
      why = "exit status " + std::to_string(WEXITSTATUS(status)) + ", expected " + std::to_string(want);
    } else if (want == 2) {
      const std::string e = read_file(err);
      const std::string prefix = "edgeplane_segment: error: ";
      const auto newline = e.find('\n');
      if (e.compare(0, prefix.size(), prefix) != 0)
        why = "stderr does not start with '" + prefix + "'";
      else if (newline == std::string::npos || newline + 1 != e.size())
        why = "stderr is not exactly one line";
    }
    if (why.empty()) {
      ++passed;
      std::printf("ok      %s\n", name.c_str());
    } else {
      ++failed;
      std::printf("FAILED  %s: %s\n  stderr: %s\n", name.c_str(), why.c_str(), read_file(work / "stderr.txt").c_str());
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: edgeplane_cli_tests PATH/TO/edgeplane_segment WORK_DIR\n");
    return 2;
  }
  runner r{argv[1], argv[2]};
  fs::remove_all(r.work);
  fs::create_directories(r.work);
  auto file = [&](const std::string& name, const bytes& b) {
    const fs::path p = r.work / name;
    write_file(p, b);
    return p.string();
  };
  const std::vector<std::string> k{"--fx", "365", "--fy", "365", "--cx", "32", "--cy", "24", "--depth-scale", "0.001"};
  auto with_k = [&](std::vector<std::string> a) {
    a.insert(a.end(), k.begin(), k.end());
    return a;
  };

  const bytes good = make_png(64, 48, 16, 0, 2000);
  const std::string good_path = file("good.png", good);

  // ---- bad files ------------------------------------------------------------------------------
  r.expect("missing file", with_k({(r.work / "nope.png").string()}), 2);
  r.expect("empty file", with_k({file("empty.png", {})}), 2);
  fs::create_directories(r.work / "dir.png");
  r.expect("a directory", with_k({(r.work / "dir.png").string()}), 2);
  r.expect("a text file", with_k({file("text.png", bytes{'h', 'e', 'l', 'l', 'o', '\n'})}), 2);
  r.expect("a JPEG named .png", with_k({file("jpeg.png", bytes{0xff, 0xd8, 0xff, 0xe0, 0, 0x10, 'J', 'F', 'I', 'F', 0})}), 2);
  r.expect("only the PNG signature", with_k({file("sig.png", bytes(good.begin(), good.begin() + 8))}), 2);
  r.expect("truncated to half", with_k({file("half.png", bytes(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(good.size() / 2)))}), 2);
  r.expect("truncated by one byte", with_k({file("short.png", bytes(good.begin(), good.end() - 1))}), 2);
  {
    bytes b = good;
    b[60] ^= 0x5a;  // inside IDAT: the chunk's CRC no longer matches
    r.expect("corrupt CRC", with_k({file("crc.png", b)}), 2);
  }
  {
    // IDAT whose CRC is right but whose zlib data are garbage: libpng itself fails
    bytes png(good.begin(), good.begin() + 33);  // signature + IHDR
    bytes junk(200);
    for (std::size_t i = 0; i < junk.size(); ++i) junk[i] = static_cast<unsigned char>(i * 37 + 11);
    chunk(png, "IDAT", junk);
    chunk(png, "IEND", {});
    r.expect("corrupt compressed data", with_k({file("zlib.png", png)}), 2);
  }
  r.expect("IDAT shorter than the image", with_k({file("shortdata.png", make_png(64, 48, 16, 0, 1000, false))}), 2);
  r.expect("8-bit greyscale", with_k({file("grey8.png", make_png(64, 48, 8, 0))}), 2);
  r.expect("8-bit RGB", with_k({file("rgb8.png", make_png(64, 48, 8, 2))}), 2);
  r.expect("16-bit RGB", with_k({file("rgb16.png", make_png(64, 48, 16, 2))}), 2);
  r.expect("16-bit grey + alpha", with_k({file("ga16.png", make_png(64, 48, 16, 4))}), 2);
  r.expect("16-bit RGBA", with_k({file("rgba16.png", make_png(16, 12, 16, 6))}), 2);
  r.expect("palette", with_k({file("palette.png", make_png(64, 48, 8, 3))}), 2);
  r.expect("zero width", with_k({file("zero.png", make_png(0, 48, 16, 0, 1000, false))}), 2);
  r.expect("30000x30000 header, no data", with_k({file("huge.png", make_png(30000, 30000, 16, 0, 1000, false))}), 2);
  r.expect("2^31-1 square header", with_k({file("max.png", make_png(0x7fffffffu, 0x7fffffffu, 16, 0, 1000, false))}), 2);
  r.expect("one bad file among good ones", with_k({good_path, file("bad2.png", {})}), 2);

  // ---- bad arguments ---------------------------------------------------------------------------
  r.expect("no arguments", {}, 2);
  r.expect("no intrinsics", {good_path}, 2);
  r.expect("fx = 0", {good_path, "--fx", "0", "--fy", "365", "--cx", "32", "--cy", "24", "--depth-scale", "0.001"}, 2);
  r.expect("fx = nan", {good_path, "--fx", "nan", "--fy", "365", "--cx", "32", "--cy", "24", "--depth-scale", "0.001"}, 2);
  r.expect("fy = inf", {good_path, "--fx", "365", "--fy", "inf", "--cx", "32", "--cy", "24", "--depth-scale", "0.001"}, 2);
  r.expect("cx = 1e99 (overflows float)", {good_path, "--fx", "365", "--fy", "365", "--cx", "1e99", "--cy", "24", "--depth-scale", "0.001"}, 2);
  r.expect("fx not a number", {good_path, "--fx", "abc", "--fy", "365", "--cx", "32", "--cy", "24", "--depth-scale", "0.001"}, 2);
  r.expect("depth scale 0", {good_path, "--fx", "365", "--fy", "365", "--cx", "32", "--cy", "24", "--depth-scale", "0"}, 2);
  r.expect("depth scale negative", {good_path, "--fx", "365", "--fy", "365", "--cx", "32", "--cy", "24", "--depth-scale", "-0.001"}, 2);
  r.expect("missing depth scale", {good_path, "--fx", "365", "--fy", "365", "--cx", "32", "--cy", "24"}, 2);
  r.expect("option without its value", with_k({good_path, "--preset"}), 2);
  r.expect("unknown option", with_k({good_path, "--frobnicate"}), 2);
  r.expect("unknown preset", with_k({good_path, "--preset", "kinect9"}), 2);
  r.expect("unknown backend", with_k({good_path, "--backend", "fpga"}), 2);
  r.expect("repeat -3", with_k({good_path, "--repeat", "-3"}), 2);
  r.expect("repeat not a number", with_k({good_path, "--repeat", "lots"}), 2);
  r.expect("out-dir under a regular file", with_k({good_path, "--out-dir", good_path + "/sub"}), 2);
  r.expect("labels-out in a missing directory", with_k({good_path, "--labels-out", (r.work / "no/such/l.png").string()}), 2);

  // ---- good inputs, however small ---------------------------------------------------------------
  r.expect("a good 64x48 frame", with_k({good_path, "--out-dir", (r.work / "out").string(), "--quiet"}), 0);
  r.expect("a 1x1 frame", with_k({file("one.png", make_png(1, 1, 16, 0, 1500)), "--quiet"}), 0);
  r.expect("a 1x300 frame", with_k({file("row.png", make_png(300, 1, 16, 0, 1500)), "--quiet"}), 0);
  r.expect("an all-zero frame", with_k({file("zeros.png", make_png(64, 48, 16, 0, 0)), "--quiet"}), 0);
  r.expect("saturated depth (65535)", with_k({file("sat.png", make_png(64, 48, 16, 0, 65535)), "--quiet"}), 0);
  const bool labels_written = fs::exists(r.work / "out" / "good_labels.png") && fs::exists(r.work / "out" / "good_planes.json");
  if (labels_written) {
    ++r.passed;
    std::printf("ok      the good frame's labels and planes were written\n");
  } else {
    ++r.failed;
    std::printf("FAILED  the good frame's labels and planes were not written\n");
  }
  std::printf("%d passed, %d failed\n", r.passed, r.failed);
  return r.failed == 0 ? 0 : 1;
}
