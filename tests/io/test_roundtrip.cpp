// Write -> read round trips: exactness in float mode, the stated error bound
// in quantized mode, containment in chunk boxes, seeking.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "sluice/io/reader.h"
#include "test_util.h"

namespace test = sluice::test;
namespace io = sluice::io;
using namespace sluice::io;

namespace {

std::vector<ParticleFrame> frames3(uint64_t n) {
  return {test::lattice_frame(n, 0.0, 1), test::lattice_frame(n, 0.5, 2), test::lattice_frame(n / 2, 1.0, 3)};
}

float ulp(float v) { return std::nextafter(std::fabs(v), INFINITY) - std::fabs(v); }

}  // namespace

TEST(RoundTrip, HeaderAndIndexSurvive) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  const auto frames = frames3(5000);
  const ContainerReader r(test::write_file(dir / "a.sluice", h, frames));
  EXPECT_EQ(r.header().particle_spacing, 0.01f);
  EXPECT_EQ(r.header().frame_rate, 30.f);
  ASSERT_EQ(r.header().attributes.size(), 1u);
  EXPECT_EQ(r.header().attributes[0].name, "rho");
  EXPECT_EQ(r.header().source, "synthetic lattice");
  ASSERT_EQ(r.frame_count(), 3u);
  for (size_t f = 0; f < 3; ++f) {
    EXPECT_EQ(r.index().frames[f].particle_count, frames[f].count());
    EXPECT_EQ(r.index().frames[f].time, frames[f].time);
    EXPECT_EQ(r.index().frames[f].layer_particles[0], frames[f].count());
  }
  EXPECT_GT(r.index().attribute_ranges[0][1], r.index().attribute_ranges[0][0]);
}

TEST(RoundTrip, FloatModeIsExact) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Float32);
  const auto frames = frames3(20000);
  const ContainerReader r(test::write_file(dir / "f.sluice", h, frames));
  for (size_t f = 0; f < frames.size(); ++f) {
    const DecodedFrame d = decode_frame(r, f);
    const std::vector<float> xyz = world_positions(d, PositionCoding::Float32);
    const std::vector<uint16_t> lod = lod_values_of(d, PositionCoding::Float32);
    const std::vector<uint16_t> lod_in = lod_values(frames[f].ids, frames[f].count());
    using P = std::array<float, 4>;
    std::vector<P> got, want;
    for (size_t i = 0; i < frames[f].count(); ++i) {
      want.push_back({frames[f].positions[3 * i], frames[f].positions[3 * i + 1], frames[f].positions[3 * i + 2],
                      float(lod_in[i])});
      got.push_back({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], float(lod[i])});
    }
    std::sort(got.begin(), got.end());
    std::sort(want.begin(), want.end());
    EXPECT_EQ(got, want) << "frame " << f;
  }
}

// Matches every decoded particle to the source particle with the same LOD
// value nearest to it, requires a one-to-one match, and checks the error of
// each axis against half a quantization step plus float rounding.
TEST(RoundTrip, QuantizedErrorWithinBoundForEveryParticle) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  const auto frames = frames3(30000);
  const ContainerReader r(test::write_file(dir / "q.sluice", h, frames));
  for (size_t f = 0; f < frames.size(); ++f) {
    const ParticleFrame& src = frames[f];
    const std::vector<uint16_t> lod_in = lod_values(src.ids, src.count());
    std::multimap<uint16_t, size_t> by_lod;
    for (size_t i = 0; i < src.count(); ++i) by_lod.emplace(lod_in[i], i);
    const DecodedFrame d = decode_frame(r, f);
    const std::vector<float> xyz = world_positions(d, PositionCoding::Quantized16);
    const std::vector<uint16_t> lod = lod_values_of(d, PositionCoding::Quantized16);
    std::vector<int> used(src.count(), 0);
    double worst_ratio = 0;
    for (size_t c = 0; c < d.header.chunks.size(); ++c) {
      const ChunkDesc& chunk = d.header.chunks[c];
      for (uint64_t i = d.chunk_first[c]; i < d.chunk_first[c] + chunk.particle_count; ++i) {
        auto [lo, hi] = by_lod.equal_range(lod[i]);
        size_t best = SIZE_MAX;
        double best_d = INFINITY;
        for (auto it = lo; it != hi; ++it) {
          double dist = 0;
          for (int a = 0; a < 3; ++a) dist += std::pow(double(xyz[3 * i + a]) - src.positions[3 * it->second + a], 2);
          if (dist < best_d) best_d = dist, best = it->second;
        }
        ASSERT_NE(best, SIZE_MAX) << "decoded LOD value not in the source";
        ASSERT_EQ(used[best]++, 0) << "two decoded particles match one source particle";
        for (int a = 0; a < 3; ++a) {
          const float step = (chunk.bounds.max[a] - chunk.bounds.min[a]) / 65535.f;
          const float bound = 0.5f * step + 2 * ulp(std::max(std::fabs(chunk.bounds.min[a]), std::fabs(chunk.bounds.max[a])));
          const float err = std::fabs(xyz[3 * i + a] - src.positions[3 * best + a]);
          ASSERT_LE(err, bound) << "frame " << f << " chunk " << c << " axis " << a;
          worst_ratio = std::max(worst_ratio, double(err) / h.particle_spacing);
        }
      }
    }
    EXPECT_LT(worst_ratio, 1e-3) << "error should be well under 1/1000 of the spacing";
  }
}

