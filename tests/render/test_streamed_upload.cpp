// The streaming runtime feeding the renderer: frames the pipeline decodes
// into a StagingAllocator (copied by the GPU straight from there), or into
// host memory (copied through the renderer's staging), must render exactly
// as the same frames read and decoded by Renderer::load_frame.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "render_test_util.h"
#include "sluice/io/codec.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/reader.h"
#include "sluice/io/writer.h"
#include "sluice/render/image_io.h"
#include "sluice/render/inspection.h"
#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/render/load.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::render {
namespace {

namespace fs = std::filesystem;
using testing::context;
using testing::ValidationGuard;

constexpr uint64_t kFrames = 4;

// A falling block of 24^3 jittered particles with a height attribute, in
// chunks of 1000 particles, a different drop height per frame. Without
// `zstd_planes`, every plane is one the GPU decodes (--gpu-decodable).
fs::path write_block_file(bool zstd_planes = true) {
  const fs::path path = fs::temp_directory_path() /
                        ("sluice_streamed_" + std::to_string(::getpid()) + (zstd_planes ? "" : "_gpu") + ".sluice");
  io::FileHeader header;
  header.particle_spacing = 0.02f;
  header.particle_radius = 0.01f;
  header.frame_rate = 30;
  header.attributes.push_back({"height"});
  io::ContainerWriter writer(path, header);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.003f, 0.003f);
  for (uint64_t f = 0; f < kFrames; ++f) {
    std::vector<float> xyz, height;
    std::vector<uint16_t> lod;
    for (int i = 0; i < 24 * 24 * 24; ++i) {
      const float z = float(i / 576) * 0.02f + 0.3f - 0.05f * float(f) + jitter(rng);
      xyz.insert(xyz.end(), {float(i % 24) * 0.02f + jitter(rng), float((i / 24) % 24) * 0.02f + jitter(rng), z});
      height.push_back(z);
      lod.push_back(uint16_t(rng()));
    }
    io::FrameInput in;
    in.positions = xyz;
    in.lod = lod;
    in.attributes.push_back(height);
    in.time = double(f) / 30;
    io::EncodeOptions options;
    options.chunk_particles = 1000;
    options.planes = zstd_planes ? io::PlaneCoding::Packed : io::PlaneCoding::GpuDecodable;
    writer.append(io::encode_frame(in, header, options));
  }
  writer.finish();
  return path;
}

struct Rendered {
  std::vector<uint8_t> rgba;
  std::vector<float> depth;
  uint64_t particles = 0;
};

Rendered draw(testing::OffscreenRenderer& r, const SceneInfo& scene) {
  FluidOptions o;
  o.scalar_visibility = true;
  o.color_attribute = 0;
  const Camera cam = Camera::framing(scene.bounds, Vec3{0, 0, 1}, 160.0f / 120.0f);
  const FrameStats stats = r.render(cam, o, {});
  return {r.read_rgba8(), sluice::render::read_raw_depth(r), stats.particles};
}

// Renders every frame through a pipeline over `allocator`, handing
// `from` (the allocator again when it is a StagingAllocator) to
// commit (with `encoded` the frames stay encoded and the GPU decodes them).
std::vector<Rendered> streamed(const io::ContainerReader& reader, runtime::FrameAllocator& allocator,
                               const StagingAllocator* from, bool encoded = false, runtime::PipelineStats* stats = nullptr) {
  const SceneInfo scene = scene_info(reader);
  testing::OffscreenRenderer r(context(), scene, 160, 120);
  runtime::PipelineOptions po;
  po.decode.threads = 2;
  po.decode.attributes = std::vector<uint32_t>{0};
  po.decode.mode = (encoded) ? sluice::runtime::DecodeMode::KeepEncoded : sluice::runtime::DecodeMode::Cpu;
  po.decode.color_attribute = 0;
  runtime::Pipeline pipeline(reader, allocator, po);
  pipeline.restart({reader.frame_count(), 0, 1, 1, runtime::EndMode::Stop});
  std::vector<Rendered> out;
  while (true) {
    const runtime::NextEntry next = pipeline.wait_next();
    if (next.end) break;
    runtime::FrameHandle h = pipeline.take();
    EXPECT_FALSE(h.failed()) << (h.failed() ? h.error()->text() : "");
    if (h.failed()) break;
    EXPECT_EQ(h.gpu_plan() != nullptr, encoded);
    EXPECT_EQ(h.content(), encoded ? (h.layout().resident ? runtime::FrameContent::Relayed : runtime::FrameContent::Encoded)
                                   : runtime::FrameContent::Decoded);
    r.commit(h, 0, from);  // decoded, or kept encoded and decoded by the GPU
    out.push_back(draw(r, scene));
  }
  if (stats) *stats = pipeline.stats();
  return out;
}

