// A .sluice file rewritten in another layout (io/maintenance.h): the same
// particles, LOD values and attributes (positions within the stated bound,
// float32 ones bit for bit), the header kept, damage a named error that
// leaves no output.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>

#include "sluice/io/particles.h"
#include "sluice/io/maintenance.h"
#include "test_util.h"

using namespace sluice;

namespace {

io::FileHeader header_for(uint16_t major, io::PositionCoding coding) {
  io::FileHeader h = test::test_header(coding);
  h.precision_bits = coding == io::PositionCoding::Quantized16 ? io::kDefaultPrecisionBits : 0;
  io::set_format_version(h, major);
  return h;
}

std::filesystem::path write_scattered(const std::filesystem::path& path, const io::FileHeader& h, bool layers) {
  std::vector<io::ParticleFrame> frames;
  for (uint32_t f = 0; f < 2; ++f) {
    frames.push_back(test::scattered_frame(30000, 7 + f));
    frames.back().time = 0.5 * f;
  }
  return test::write_file(path, h, frames, 4096, layers);
}

io::ParticleArrays all_of(const io::ContainerReader& r, uint64_t frame) {
  io::ParticleQuery q;
  for (size_t a = 0; a < r.header().attributes.size(); ++a) q.attributes.push_back(a);
  return io::read_particles(r, frame, q);
}

// Every particle of `b` matched one to one with a particle of `a` of the same
// LOD value whose position lies within `bound` on each axis and whose
// attribute lies within `attribute_error`.
void expect_same_particles(const io::ParticleArrays& a, const io::ParticleArrays& b, float bound, float attribute_error) {
  ASSERT_EQ(a.count(), b.count());
  std::multimap<uint16_t, uint64_t> unused;
  for (uint64_t i = 0; i < a.count(); ++i) unused.emplace(a.lod[i], i);
  for (uint64_t j = 0; j < b.count(); ++j) {
    auto [first, last] = unused.equal_range(b.lod[j]);
    auto match = last;
    for (auto it = first; it != last && match == last; ++it) {
      bool near = true;
      for (int k = 0; k < 3; ++k) near &= std::fabs(a.positions[it->second * 3 + k] - b.positions[j * 3 + k]) <= bound;
      if (near) match = it;
    }
    ASSERT_NE(match, last) << "particle " << j << " (LOD value " << b.lod[j] << ") has no counterpart within " << bound;
    for (size_t k = 0; k < a.attributes.size(); ++k) {
      EXPECT_NEAR(a.attributes[k][match->second], b.attributes[k][j], attribute_error) << "particle " << j;
    }
    unused.erase(match);
  }
}

}  // namespace

TEST(Relayout, A1_5FileRewrittenAs3_0HoldsTheSameParticles) {
  test::TempDir dir;
  const io::FileHeader h = header_for(1, io::PositionCoding::Quantized16);
  const auto old_path = write_scattered(dir / "old.sluice", h, true);
  io::RelayoutOptions o;
  o.chunk_particles = 4096;
  const io::RelayoutReport report = io::relayout_container(old_path, dir / "new.sluice", o);
  EXPECT_EQ(report.frames, 2u);
  EXPECT_EQ(report.particles, 60000u);
  EXPECT_TRUE(report.encode.layers);
  EXPECT_TRUE(report.encode.lod_tiers);

  const io::ContainerReader before(old_path), after(dir / "new.sluice");
  EXPECT_EQ(after.header().version_major, 3);
  EXPECT_EQ(after.header().particle_spacing, h.particle_spacing);
  EXPECT_EQ(after.header().precision_bits, h.precision_bits);
  ASSERT_EQ(after.header().attributes.size(), 1u);
  EXPECT_EQ(after.header().attributes[0].name, "rho");
  ASSERT_EQ(after.frame_count(), 2u);
  // Each position within the file's bound (plus two ulps) of the input's.
  const float bound = io::position_bound(after.header()) * 1.001f + 4e-7f;
  for (uint64_t f = 0; f < 2; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    EXPECT_FALSE(before.read_table(f).coarse_to_fine);
    EXPECT_TRUE(after.read_table(f).coarse_to_fine);
    const io::ParticleArrays a = all_of(before, f), b = all_of(after, f);
    EXPECT_EQ(b.time, a.time);
    expect_same_particles(a, b, bound, 0.01f);
  }
}

