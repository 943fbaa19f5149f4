// Helpers for the runtime tests: small containers in which every frame says
// which frame it is, a check of a delivered frame's content, temp dirs, and a
// record source that injects faults around the real one.
#pragma once

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/error.h"
#include "sluice/io/writer.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::test {

// A fresh directory under the system temp dir, removed at destruction.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static int counter = 0;
    path = std::filesystem::temp_directory_path() /
           ("sluice-rt-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
            std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::filesystem::path operator/(const std::string& name) const { return path / name; }
};

// Frame f of a tiny file: particles_in(f) particles, every LOD value equal to
// f (so a decoded buffer shows which frame it holds), and one attribute equal
// to the particle's x (so the attribute stream can be checked against the
// positions it travels with).
struct TinySpec {
  uint64_t frames = 64;
  uint32_t particles = 90;  // base count; frames differ by up to 12 more
  uint32_t chunk = 32;      // particles per chunk: several chunks per frame
  bool attribute = true;
  io::PlaneCoding planes = io::PlaneCoding::Packed;
};

inline uint64_t particles_in(const TinySpec& spec, uint64_t frame) { return spec.particles + (frame * 7) % 13; }

inline io::EncodedFrame tiny_frame(const TinySpec& spec, const io::FileHeader& header, uint64_t frame) {
  const uint64_t n = particles_in(spec, frame);
  std::mt19937 rng(static_cast<uint32_t>(frame) + 1);
  std::uniform_real_distribution<float> jitter(-0.002f, 0.002f);
  std::vector<float> xyz;
  std::vector<float> x;
  for (uint64_t i = 0; i < n; ++i) {
    const float px = float(i % 5) * 0.01f + jitter(rng) + float(frame) * 0.001f;
    xyz.insert(xyz.end(), {px, float((i / 5) % 5) * 0.01f + jitter(rng), float(i / 25) * 0.01f + jitter(rng)});
    x.push_back(px);
  }
  const std::vector<uint16_t> lod(n, static_cast<uint16_t>(frame & 0xffff));
  io::FrameInput in;
  in.positions = xyz;
  in.lod = lod;
  if (spec.attribute) in.attributes.push_back(x);
  in.time = double(frame) / 30.0;
  io::EncodeOptions options;
  options.chunk_particles = spec.chunk;
  options.planes = spec.planes;
  return io::encode_frame(in, header, options);
}

inline std::filesystem::path write_tiny_file(const std::filesystem::path& path, const TinySpec& spec) {
  io::FileHeader header;
  header.particle_spacing = 0.01f;
  header.particle_radius = 0.005f;
  header.frame_rate = 30.f;
  if (spec.attribute) header.attributes.push_back({"x"});
  header.source = "runtime test: LOD value = frame number";
  io::ContainerWriter writer(path, header);
#if defined(__SANITIZE_THREAD__)
  // TSan cannot see libtbb's synchronisation: encode on this thread alone
  // (io's encoder uses TBB inside) so the setup reports nothing.
  tbb::task_arena arena(1, 1);
  arena.execute([&] {
    for (uint64_t f = 0; f < spec.frames; ++f) writer.append(tiny_frame(spec, header, f));
  });
#else
  constexpr uint64_t kBatch = 256;  // encode in parallel, append in order
  for (uint64_t first = 0; first < spec.frames; first += kBatch) {
    std::vector<io::EncodedFrame> batch(std::min(kBatch, spec.frames - first));
    tbb::parallel_for(size_t(0), batch.size(), [&](size_t i) { batch[i] = tiny_frame(spec, header, first + i); });
    for (auto& f : batch) writer.append(std::move(f));
  }
#endif
  writer.finish();
  return path;
}