TEST(RoundTrip, EveryParticleInsideItsChunkBox) {
  for (PositionCoding coding : {PositionCoding::Quantized16, PositionCoding::Float32}) {
    test::TempDir dir;
    const FileHeader h = test::test_header(coding);
    const ContainerReader r(test::write_file(dir / "b.sluice", h, frames3(40000), 3000));
    for (uint64_t f = 0; f < r.frame_count(); ++f) {
      const DecodedFrame d = decode_frame(r, f);
      const std::vector<float> xyz = world_positions(d, coding);
      ASSERT_GT(d.header.chunks.size(), 5u);
      for (size_t c = 0; c < d.header.chunks.size(); ++c) {
        const Aabb& box = d.header.chunks[c].bounds;
        for (uint64_t i = d.chunk_first[c]; i < d.chunk_first[c] + d.header.chunks[c].particle_count; ++i) {
          ASSERT_TRUE(box.contains(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2])) << "chunk " << c;
          ASSERT_TRUE(d.header.bounds.contains(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]) ||
                      coding == PositionCoding::Quantized16);
        }
      }
    }
  }
}

TEST(RoundTrip, AttributeErrorWithinBound) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Float32);
  const ParticleFrame src = test::lattice_frame(10000, 0.0);
  const ContainerReader r(test::write_file(dir / "a.sluice", h, {src}));
  const DecodedFrame d = decode_frame(r, 0);
  const std::vector<float> xyz = world_positions(d, PositionCoding::Float32);
  std::map<std::array<float, 3>, float> truth;
  for (size_t i = 0; i < src.count(); ++i) {
    truth[{src.positions[3 * i], src.positions[3 * i + 1], src.positions[3 * i + 2]}] = src.attributes[0][i];
  }
  for (size_t c = 0; c < d.header.chunks.size(); ++c) {
    const auto range = d.header.chunks[c].attribute_ranges[0];
    for (uint64_t i = d.chunk_first[c]; i < d.chunk_first[c] + d.header.chunks[c].particle_count; ++i) {
      const float v = dequantize(d.attributes[0][i], range[0], range[1]);
      const float want = truth.at({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
      ASSERT_NEAR(v, want, 0.5f * (range[1] - range[0]) / 65535.f + 2 * ulp(want));
    }
  }
}

TEST(RoundTrip, SeekReturnsTheSameBytesAsSequentialRead) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  std::vector<ParticleFrame> frames;
  for (int f = 0; f < 12; ++f) frames.push_back(test::lattice_frame(3000 + 100 * f, f * 0.1, f));
  const ContainerReader r(test::write_file(dir / "s.sluice", h, frames));
  std::vector<std::vector<std::byte>> sequential;
  for (uint64_t f = 0; f < r.frame_count(); ++f) sequential.push_back(r.read_record(f));
  std::mt19937 rng(11);
  for (int k = 0; k < 100; ++k) {
    const uint64_t f = rng() % r.frame_count();
    ASSERT_EQ(r.read_record(f), sequential[f]) << "frame " << f;
    EXPECT_EQ(decode_frame(r, f).particles.size(), frames[f].count() * 8);
  }
}

TEST(RoundTrip, EmptyFrameIsAllowed) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  ParticleFrame empty;
  empty.attributes.resize(1);
  empty.time = 0.25;
  const ContainerReader r(test::write_file(dir / "e.sluice", h, {test::lattice_frame(100, 0), empty}));
  ASSERT_EQ(r.frame_count(), 2u);
  const DecodedFrame d = decode_frame(r, 1);
  EXPECT_EQ(d.header.particle_count, 0u);
  EXPECT_EQ(d.header.time, 0.25);
  EXPECT_TRUE(d.header.chunks.empty());
}