class StreamedUpload : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = write_block_file();
    gpu_path_ = write_block_file(false);
  }
  static void TearDownTestSuite() {
    fs::remove(path_);
    fs::remove(gpu_path_);
  }
  static fs::path path_, gpu_path_;

  // What load_frame renders, frame by frame.
  static std::vector<Rendered> reference(const io::ContainerReader& reader) {
    const SceneInfo scene = scene_info(reader);
    testing::OffscreenRenderer r(context(), scene, 160, 120);
    std::vector<Rendered> out;
    for (uint64_t f = 0; f < reader.frame_count(); ++f) {
      sluice::render::load_frame(r, reader, f, 0);
      out.push_back(draw(r, scene));
    }
    return out;
  }

  static void expect_same(const std::vector<Rendered>& actual, const std::vector<Rendered>& expected) {
    ASSERT_EQ(actual.size(), expected.size());
    for (size_t f = 0; f < actual.size(); ++f) {
      EXPECT_EQ(actual[f].particles, 13824u) << "frame " << f;
      // Depth is a min over splats: bit-exact. Colour sums thickness with
      // atomics in any order: within a PSNR that allows only that.
      EXPECT_EQ(actual[f].depth, expected[f].depth) << "frame " << f;
      const double db = psnr({160, 120, actual[f].rgba}, {160, 120, expected[f].rgba});
      EXPECT_GE(db, 50.0) << "frame " << f;
    }
    // Frames differ from each other (so equality above means something).
    EXPECT_NE(expected[0].depth, expected[1].depth);
  }
};
fs::path StreamedUpload::path_, StreamedUpload::gpu_path_;

TEST_F(StreamedUpload, FromStagingMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(path_);
  const std::vector<Rendered> expected = reference(reader);
  StagingAllocator staging(context());
  expect_same(streamed(reader, staging, &staging), expected);
  EXPECT_EQ(staging.fallback_allocations(), 0u);
  EXPECT_GT(staging.peak_held_bytes(), 13824u * 8);
}

TEST_F(StreamedUpload, FromHostMemoryMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(path_);
  const std::vector<Rendered> expected = reference(reader);
  runtime::HostFrameAllocator host;
  expect_same(streamed(reader, host, nullptr), expected);
}

// Kept encoded (the file's zstd planes inflated by the workers, the rest
// as read) and decoded on the GPU: the same pictures.
TEST_F(StreamedUpload, EncodedFromStagingMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(path_);
  const std::vector<Rendered> expected = reference(reader);
  StagingAllocator staging(context());
  expect_same(streamed(reader, staging, &staging, true), expected);
  EXPECT_EQ(staging.fallback_allocations(), 0u);
}

TEST_F(StreamedUpload, EncodedFromHostMemoryMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(path_);
  const std::vector<Rendered> expected = reference(reader);
  runtime::HostFrameAllocator host;
  expect_same(streamed(reader, host, nullptr, true), expected);
}

// A resident window (frame_allocator.h): the frames' pieces go through the ring
// into device memory as they are read, planned chunk by chunk, and the
// GPU decodes them there. The same pictures, every frame relayed.
TEST_F(StreamedUpload, RelayedIntoDeviceMemoryMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(gpu_path_);
  const std::vector<Rendered> expected = reference(reader);
  StagingAllocator staging(context(), {.resident = true});
  ASSERT_NE(staging.relay(), nullptr);
  runtime::PipelineStats stats;
  expect_same(streamed(reader, staging, &staging, true, &stats), expected);
  EXPECT_EQ(stats.frames_relayed, kFrames);
  EXPECT_EQ(stats.frames_read, kFrames);
}

// The ring in anonymous memory the device imports (RingMemory::Imported;
// lavapipe offers VK_EXT_external_memory_host): the same pictures.
TEST_F(StreamedUpload, RelayedThroughAnImportedRingMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(gpu_path_);
  const std::vector<Rendered> expected = reference(reader);
  StagingAllocator staging(context(), {.resident = true, .ring_memory = RingMemory::Imported});
  ASSERT_TRUE(staging.ring_imported()) << "the device did not import the ring";
  runtime::PipelineStats stats;
  expect_same(streamed(reader, staging, &staging, true, &stats), expected);
  EXPECT_EQ(stats.frames_relayed, kFrames);
  StagingAllocator driver(context(), {.resident = true});
  EXPECT_FALSE(driver.ring_imported());
}

