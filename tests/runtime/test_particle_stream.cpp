// runtime::ParticleStream: frames through the prefetch pipeline as
// world-unit arrays, equal to io::read_particles frame by frame, reading
// only the tiers a uniform LOD level keeps, reusing the arrays handed back,
// and reporting a damaged frame with its file, frame and chunk.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>

#include "runtime_test_util.h"
#include "sluice/io/lod.h"
#include "sluice/io/particles.h"
#include "sluice/runtime/particle_stream.h"

using namespace sluice;

namespace {

// Scattered particles with random ids (LOD tiers pay there) and one attribute.
std::filesystem::path scattered_file(const std::filesystem::path& path, uint64_t frames, uint64_t n) {
  io::FileHeader h;
  h.particle_spacing = 0.01f;
  h.particle_radius = 0.005f;
  h.attributes.push_back({"speed"});
  io::ContainerWriter w(path, h);
  for (uint64_t f = 0; f < frames; ++f) {
    std::mt19937 rng(uint32_t(f) + 7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<float> xyz, speed;
    std::vector<uint64_t> ids;
    for (uint64_t i = 0; i < n; ++i) {
      xyz.insert(xyz.end(), {u(rng), u(rng), 0.3f * u(rng)});
      speed.push_back(float(f) + u(rng));
      ids.push_back(i * 2654435761u + 17);
    }
    const std::vector<uint16_t> lod = io::lod_values(ids, n);
    io::FrameInput in;
    in.positions = xyz;
    in.lod = lod;
    in.attributes.push_back(speed);
    in.time = 0.1 * double(f);
    io::EncodeOptions o;
    o.chunk_particles = 4096;
    w.append(io::encode_frame(in, h, o));
  }
  w.finish();
  return path;
}

TEST(ParticleStream, FramesEqualReadParticlesInOrder) {
  test::TempDir dir;
  const auto reader = std::make_shared<io::ContainerReader>(scattered_file(dir / "s.sluice", 9, 20000));
  io::ParticleQuery q;
  q.attributes = {0};
  runtime::ParticleStream stream(reader, {1, 9, 2}, q, 64 << 20);
  EXPECT_EQ(stream.remaining(), 4u);
  io::ParticleArrays spare;
  for (uint64_t f : {1u, 3u, 5u, 7u}) {
    ASSERT_EQ(stream.next_frame(), f);
    std::optional<runtime::StreamedFrame> got = stream.next(std::move(spare));
    ASSERT_TRUE(got);
    EXPECT_EQ(got->index, f);
    const io::ParticleArrays want = io::read_particles(*reader, f, q);
    EXPECT_EQ(got->arrays.positions, want.positions);
    EXPECT_EQ(got->arrays.lod, want.lod);
    EXPECT_EQ(got->arrays.attributes, want.attributes);
    EXPECT_EQ(got->arrays.time, want.time);
    spare = std::move(got->arrays);  // the next frame takes this memory over
  }
  EXPECT_FALSE(stream.next());
  EXPECT_EQ(stream.remaining(), 0u);
}

// Lent frames: the workers' world-unit arrays in the pipeline's buffers,
// equal to read_particles; the consumer may hold most_lent() of them while
// it asks for the next, and giving them back lets the stream go on.
TEST(ParticleStream, LentFramesEqualReadParticlesWhileHeld) {
  test::TempDir dir;
  const auto reader = std::make_shared<io::ContainerReader>(scattered_file(dir / "s.sluice", 12, 20000));
  io::ParticleQuery q;
  q.attributes = {0};
  q.lod_level = 0.5f;
  runtime::ParticleStream stream(reader, {0, 12, 1}, q, 64 << 20, 8);
  ASSERT_GE(stream.most_lent(), 2u);
  std::vector<runtime::LentFrame> held;
  uint64_t frame = 0;
  while (auto lent = stream.next_lent()) {
    EXPECT_EQ(lent->index, frame);
    const io::ParticleArrays want = io::read_particles(*reader, frame, q);
    const io::ParticleSpans& got = lent->arrays;
    ASSERT_EQ(got.count, want.count());
    EXPECT_EQ(std::vector<float>(got.positions, got.positions + 3 * got.count), want.positions);
    EXPECT_EQ(std::vector<uint16_t>(got.lod, got.lod + got.count), want.lod);
    EXPECT_EQ(std::vector<uint8_t>(got.layer, got.layer + got.count), want.layer);
    ASSERT_EQ(got.attributes.size(), 1u);
    EXPECT_EQ(std::vector<float>(got.attributes[0], got.attributes[0] + got.count), want.attributes[0]);
    EXPECT_EQ(lent->time, want.time);
    EXPECT_EQ(lent->handle.content(), runtime::FrameContent::World);
    held.push_back(std::move(*lent));
    if (held.size() > stream.most_lent()) held.erase(held.begin());  // most_lent() held at the next call
    ++frame;
  }
  EXPECT_EQ(frame, 12u);
}

// A loop whose frames all fit in the window: frames lent (thinned in place,
// perhaps changed by the caller) are read again, never served from the
// changed buffers.
TEST(ParticleStream, ALoopNeverServesALentFramesChangedBuffer) {
  test::TempDir dir;
  const auto reader = std::make_shared<io::ContainerReader>(scattered_file(dir / "s.sluice", 3, 20000));
  io::ParticleQuery q;
  q.lod_level = 0.5f;
  runtime::ParticleStream stream(reader, {0, 3, 1, true}, q, 64 << 20, 8);
  for (int k = 0; k < 9; ++k) {
    std::optional<runtime::LentFrame> lent = stream.next_lent();
    ASSERT_TRUE(lent);
    const io::ParticleArrays want = io::read_particles(*reader, lent->index, q);
    ASSERT_EQ(lent->arrays.count, want.count()) << "pass " << k / 3;
    EXPECT_EQ(std::vector<float>(lent->arrays.positions, lent->arrays.positions + 3 * want.count()), want.positions);
    lent->arrays.positions[0] = -1e9f;  // the caller's change
  }
  EXPECT_EQ(stream.stats().cache_hits, 0u);
}

TEST(ParticleStream, AUniformLevelReadsOnlyItsTiers) {
  test::TempDir dir;
  const auto reader = std::make_shared<io::ContainerReader>(scattered_file(dir / "s.sluice", 6, 40000));
  io::ParticleQuery q;
  q.lod_level = 0.1f;
  runtime::ParticleStream stream(reader, {0, 6, 1}, q, 64 << 20);
  uint64_t kept = 0, alone = 0;
  while (auto f = stream.next()) {
    const io::ParticleArrays want = io::read_particles(*reader, f->index, q);
    EXPECT_EQ(f->arrays.positions, want.positions);
    kept += f->arrays.count();
    alone += want.bytes_read;
  }
  EXPECT_GT(kept, 6u * 40000 / 20);
  EXPECT_LT(kept, 6u * 40000 / 6);
  const runtime::PipelineStats s = stream.stats();
  ASSERT_GT(s.record_bytes, 0u);
  // The stream reads what read_particles reads of each frame (its tables
  // and the kept tiers; cells whose tiers would not pay are written whole
  // and read whole), well under the records.
  EXPECT_LE(s.bytes_read, alone + 6 * 4096) << s.bytes_read << " against " << alone;
  EXPECT_LT(s.bytes_read, s.record_bytes * 6 / 10) << s.bytes_read << " of " << s.record_bytes;
}

TEST(ParticleStream, ADamagedFrameNamesItsFileFrameAndChunk) {
  test::TempDir dir;
  const auto path = scattered_file(dir / "s.sluice", 5, 20000);
  {
    const io::ContainerReader r(path);
    const io::FrameHeader h = r.read_table(2);
    std::FILE* file = std::fopen(path.c_str(), "r+b");
    ASSERT_NE(file, nullptr);
    std::fseek(file, long(r.index().frames[2].offset + h.chunks[1].offset + 3), SEEK_SET);
    const int c = std::fgetc(file);
    std::fseek(file, -1, SEEK_CUR);
    std::fputc(c ^ 0x3c, file);
    std::fclose(file);
  }
  const auto reader = std::make_shared<io::ContainerReader>(path);
  runtime::ParticleStream stream(reader, {0, 5, 1}, {}, 64 << 20);
  ASSERT_TRUE(stream.next());
  ASSERT_TRUE(stream.next());
  try {
    stream.next();
    FAIL() << "frame 2 is damaged";
  } catch (const io::Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("s.sluice"), std::string::npos) << what;
    EXPECT_NE(what.find("frame 2"), std::string::npos) << what;
    EXPECT_NE(what.find("chunk"), std::string::npos) << what;
  }
  EXPECT_TRUE(stream.next());  // the frames after it still come
}

TEST(ParticleStream, AnEmptyRangeGivesNothing) {
  test::TempDir dir;
  const auto reader = std::make_shared<io::ContainerReader>(scattered_file(dir / "s.sluice", 2, 100));
  runtime::ParticleStream stream(reader, {5, 9, 1}, {}, 0);
  EXPECT_EQ(stream.remaining(), 0u);
  EXPECT_FALSE(stream.next());
  EXPECT_THROW(runtime::ParticleStream(reader, {0, 2, 0}, {}, 0), io::Error);
}

}  // namespace