// The plane coding follows the input's first frame: GPU-decodable stays
// so (players decode it on the GPU), zstd planes give the default packing.
TEST(Relayout, APlaneCodingTheGpuDecodesIsKept) {
  test::TempDir dir;
  const io::FileHeader h = header_for(1, io::PositionCoding::Quantized16);
  for (const io::PlaneCoding planes : {io::PlaneCoding::GpuDecodable, io::PlaneCoding::Zstd}) {
    const auto path = dir / (planes == io::PlaneCoding::Zstd ? "zstd.sluice" : "gpu.sluice");
    {
      io::ContainerWriter w(path, h);
      const io::ParticleFrame f = test::scattered_frame(30000, 3);
      const std::vector<uint16_t> lod = io::lod_values(f.ids, f.count());
      io::FrameInput in;
      in.positions = f.positions;
      in.lod = lod;
      in.attributes.push_back(f.attributes[0]);
      io::EncodeOptions o;
      o.chunk_particles = 4096;
      o.planes = planes;
      w.append(io::encode_frame(in, h, o));
      w.finish();
    }
    const io::ContainerReader reader(path);
    const io::EncodeOptions used = io::encoding_of(reader, {});
    EXPECT_EQ(used.planes, planes == io::PlaneCoding::Zstd ? io::PlaneCoding::Packed : io::PlaneCoding::GpuDecodable);
  }
}

TEST(Relayout, Float32PositionsComeThroughBitForBit) {
  test::TempDir dir;
  const auto old_path = write_scattered(dir / "old.sluice", header_for(2, io::PositionCoding::Float32), false);
  io::RelayoutOptions o;
  o.format_major = 1;
  io::relayout_container(old_path, dir / "new.sluice", o);
  const io::ContainerReader before(old_path), after(dir / "new.sluice");
  EXPECT_EQ(after.header().version_major, 1);
  EXPECT_EQ(after.header().version_minor, io::kLegacyMinor);
  for (uint64_t f = 0; f < 2; ++f) expect_same_particles(all_of(before, f), all_of(after, f), 0.f, 0.01f);
}

TEST(Relayout, ADamagedFrameIsNamedAndLeavesNoOutput) {
  test::TempDir dir;
  const auto old_path = write_scattered(dir / "old.sluice", header_for(1, io::PositionCoding::Quantized16), true);
  {
    // A byte in the middle of frame 1's payloads.
    const io::ContainerReader r(old_path);
    const io::FrameIndexEntry& e = r.index().frames.at(1);
    std::fstream file(old_path, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(std::streamoff(e.offset + e.bytes / 2));
    file.put('\x5a' ^ char(file.peek()));
  }
  const auto out = dir / "new.sluice";
  try {
    io::relayout_container(old_path, out, {});
    FAIL() << "a damaged frame was rewritten";
  } catch (const io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("frame 1"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(out.string() + ".partial"));
}

TEST(Relayout, RefusesToWriteOverItsInput) {
  test::TempDir dir;
  const auto path = write_scattered(dir / "old.sluice", header_for(1, io::PositionCoding::Quantized16), false);
  const auto size = std::filesystem::file_size(path);
  EXPECT_THROW(io::relayout_container(path, path, {}), io::Error);
  EXPECT_EQ(std::filesystem::file_size(path), size);
  EXPECT_TRUE(io::is_container(path));
  EXPECT_FALSE(io::is_container(dir / "missing.sluice"));
}