TEST(RoundTrip, NonFiniteInputIsRefusedByTheEncoder) {
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  ParticleFrame f = test::lattice_frame(100, 0);
  f.positions[7] = NAN;
  EXPECT_THROW(test::encode(f, h), Error);
}

namespace sluice::io {
namespace {

// PlaneCoding::Stored: every chunk stored, the same particles
// decoded as from the compressed encoding, 8 bytes per particle in payloads.
TEST(RoundTrip, UncompressedChunksDecodeToTheSameParticles) {
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  const ParticleFrame f = test::lattice_frame(20000, 0.5);
  const std::vector<uint16_t> lod = lod_values(f.ids, f.count());
  FrameInput in{f.positions, lod, {f.attributes[0]}, f.time};
  EncodeOptions packed;
  packed.chunk_particles = 4096;
  packed.lod_tiers = false;  // stored frames are written untiered: compare the codings alone
  EncodeOptions stored = packed;
  stored.planes = PlaneCoding::Stored;
  const EncodedFrame a = encode_frame(in, h, packed), b = encode_frame(in, h, stored);
  ASSERT_EQ(a.header.chunks.size(), b.header.chunks.size());
  const auto decode = [&](const EncodedFrame& e) {
    std::vector<uint64_t> starts(e.header.chunks.size());
    chunk_starts(e.header, starts);
    std::vector<std::byte> particles(e.header.particle_count * decoded_particle_bytes(h.position_coding));
    std::vector<uint16_t> attribute(e.header.particle_count);
    const std::vector<uint16_t*> attributes{attribute.data()};
    decode_record(e.record, e.header, h, starts, particles, attributes, {"test", 0, {}});
    return std::make_pair(particles, attribute);
  };
  uint64_t payload = 0;
  for (const ChunkDesc& c : b.header.chunks) {
    EXPECT_EQ(c.codec, ChunkCodec::Stored);
    payload += c.compressed_size;
  }
  EXPECT_EQ(payload, b.header.particle_count * 10);  // 8 bytes of position and LOD, 2 of the attribute
  EXPECT_EQ(decode(a), decode(b));
}

}  // namespace
}  // namespace sluice::io

// Format 1.2: the up axis, how it was found and the time source live in the
// header's flags; the converter rewrites them in place once it knows.
TEST(RoundTrip, UpAxisAndTimeSourceSurviveAndCanBeRewrittenInPlace) {
  test::TempDir dir;
  io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  h.up = io::UpAxis::PosZ;
  h.up_evidence = io::UpEvidence::Shape;
  h.time_source = io::TimeSource::Step;
  const auto path = dir.path / "up.sluice";
  {
    io::ContainerWriter w(path, h);
    w.append(test::encode(test::lattice_frame(500, 0.0), h));
    h.up = io::UpAxis::NegY;
    h.up_evidence = io::UpEvidence::Motion;
    w.update_header(h);
    w.append(test::encode(test::lattice_frame(500, 0.1), h));
    io::FileHeader longer = h;
    longer.source += " and more";
    EXPECT_THROW(w.update_header(longer), io::Error);  // the size may not change
    w.finish();
  }
  const io::ContainerReader r(path);
  EXPECT_EQ(r.header().version_minor, io::kFormatMinor);
  EXPECT_EQ(r.header().up, io::UpAxis::NegY);
  EXPECT_EQ(r.header().up_evidence, io::UpEvidence::Motion);
  EXPECT_EQ(r.header().time_source, io::TimeSource::Step);
  EXPECT_EQ(r.frame_count(), 2u);
  const std::array<float, 3> up = io::up_vector(r.header().up);
  EXPECT_EQ(up[1], -1.0f);
}

TEST(RoundTrip, UpAxisNamesParseBothWays) {
  for (int code = 1; code <= 6; ++code) {
    const auto up = static_cast<io::UpAxis>(code);
    EXPECT_EQ(io::parse_up_axis(io::up_axis_name(up)), up);
  }
  EXPECT_EQ(io::parse_up_axis("y"), io::UpAxis::PosY);
  EXPECT_EQ(io::parse_up_axis("-Z"), io::UpAxis::NegZ);
  EXPECT_FALSE(io::parse_up_axis("w"));
  EXPECT_FALSE(io::parse_up_axis("--x"));
  EXPECT_FALSE(io::parse_up_axis(""));
  EXPECT_EQ(io::up_axis_name(io::UpAxis::Unstated), "+z");  // files before 1.2
}