// Pieces smaller than a chunk (a chunk here is about 5 KB): each chunk is
// read whole on its own and sent in parts, several slots at once.
TEST_F(StreamedUpload, RelayedInPiecesSmallerThanAChunkMatchesLoadFrame) {
  ValidationGuard guard;
  const io::ContainerReader reader(gpu_path_);
  const std::vector<Rendered> expected = reference(reader);
  StagingAllocator staging(context(), {.resident = true, .ring_slots = 3, .ring_piece_bytes = 4096});
  runtime::PipelineStats stats;
  expect_same(streamed(reader, staging, &staging, true, &stats), expected);
  EXPECT_EQ(stats.frames_relayed, kFrames);
}

// A file with zstd planes (the mixed rule: the CPU inflates them into the
// area, so the record must be on the host): the first frame relayed meets
// one, is read again into host staging, and the rest are never relayed.
TEST_F(StreamedUpload, RelayMeetingZstdPlanesFallsBackToHostStaging) {
  ValidationGuard guard;
  const io::ContainerReader reader(path_);
  const std::vector<Rendered> expected = reference(reader);
  StagingAllocator staging(context(), {.resident = true});
  runtime::PipelineStats stats;
  expect_same(streamed(reader, staging, &staging, true, &stats), expected);
  EXPECT_EQ(stats.frames_relayed, 0u);
  EXPECT_EQ(stats.frames_failed, 0u);
}

// A corrupt chunk in a relayed frame: that frame fails, naming the chunk;
// the others arrive and render as before.
TEST_F(StreamedUpload, RelayedCorruptChunkFailsItsFrameOnly) {
  ValidationGuard guard;
  const fs::path copy = fs::path(gpu_path_).replace_extension(".corrupt.sluice");
  fs::copy_file(gpu_path_, copy, fs::copy_options::overwrite_existing);
  std::vector<Rendered> expected;
  uint64_t at = 0;
  {
    const io::ContainerReader reader(gpu_path_);
    expected = reference(reader);
    const std::vector<std::byte> record = reader.read_record(2);
    const io::FrameHeader header = reader.parse_record(2, record);
    const io::ChunkDesc& chunk = header.chunks[3];
    at = reader.index().frames[2].offset + chunk.offset + chunk.compressed_size / 2;
  }
  {
    std::FILE* f = std::fopen(copy.c_str(), "r+b");
    ASSERT_NE(f, nullptr);
    std::fseek(f, long(at), SEEK_SET);
    const int byte = std::fgetc(f);
    std::fseek(f, long(at), SEEK_SET);
    std::fputc(byte ^ 0x5a, f);
    std::fclose(f);
  }
  const io::ContainerReader reader(copy);
  const SceneInfo scene = scene_info(reader);
  testing::OffscreenRenderer r(context(), scene, 160, 120);
  StagingAllocator staging(context(), {.resident = true});
  runtime::PipelineOptions po;
  po.decode.mode = sluice::runtime::DecodeMode::KeepEncoded;
  po.decode.color_attribute = 0;
  runtime::Pipeline pipeline(reader, staging, po);
  pipeline.restart({reader.frame_count(), 0, 1, 1, runtime::EndMode::Stop});
  for (uint64_t f = 0; f < kFrames; ++f) {
    ASSERT_FALSE(pipeline.wait_next().end);
    runtime::FrameHandle h = pipeline.take();
    if (f == 2) {
      ASSERT_TRUE(h.failed());
      EXPECT_EQ(h.error()->where.frame, 2u);
      EXPECT_EQ(h.error()->where.chunk, 3u);
      EXPECT_NE(h.error()->message.find("checksum"), std::string::npos) << h.error()->text();
      continue;
    }
    ASSERT_FALSE(h.failed()) << h.error()->text();
    r.commit(h, 0, &staging);
    EXPECT_EQ(draw(r, scene).depth, expected[f].depth) << "frame " << f;
  }
  EXPECT_EQ(pipeline.stats().frames_relayed, kFrames - 1);
  fs::remove(copy);
}

