// A probe, not part of the build: ways to move a file's frames from the page
// cache into a window of frame-sized areas on T threads (GB/s, frames/s).
// It chose the pipeline's read (runtime/src/mapped_copy.h); its figures are
// in docs/measurements.md ("Reading out of the file's mapping"). Build and run (run.sh's readpath stage carries it):
//   g++ -O2 -mavx2 -std=c++20 bench/device/readpath.cpp -o .gpu/readpath -lxxhash -pthread
//   readpath FILE FRAME_BYTES THREADS...
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>
#include "probe.h"
using probe::Clock;
using probe::nt_copy;
using probe::since;

int main(int argc, char** argv) {
  if (argc < 4) { std::fprintf(stderr, "usage: readpath FILE FRAME_BYTES THREADS... \n"); return 2; }
  const std::string path = argv[1];
  const uint64_t frame = std::strtoull(argv[2], nullptr, 10);
  int fd = ::open(path.c_str(), O_RDONLY);
  struct stat st; fstat(fd, &st);
  const uint64_t size = uint64_t(st.st_size);
  const uint64_t frames = size / frame;
  const uint64_t window = 12;
  const double min_s = 2.0;
  std::vector<char*> ring(window);
  for (auto& r : ring) { r = (char*)std::aligned_alloc(4096, (frame + 4095) / 4096 * 4096); std::memset(r, 1, frame); }
  char* map = (char*)::mmap(nullptr, size, PROT_READ, MAP_SHARED | MAP_POPULATE, fd, 0);
  { volatile uint64_t s = 0; for (uint64_t i = 0; i < size; i += 4096) s = s + map[i]; }
  std::printf("file %s: %.1f MB, %llu frames of %.1f MB\n", path.c_str(), size / 1e6, (unsigned long long)frames, frame / 1e6);
  std::atomic<uint64_t> sink{0};
  auto bench = [&](const char* name, int T, uint64_t piece, auto&& body) {
    // pieces of consecutive frames from one queue (no barrier between frames)
    const uint64_t per_frame = (frame + piece - 1) / piece;
    auto t0 = Clock::now();
    uint64_t done_frames = 0;
    do {
      std::atomic<uint64_t> next{0};
      const uint64_t total = per_frame * frames;
      std::vector<std::thread> pool;
      for (int t = 0; t < T; ++t) pool.emplace_back([&] {
        for (uint64_t p; (p = next.fetch_add(1)) < total;) {
          const uint64_t f = p / per_frame, at = (p % per_frame) * piece;
          const uint64_t n = std::min(piece, frame - at);
          body(ring[(done_frames + f) % window] + at, f * frame + at, n);
        }
      });
      for (auto& t : pool) t.join();
      done_frames += frames;
    } while (since(t0) < min_s);
    const double s = since(t0);
    std::printf("%-40s T=%2d  %6.2f GB/s  %7.1f frames/s\n", name, T, double(done_frames) * frame / s / 1e9, done_frames / s);
    std::fflush(stdout);
  };
  for (int a = 3; a < argc; ++a) {
    const int T = std::atoi(argv[a]);
    // A: the current bound (8 MiB into a per-thread hot buffer)
    {
      const uint64_t piece = 8 << 20;
      std::vector<char*> own(T);
      for (auto& o : own) { o = (char*)std::aligned_alloc(4096, piece); std::memset(o, 0, piece); }
      std::atomic<int> id{0};
      thread_local int me = -1;
      bench("pread 8MiB into own hot buffer", T, piece, [&](char*, uint64_t off, uint64_t n) {
        if (me < 0 || me >= T) me = id.fetch_add(1) % T;
        pread(fd, own[me], n, off);
      });
      id = 0;
    }
    bench("pread 8MiB into window", T, 8 << 20, [&](char* d, uint64_t off, uint64_t n) { pread(fd, d, n, off); });
    bench("pread 1MiB into window", T, 1 << 20, [&](char* d, uint64_t off, uint64_t n) { pread(fd, d, n, off); });
    bench("pread 1MiB into window + xxh3 of it", T, 1 << 20, [&](char* d, uint64_t off, uint64_t n) {
      pread(fd, d, n, off); sink += XXH3_64bits(d, n); });
    bench("pread 256KiB into window + xxh3 of it", T, 256 << 10, [&](char* d, uint64_t off, uint64_t n) {
      pread(fd, d, n, off); sink += XXH3_64bits(d, n); });
    {
      std::atomic<int> id{0};
      std::vector<char*> bounce(T);
      for (auto& o : bounce) { o = (char*)std::aligned_alloc(4096, 1 << 20); std::memset(o, 0, 1 << 20); }
      thread_local int mine = -1;
      thread_local const void* owner = nullptr;
      auto my = [&]() -> char* { thread_local char* h = nullptr; if (!h) { h = (char*)std::aligned_alloc(4096, 1 << 20); std::memset(h, 0, 1 << 20); } return h; };
      for (uint64_t b : {uint64_t(256) << 10, uint64_t(1) << 20}) {
        std::string n1 = "pread " + std::to_string(b >> 10) + "KiB bounce + NT copy";
        bench(n1.c_str(), T, 8 << 20, [&](char* d, uint64_t off, uint64_t n) {
          char* h = my();
          for (uint64_t at = 0; at < n; at += b) { const uint64_t k = std::min(b, n - at); pread(fd, h, k, off + at); nt_copy(d + at, h, k); }
        });
        std::string n2 = n1 + " + xxh3";
        bench(n2.c_str(), T, 8 << 20, [&](char* d, uint64_t off, uint64_t n) {
          char* h = my();
          for (uint64_t at = 0; at < n; at += b) { const uint64_t k = std::min(b, n - at); pread(fd, h, k, off + at); nt_copy(d + at, h, k); sink += XXH3_64bits(h, k); }
        });
      }
    }
    bench("mmap memcpy 8MiB into window", T, 8 << 20, [&](char* d, uint64_t off, uint64_t n) { std::memcpy(d, map + off, n); });
    bench("mmap NT copy 8MiB into window", T, 8 << 20, [&](char* d, uint64_t off, uint64_t n) { nt_copy(d, map + off, n); });
    bench("mmap NT copy 256KiB + xxh3 of source", T, 256 << 10, [&](char* d, uint64_t off, uint64_t n) {
      nt_copy(d, map + off, n); sink += XXH3_64bits(map + off, n); });
    bench("xxh3 of window only (checksum cost)", T, 1 << 20, [&](char* d, uint64_t, uint64_t n) { sink += XXH3_64bits(d, n); });
  }
  return sink == 42 ? 1 : 0;
}