// Does a delivered frame hold frame `frame`, completely?
inline ::testing::AssertionResult holds_frame(const runtime::FrameHandle& h, uint64_t frame, const TinySpec& spec) {
  if (h.empty() || h.failed()) return ::testing::AssertionFailure() << "no frame (failed or empty handle)";
  if (h.frame() != frame) return ::testing::AssertionFailure() << "handle says frame " << h.frame() << ", expected " << frame;
  const uint64_t n = particles_in(spec, frame);
  if (h.layout().particles != n) return ::testing::AssertionFailure() << "frame " << frame << " has " << h.layout().particles << " particles, expected " << n;
  const std::byte* p = h.buffers().particles.data();
  for (uint64_t i = 0; i < n; ++i) {
    uint16_t q[4];
    std::memcpy(q, p + 8 * i, 8);
    if (q[3] != (frame & 0xffff)) {
      return ::testing::AssertionFailure() << "particle " << i << " of frame " << frame << " carries LOD " << q[3]
                                           << ": the buffer holds (part of) another frame";
    }
  }
  if (spec.attribute && h.layout().attribute_streams > 0) {
    const uint16_t* a = h.buffers().attributes[0].data();
    const auto& chunks = h.header().chunks;
    for (size_t c = 0; c < chunks.size(); ++c) {
      const auto& ch = chunks[c];
      const float tolerance = 2.5f * ((ch.bounds.max[0] - ch.bounds.min[0]) + (ch.attribute_ranges[0][1] - ch.attribute_ranges[0][0])) / 65535.f + 1e-6f;
      for (uint64_t i = h.chunk_first()[c]; i < h.chunk_first()[c] + ch.particle_count; ++i) {
        uint16_t q[4];
        std::memcpy(q, p + 8 * i, 8);
        const float x = io::dequantize(q[0], ch.bounds.min[0], ch.bounds.max[0]);
        const float ax = io::dequantize(a[i], ch.attribute_ranges[0][0], ch.attribute_ranges[0][1]);
        if (std::abs(x - ax) > tolerance) {
          return ::testing::AssertionFailure() << "frame " << frame << " particle " << i << ": attribute " << ax
                                               << " does not travel with its position x " << x;
        }
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Wraps the real record source and misbehaves over one byte range.
class FaultySource final : public runtime::RecordSource {
 public:
  enum class Fault {
    Fail,     // reads touching the range throw (an I/O error)
    EndEarly, // the file seems to end where the range begins
    Dribble,  // every read returns at most 777 bytes (legal, short reads)
  };
  FaultySource(std::shared_ptr<runtime::RecordSource> inner, std::string path, Fault fault, uint64_t begin, uint64_t end)
      : inner_(std::move(inner)), path_(std::move(path)), fault_(fault), begin_(begin), end_(end) {}

  size_t read_at(std::span<std::byte> dst, uint64_t offset) override {
    const bool touches = offset < end_ && offset + dst.size() > begin_;
    switch (fault_) {
      case Fault::Fail:
        if (touches) throw io::Error({path_}, "read failed: Input/output error (injected)");
        break;
      case Fault::EndEarly:
        if (offset >= begin_) return 0;
        if (touches) dst = dst.first(begin_ - offset);
        break;
      case Fault::Dribble:
        dst = dst.first(std::min<size_t>(dst.size(), 777));
        break;
    }
    return inner_->read_at(dst, offset);
  }
  size_t alignment() const override { return inner_->alignment(); }
  std::string describe() const override { return "faulty " + inner_->describe(); }

 private:
  std::shared_ptr<runtime::RecordSource> inner_;
  std::string path_;
  Fault fault_;
  uint64_t begin_, end_;
};

// Wraps the real record source and lets only as many reads through as the
// test allows: a frame that cannot have been read yet, without timing.
class GatedSource final : public runtime::RecordSource {
 public:
  GatedSource(std::shared_ptr<runtime::RecordSource> inner, uint32_t allowed) : inner_(std::move(inner)), allowed_(allowed) {}

  size_t read_at(std::span<std::byte> dst, uint64_t offset) override {
    const uint32_t mine = reads_.fetch_add(1);
    for (uint32_t a = allowed_.load(); mine >= a; a = allowed_.load()) allowed_.wait(a);
    return inner_->read_at(dst, offset);
  }
  size_t alignment() const override { return inner_->alignment(); }
  std::string describe() const override { return "gated " + inner_->describe(); }

  void allow(uint32_t reads) {
    allowed_ += reads;
    allowed_.notify_all();
  }
  void open() { allow(1u << 30); }
  // Reads that have come to the gate and not passed it yet.
  uint32_t waiting() const {
    const uint32_t arrived = reads_.load(), allowed = allowed_.load();
    return arrived > allowed ? arrived - allowed : 0;
  }

 private:
  std::shared_ptr<runtime::RecordSource> inner_;
  std::atomic<uint32_t> allowed_;
  std::atomic<uint32_t> reads_{0};
};

// Opens a gate when leaving a scope, so the pipeline can stop.
struct OpenAtExit {
  GatedSource& gate;
  ~OpenAtExit() { gate.open(); }
};

inline void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  const auto temp = path.string() + ".tmp";
  std::ofstream(temp, std::ios::trunc) << text;
  std::filesystem::rename(temp, path);  // readers never see half a file
}

}  // namespace sluice::test