// A host's own frame as plain data (FrameUpload from host memory: a decoded
// frame, and the same frame kept encoded with its plan) draws what
// load_frame draws; uploads that do not add up are refused by name, before
// anything is submitted, and the renderer goes on drawing.
TEST_F(StreamedUpload, AHostsPlainFrameMatchesLoadFrameAndBadOnesAreRefused) {
  ValidationGuard guard;
  const io::ContainerReader reader(gpu_path_);
  const std::vector<Rendered> expected = reference(reader);
  const SceneInfo scene = scene_info(reader);
  testing::OffscreenRenderer r(context(), scene, 160, 120);

  const io::DecodedFrame decoded = io::decode_frame(reader, 1);  // the layers load_frame draws
  FrameUpload good;
  good.header = &decoded.header;
  good.chunk_first = decoded.chunk_first;
  good.particles.host = decoded.particles;
  good.color.host = std::as_bytes(std::span(decoded.attributes[0]));
  good.color_attribute = 0;
  r.renderer.wait_upload(r.renderer.commit(good));
  EXPECT_EQ(draw(r, scene).depth, expected[1].depth) << "decoded, from host memory";

  const std::vector<std::byte> record = reader.read_record(2);
  io::FrameHeader header = reader.parse_record(2, record);
  io::keep_layers(header, io::LayerSet::particles());
  io::GpuDecodePlan plan;
  io::plan_gpu_decode(record, header, reader.header(), {.color_attribute = 0}, plan, reader.location(2));
  std::vector<std::byte> staged(plan.staged_bytes());
  io::stage_frame(record, header, plan, staged, true, reader.location(2));
  std::vector<uint64_t> first(header.chunks.size());
  io::chunk_starts(header, first);
  FrameUpload encoded;
  encoded.header = &header;
  encoded.chunk_first = first;
  encoded.particles.host = staged;
  encoded.color_attribute = 0;
  encoded.plan = &plan;
  r.renderer.wait_upload(r.renderer.commit(encoded));
  EXPECT_EQ(draw(r, scene).depth, expected[2].depth) << "encoded, from host memory";

  const auto refused = [&](FrameUpload bad, const std::string& what) {
    try {
      r.renderer.commit(bad);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  FrameUpload bad = good;
  bad.header = nullptr;
  refused(bad, "without its header");
  bad = good;
  bad.chunk_first = std::span(decoded.chunk_first).first(1);
  refused(bad, "one first index per chunk");
  bad = good;
  bad.particles.host = bad.particles.host.first(bad.particles.host.size() / 2);
  refused(bad, "particle bytes are fewer");
  bad = good;
  bad.color.host = bad.color.host.first(8);
  refused(bad, "fewer colour values");
  bad = encoded;
  bad.particles.host = bad.particles.host.first(16);
  refused(bad, "staged area is too small");
  bad = encoded;
  bad.particles = {};
  bad.resident = {.buffer = reinterpret_cast<VkBuffer>(uintptr_t(1)), .address = 0, .bytes = plan.staged_bytes()};
  refused(bad, "without its device address");  // checked before the handle is used
  bad.resident.bytes = 16;
  refused(bad, "resident area is too small");

  r.renderer.wait_upload(r.renderer.commit(good));
  EXPECT_EQ(draw(r, scene).depth, expected[1].depth) << "after the refusals";
}

// Seeking while frames are relayed: reads cut short leave copies in flight
// into areas the next frames reuse. Every frame that arrives, whatever the
// seeks, renders as load_frame renders it.
TEST_F(StreamedUpload, RelayedFramesSurviveSeeks) {
  ValidationGuard guard;
  const io::ContainerReader reader(gpu_path_);
  const std::vector<Rendered> expected = reference(reader);
  const SceneInfo scene = scene_info(reader);
  testing::OffscreenRenderer r(context(), scene, 160, 120);
  StagingAllocator staging(context(), {.resident = true, .ring_slots = 2, .ring_piece_bytes = 8192});
  runtime::PipelineOptions po;
  po.decode.mode = sluice::runtime::DecodeMode::KeepEncoded;
  po.decode.color_attribute = 0;
  runtime::Pipeline pipeline(reader, staging, po);
  uint64_t drawn = 0;
  for (int seek = 0; seek < 12; ++seek) {
    const uint64_t start = uint64_t(seek * 5) % kFrames;
    pipeline.restart({reader.frame_count(), int64_t(start), seek % 2 ? -1 : 1, 1, runtime::EndMode::Loop});
    for (int taken = 0; taken < 1 + seek % 3; ++taken) {
      ASSERT_FALSE(pipeline.wait_next().end);
      runtime::FrameHandle h = pipeline.take();
      ASSERT_FALSE(h.failed()) << h.error()->text();
      r.commit(h, 0, &staging);
      EXPECT_EQ(draw(r, scene).depth, expected[h.frame()].depth) << "seek " << seek << ", frame " << h.frame();
      ++drawn;
    }
  }
  EXPECT_GE(drawn, 12u);
  EXPECT_GT(pipeline.stats().frames_relayed, 0u);
}

}  // namespace
}  // namespace sluice::render
