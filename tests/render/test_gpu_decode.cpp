// The GPU decoder (render/gpu_decoder.h, shaders/decode.comp) against the
// CPU decoder (io::decode_record), bit for bit: particles and the colour
// attribute, for every chunk codec (stored, zstd planes inflated on the
// CPU, bit-packed planes, the GPU-decodable writer mode), odd chunk
// lengths around the 2048-particle tiles, every packed width 1..7, the
// synthetic pool and the bundled PySPH frames; corrupt planes give an error
// naming the chunk; no validation error.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <set>
#include <vector>

#include <xxhash.h>

#include "../io/test_util.h"
#include "render_test_util.h"
#include "sluice/bench/synth.h"
#include "sluice/io/codec.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/gpu_decode_reference.h"
#include "sluice/import/source.h"
#include "sluice/io/lod.h"
#include "sluice/render/gpu_decoder.h"
#include "sluice/render/transfer_bound.h"

namespace sluice::render {
namespace {

using testing::context;
using testing::ValidationGuard;

GpuDecoder& decoder() {
  static GpuDecoder d(context());
  return d;
}

struct CpuFrame {
  std::vector<uint64_t> particles;
  std::vector<uint16_t> attribute;
};

CpuFrame decode_on_cpu(const io::EncodedFrame& f, const io::FileHeader& h, int color) {
  CpuFrame out;
  const uint64_t n = f.header.particle_count;
  out.particles.resize(n);
  std::vector<uint64_t> starts(f.header.chunks.size());
  io::chunk_starts(f.header, starts);
  std::vector<uint16_t*> attributes(h.attributes.size(), nullptr);
  if (color >= 0) {
    out.attribute.resize(n);
    attributes[size_t(color)] = out.attribute.data();
  }
  io::decode_record(f.record, f.header, h, starts, std::as_writable_bytes(std::span(out.particles)), attributes, {});
  return out;
}

io::EncodedFrame encode(const io::ParticleFrame& frame, const io::FileHeader& h, const io::EncodeOptions& options) {
  const std::vector<uint16_t> lod = io::lod_values(frame.ids, frame.count());
  io::FrameInput in;
  in.positions = frame.positions;
  in.lod = lod;
  for (const auto& a : frame.attributes) in.attributes.push_back(a);
  return io::encode_frame(in, h, options);
}

// Decodes `f` on the GPU and expects exactly the CPU's output; returns the plan.
io::GpuDecodePlan expect_same_decode(const io::EncodedFrame& f, const io::FileHeader& h, int color, const char* what) {
  const CpuFrame cpu = decode_on_cpu(f, h, color);
  decoder().load(f.record, f.header, h, {.color_attribute = color}, true, {});
  decoder().run();
  const GpuDecodeOutput gpu = decoder().read();
  EXPECT_EQ(gpu.chunks_with_errors, 0u) << what;
  EXPECT_EQ(gpu.particles.size(), cpu.particles.size()) << what;
  size_t differ = 0, first = 0;
  for (size_t i = 0; i < std::min(gpu.particles.size(), cpu.particles.size()); ++i) {
    if (gpu.particles[i] != cpu.particles[i] && differ++ == 0) first = i;
  }
  EXPECT_EQ(differ, 0u) << what << ": particles differ; first " << first;
  EXPECT_EQ(gpu.attribute, cpu.attribute) << what;
  // The plan's own CPU reading agrees too.
  io::GpuDecodePlan plan = decoder().plan();
  std::vector<std::byte> encoded(plan.encoded_bytes());
  io::stage_frame(f.record, f.header, plan, encoded, true, {});
  std::vector<uint64_t> particles(cpu.particles.size());
  std::vector<uint16_t> attribute(cpu.attribute.size());
  io::decode_plan_on_cpu(encoded, plan, particles, attribute);
  EXPECT_EQ(particles, cpu.particles) << what;
  EXPECT_EQ(attribute, cpu.attribute) << what;
  return plan;
}

// `n` particles spread uniformly in a box: Morton deltas of every size, so
// across chunk sizes the packed planes take every width.
io::ParticleFrame uniform_frame(uint64_t n, uint32_t seed) {
  io::ParticleFrame f;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  f.attributes.resize(1);
  for (uint64_t i = 0; i < n; ++i) {
    const float x = u(rng), y = u(rng), z = u(rng);
    f.positions.insert(f.positions.end(), {x, y, z});
    f.ids.push_back(i);
    f.attributes[0].push_back(std::sin(7 * x) + y + 0.01f * u(rng));
  }
  return f;
}

TEST(GpuDecode, EveryCodecMatchesTheCpuBitForBit) {
  ValidationGuard guard;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame frame = test::lattice_frame(30000, 0.25);
  struct Mode {
    const char* name;
    io::EncodeOptions options;
  };
  std::vector<Mode> modes;
  modes.push_back({"stored", {.chunk_particles = 4096, .planes = io::PlaneCoding::Stored}});
  modes.push_back({"zstd planes (format 1.0)", {.chunk_particles = 4096, .planes = io::PlaneCoding::Zstd}});
  modes.push_back({"default (packed + zstd)", {.chunk_particles = 4096}});
  modes.push_back({"GPU-decodable (no zstd)", {.chunk_particles = 4096, .planes = io::PlaneCoding::GpuDecodable}});
  for (const Mode& m : modes) {
    const io::EncodedFrame f = encode(frame, h, m.options);
    const io::GpuDecodePlan plan = expect_same_decode(f, h, 0, m.name);
    expect_same_decode(f, h, -1, m.name);  // positions only
    std::printf("%-26s %zu chunks: planes stored %llu, packed %llu, zstd %llu (inflated %llu bytes)\n", m.name,
                plan.chunks.size(), (unsigned long long)plan.stored_planes, (unsigned long long)plan.packed_planes,
                (unsigned long long)plan.zstd_planes, (unsigned long long)plan.inflated_bytes);
    if (m.options.planes == io::PlaneCoding::Stored) {
      EXPECT_EQ(plan.packed_planes + plan.zstd_planes, 0u);
    }
    if (m.options.planes == io::PlaneCoding::GpuDecodable) {
      EXPECT_EQ(plan.zstd_planes, 0u);
      EXPECT_GT(plan.packed_planes, 0u);
    }
    if (m.options.planes == io::PlaneCoding::Zstd) {
      EXPECT_EQ(plan.packed_planes, 0u);
      EXPECT_GT(plan.zstd_planes, 0u);
    }
  }
}

TEST(GpuDecode, OddLengthsAndTheEncodersWidths) {
  ValidationGuard guard;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  std::set<uint32_t> widths;
  uint32_t seed = 1;
  // Chunks of 1 to 65,536 particles, around the 2048-particle tiles, and
  // frames whose last chunk is short.
  for (const uint32_t chunk : {1u, 7u, 9u, 255u, 2047u, 2048u, 2049u, 4099u, 16384u, 65536u}) {
    for (const bool gpu_mode : {false, true}) {
      const uint64_t n = std::min<uint64_t>(uint64_t(chunk) * 3 + 5, 150000);
      const io::ParticleFrame frame = uniform_frame(n, seed++);
      io::EncodeOptions o{.chunk_particles = chunk};
      o.planes = gpu_mode ? io::PlaneCoding::GpuDecodable : io::PlaneCoding::Packed;
      const io::EncodedFrame f = encode(frame, h, o);
      const std::string what = "chunk " + std::to_string(chunk) + (gpu_mode ? " GPU-decodable" : "");
      const io::GpuDecodePlan plan = expect_same_decode(f, h, 0, what.c_str());
      for (const io::GpuChunkPlan& c : plan.chunks) {
        for (const io::GpuPlane& p : c.planes) {
          if (p.width != 0) widths.insert(p.width);
        }
      }
    }
  }
  std::string seen;
  for (uint32_t w : widths) seen += std::to_string(w) + " ";
  std::printf("packed widths the encoder wrote: %s\n", seen.c_str());
  // Widths 1..6 come from the encoder here; 7 only by hand (below).
  for (uint32_t w = 1; w <= 4; ++w) EXPECT_TRUE(widths.count(w)) << "no plane of width " << w << " was decoded";
}

// Format 3.0: split positions decode on the GPU as on the CPU, with each
// record's fine part and without it (the coarse fill), whatever codes the
// fine part (stored on scattered data, zstd or packed on a lattice).
TEST(GpuDecode, SplitPositionsWithAndWithoutTheirFineParts) {
  ValidationGuard guard;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  ASSERT_EQ(h.version_major, 3);
  for (const bool gpu_mode : {false, true}) {
    const io::ParticleFrame frame = uniform_frame(30000, 11);
    io::EncodeOptions o{.chunk_particles = 4099};
    o.planes = gpu_mode ? io::PlaneCoding::GpuDecodable : io::PlaneCoding::Packed;
    io::EncodedFrame f = encode(frame, h, o);
    ASSERT_TRUE(f.header.split_positions);
    expect_same_decode(f, h, 0, gpu_mode ? "split, GPU-decodable, fine parts read" : "split, fine parts read");
    // Every other record without its fine part.
    for (size_t c = 0; c < f.header.chunks.size(); c += 2) f.header.chunks[c].fine.dropped = true;
    expect_same_decode(f, h, 0, gpu_mode ? "split, GPU-decodable, some coarse" : "split, some coarse");
  }
}

TEST(GpuDecode, TheSyntheticPoolMatches) {
  ValidationGuard guard;
  bench::SynthOptions so;
  so.particles = 200000;
  so.frames = 2;
  so.speed_attribute = true;
  const auto source = bench::synthetic_source(so);
  io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  h.attributes = {{"speed"}};
  const io::ParticleFrame frame = source->read(1);
  ASSERT_EQ(frame.attributes.size(), 1u);
  for (const bool zstd : {true, false}) {
    const io::EncodedFrame f = encode(frame, h, {.planes = zstd ? io::PlaneCoding::Packed : io::PlaneCoding::GpuDecodable});
    expect_same_decode(f, h, 0, zstd ? "synthetic pool, default" : "synthetic pool, GPU-decodable");
  }
}

TEST(GpuDecode, TheBundledSampleMatches) {
#if !SLUICE_WITH_VTK
  GTEST_SKIP() << "needs the VTK importer to read the sample";
#endif
  ValidationGuard guard;
  const auto source = import::open_source(std::string(SLUICE_SAMPLE_DIR) + "/*.vtu", {});
  for (const uint64_t index : {0u, 12u}) {
    const io::ParticleFrame frame = source->read(index);
    io::FileHeader h = test::test_header(io::PositionCoding::Quantized16, false);
    for (size_t a = 0; a < frame.attributes.size(); ++a) h.attributes.push_back({"attribute " + std::to_string(a)});
    for (const bool zstd : {true, false}) {
      const io::EncodedFrame f =
          encode(frame, h, {.chunk_particles = 2048, .planes = zstd ? io::PlaneCoding::Packed : io::PlaneCoding::GpuDecodable});
      for (int a = -1; a < int(h.attributes.size()); ++a) expect_same_decode(f, h, a, "bundled sample");
    }
  }
}

// One plane packed at `width` as docs/format.md lays it out (u8 width;
// groups of 8 values in `width` bytes, code 2^width - 1 for "next escape";
// the escapes), written here from the description, not by the encoder.
std::vector<std::byte> pack_by_the_format(const std::vector<uint8_t>& values, uint32_t width) {
  const uint32_t code = (1u << width) - 1;
  std::vector<std::byte> out{std::byte(width)};
  std::vector<std::byte> escapes;
  for (size_t g = 0; g < (values.size() + 7) / 8; ++g) {
    uint64_t bits = 0;
    for (size_t j = 0; j < 8 && 8 * g + j < values.size(); ++j) {
      const uint8_t v = values[8 * g + j];
      if (v >= code) escapes.push_back(std::byte(v));
      bits |= uint64_t(std::min<uint32_t>(v, code)) << (j * width);
    }
    for (uint32_t b = 0; b < width; ++b) out.push_back(std::byte(uint8_t(bits >> (8 * b))));
  }
  out.insert(out.end(), escapes.begin(), escapes.end());
  return out;
}

TEST(GpuDecode, EveryPackedWidthInEveryPlane) {
  // The encoder never writes width 7 (it saves less than a stored plane's
  // 15% threshold) and writes some widths only in some planes; the format
  // allows all, so chunks are built by hand: 10 planes (one attribute), each
  // packed at a width that moves through 1..7, a tenth of the values escapes.
  ValidationGuard guard;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  std::mt19937 rng(5);
  for (uint32_t shift = 0; shift < 7; ++shift) {
    for (const uint32_t n : {1u, 8u, 3001u, 4096u}) {
      std::vector<std::byte> record(4 * 10);
      for (uint32_t p = 0; p < 10; ++p) {
        const uint32_t width = (p + shift) % 7 + 1, code = (1u << width) - 1;
        std::vector<uint8_t> values(n);
        for (uint8_t& v : values) v = rng() % 10 == 0 ? uint8_t(code + rng() % (256 - code)) : uint8_t(rng() % code);
        const std::vector<std::byte> packed = pack_by_the_format(values, width);
        const uint32_t entry = uint32_t(packed.size()) | 0x80000000u;
        std::memcpy(record.data() + 4 * p, &entry, 4);
        record.insert(record.end(), packed.begin(), packed.end());
      }
      io::EncodedFrame f;
      io::ChunkDesc c;
      c.offset = 0;
      c.compressed_size = uint32_t(record.size());
      c.particle_count = n;
      c.codec = io::ChunkCodec::Packed;
      c.bounds.extend(0, 0, 0);
      c.bounds.extend(1, 2, 3);
      c.checksum = XXH3_64bits(record.data(), record.size());
      c.attribute_ranges.push_back({0.f, 1.f});
      f.header.particle_count = n;
      f.header.chunks.push_back(c);
      f.record = record;
      const std::string what = "hand-packed, n " + std::to_string(n) + ", shift " + std::to_string(shift);
      const io::GpuDecodePlan plan = expect_same_decode(f, h, 0, what.c_str());
      EXPECT_EQ(plan.packed_planes, 10u);
    }
  }
}

// Finds the first packed plane of chunk 0: its table entry and payload offset.
bool first_packed_plane(const io::EncodedFrame& f, size_t planes, uint64_t& at) {
  const io::ChunkDesc& c = f.header.chunks[0];
  if (c.codec != io::ChunkCodec::Packed) return false;
  uint64_t offset = c.offset + 4 * planes;
  for (size_t p = 0; p < planes; ++p) {
    uint32_t entry;
    std::memcpy(&entry, f.record.data() + c.offset + 4 * p, 4);
    if (entry & 0x80000000u) {
      at = offset;
      return true;
    }
    offset += entry;
  }
  return false;
}

TEST(GpuDecode, CorruptPlanesAreCaughtAndNamed) {
  ValidationGuard guard;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame frame = uniform_frame(5000, 7);
  io::EncodedFrame f = encode(frame, h, {.chunk_particles = 5000, .planes = io::PlaneCoding::GpuDecodable});
  uint64_t at = 0;
  // A split record (format 3.0) holds two planes fewer: its fine part has them.
  ASSERT_TRUE(first_packed_plane(f, f.header.chunks[0].fine.split() ? 8 : 10, at));

  // A flipped bit in the packed values: the checksum names the chunk.
  io::EncodedFrame bad = f;
  bad.record[at + 3] ^= std::byte{0x10};
  try {
    decoder().load(bad.record, bad.header, h, {}, true, {"x.sluice", 4, {}});
    ADD_FAILURE() << "a corrupt chunk was accepted";
  } catch (const io::Error& e) {
    EXPECT_EQ(e.where().chunk, 0u);
    EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
  }
  // Unchecked, the GPU finds escape codes that disagree with the list, or
  // the values differ; it never reads outside the record either way.
  bad.record[at + 1] = std::byte{0xff};  // every value of group 0 an escape code
  decoder().load(bad.record, bad.header, h, {}, false, {});
  decoder().run();
  EXPECT_EQ(decoder().read().chunks_with_errors, 1u);

  // A width outside 1..7 is refused on the CPU, before the GPU sees it.
  io::EncodedFrame wide = f;
  wide.record[at] = std::byte{9};
  EXPECT_THROW(decoder().load(wide.record, wide.header, h, {}, false, {}), io::Error);
  // A chunk whose payload is cut short.
  io::EncodedFrame cut = f;
  cut.header.chunks[0].compressed_size -= 1;
  EXPECT_THROW(decoder().load(cut.record, cut.header, h, {}, false, {}), io::Error);
  // And it decodes good frames afterwards.
  expect_same_decode(f, h, 0, "after corrupt frames");
}


// The copy bound the GPU bench prints: every shape (copies queued at once,
// either staging memory) times real copies and leaves nothing queued
// (the validation layer sees every target outlive its copy).
TEST(CopyBound, EveryShapeTimesItsCopies) {
  ValidationGuard guard;
  for (const StagingMemory staging : {StagingMemory::Plain, StagingMemory::Cached}) {
    for (const int in_flight : {1, 3}) {
      const double gbps = host_to_device_gbps(context(), 4 << 20, {in_flight, staging, 0.0});
      EXPECT_TRUE(std::isfinite(gbps)) << in_flight << " in flight";
      EXPECT_GT(gbps, 0.0) << in_flight << " in flight";
    }
  }
}

// The copy straight from a file's page-cache pages (what the pipeline could
// use instead of the workers' copy): the driver's answer is the figure, so
// the test checks that it is asked properly: a mapping of a file at the
// device's granularity is imported by lavapipe (a GPU driver may refuse
// file-backed pages: NVIDIA 580 answers vkAllocateMemory with
// ErrorOutOfDeviceMemory, and the refusal must name the call), and a
// misaligned pointer is refused before the driver is asked.
TEST(ImportedCopy, AFilesMappingIsImportedAndMisalignmentRefused) {
  ValidationGuard guard;
  const uint64_t alignment = import_alignment(context());
  if (alignment == 0) GTEST_SKIP() << "the device has no VK_EXT_external_memory_host";
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "sluice_import_test.bin";
  const uint64_t bytes = std::max<uint64_t>(alignment, 1 << 20) / alignment * alignment;
  {
    std::vector<char> data(bytes, 7);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    ASSERT_EQ(std::fwrite(data.data(), 1, data.size(), f), data.size());
    std::fclose(f);
  }
  const int fd = ::open(path.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  void* mapped = ::mmap(nullptr, bytes, PROT_READ, MAP_SHARED | MAP_POPULATE, fd, 0);
  ASSERT_NE(mapped, MAP_FAILED);
  const ImportedCopy good = imported_host_copy_gbps(context(), mapped, bytes, {.in_flight = 1, .seconds = 0});
  if (good.imported) {
    EXPECT_GT(good.gbps, 0.0);
  } else {
    EXPECT_NE(context().device().type, "cpu") << "lavapipe imports a file's mapping: " << good.refusal;
    EXPECT_NE(good.refusal.find("vk"), std::string::npos) << good.refusal;
    std::printf("the driver refuses a file's mapping: %s\n", good.refusal.c_str());
  }
  const ImportedCopy bad = imported_host_copy_gbps(context(), static_cast<char*>(mapped) + 1, bytes - alignment, {.in_flight = 1, .seconds = 0});
  EXPECT_FALSE(bad.imported);
  EXPECT_NE(bad.refusal.find("multiple"), std::string::npos) << bad.refusal;
  ::munmap(mapped, bytes);
  ::close(fd);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace sluice::render
