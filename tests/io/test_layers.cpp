// The narrow band's layers in the container (format 1.3): what convert
// writes, what readers select, and files without layers.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "sluice/io/format.h"
#include "sluice/io/narrow_band.h"
#include "records.h"
#include "sluice/io/reader.h"
#include "test_util.h"

namespace sluice {
namespace {

using test::TempDir;

// A 20^3 jittered block, spacing 0.01: voxels of 0.02 hold 8 particles, so
// the outer two voxel shells are surface (L1, and L2 next to L1 voxels of at
// most n1 = 8 particles) and the inner 6^3 voxels (1,728 particles) interior.
constexpr uint64_t kBlock = 20 * 20 * 20;

using Points = std::vector<std::array<float, 3>>;

Points points_of(const std::vector<float>& xyz) {
  Points p(xyz.size() / 3);
  for (size_t i = 0; i < p.size(); ++i) p[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  return p;
}

// The largest distance from a point of `a` to the nearest point of `b`, both
// ways round (brute force: the sets are small).
double farthest_nearest(const Points& a, const Points& b) {
  const auto one_way = [](const Points& from, const Points& to) {
    double worst = 0;
    for (const auto& p : from) {
      double best = 1e30;
      for (const auto& q : to) {
        const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
        best = std::min(best, dx * dx + dy * dy + dz * dz);
      }
      worst = std::max(worst, best);
    }
    return std::sqrt(worst);
  };
  return std::max(one_way(a, b), one_way(b, a));
}

TEST(Layers, BlockIsWrittenAsSurfaceBlobsAndInterior) {
  TempDir dir;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame f = test::lattice_frame(kBlock, 0);
  test::write_file(dir / "layered.sluice", h, {f}, 512, true);
  const io::ContainerReader r(dir / "layered.sluice");
  EXPECT_TRUE(r.header().version_major >= 2 || r.header().version_minor >= 3);
  const io::FrameIndexEntry& e = r.index().frames[0];
  ASSERT_TRUE(e.layered());
  const uint64_t surface = e.layer_particles[size_t(io::Layer::Surface)];
  const uint64_t interior = e.layer_particles[size_t(io::Layer::Interior)];
  const uint64_t blobs = e.layer_particles[size_t(io::Layer::Blobs)];
  EXPECT_EQ(e.layer_particles[size_t(io::Layer::All)], 0u);
  EXPECT_EQ(surface + interior, kBlock);
  EXPECT_EQ(interior, 6u * 6 * 6 * 8);
  EXPECT_EQ(blobs, 6u * 6 * 6);  // one per interior voxel
  EXPECT_EQ(e.count_in(io::LayerSet::particles()), kBlock);
  EXPECT_EQ(e.count_in(io::LayerSet::surface()), surface + blobs);

  // Payloads: surface, then blobs, then interior; the surface set is a prefix.
  const io::FrameHeader table = r.read_table(0);
  EXPECT_FLOAT_EQ(table.blob_voxel, 0.02f);
  int order = 0;
  for (const io::ChunkDesc& c : table.chunks) {
    const int rank = c.layer == io::Layer::Surface ? 0 : c.layer == io::Layer::Blobs ? 1 : 2;
    EXPECT_GE(rank, order);
    order = rank;
  }
  const size_t attributes = h.attributes.size();
  const uint64_t prefix = io::layers_end(table, io::LayerSet::surface(), attributes);
  EXPECT_LT(prefix, table.frame_bytes);
  EXPECT_EQ(io::layers_end(table, io::LayerSet::particles(), attributes), table.frame_bytes);
  for (const io::ChunkDesc& c : table.chunks) {
    if (c.layer != io::Layer::Interior) EXPECT_LE(c.offset + c.compressed_size, prefix);
    else EXPECT_GE(c.offset, prefix);
  }
}

// `convert --band-f2 asymmetry`: the surface chunks hold what the asymmetry
// test keeps, fewer than every particle of the selected L2 voxels.
TEST(Layers, TheAsymmetryTestWritesItsOwnSurface) {
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame f = test::lattice_frame(kBlock, 0);
  const auto surface_of = [&](io::F2Test f2) {
    uint64_t surface = 0;
    for (const io::ChunkDesc& c : test::encode(f, h, 4096, true, f2).header.chunks) {
      if (c.layer == io::Layer::Surface) surface += c.particle_count;
    }
    return surface;
  };
  const io::NarrowBand asymmetric =
      io::classify_narrow_band(f.positions, {.diameter = h.particle_spacing, .f2 = io::F2Test::Asymmetry});
  EXPECT_EQ(surface_of(io::F2Test::Asymmetry), asymmetric.surface());
  EXPECT_LT(surface_of(io::F2Test::Asymmetry), surface_of(io::F2Test::All));
}

TEST(Layers, EveryParticleComesBackWhateverTheLayers) {
  TempDir dir;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame f = test::lattice_frame(kBlock, 0);
  test::write_file(dir / "plain.sluice", h, {f}, 512, false);
  test::write_file(dir / "layered.sluice", h, {f}, 512, true);
  const io::ContainerReader plain(dir / "plain.sluice"), layered(dir / "layered.sluice");
  const auto a = io::world_positions(io::decode_frame(plain, 0), h.position_coding);
  const auto b = io::world_positions(io::decode_frame(layered, 0), h.position_coding);
  ASSERT_EQ(a.size(), b.size());
  // Chunks differ, so quantization differs: every particle within a small
  // fraction of the spacing of its source, in both files.
  const Points source = points_of(f.positions);
  EXPECT_LT(farthest_nearest(points_of(a), source), 0.01 / 100);
  EXPECT_LT(farthest_nearest(points_of(b), source), 0.01 / 100);
}

TEST(Layers, BlobsHoldTheInteriorsCountAndCentroids) {
  TempDir dir;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame f = test::lattice_frame(kBlock, 0);
  test::write_file(dir / "layered.sluice", h, {f}, 512, true);
  const io::ContainerReader r(dir / "layered.sluice");
  const io::DecodedFrame d = io::decode_frame(r, 0, io::LayerSet::surface());
  const auto xyz = io::world_positions(d, h.position_coding);
  const auto lod = io::lod_values_of(d, h.position_coding);
  // The classifier's own answer on the source positions.
  io::NarrowBandOptions o;
  o.diameter = h.particle_spacing;
  o.blobs = true;
  const io::NarrowBand band = io::classify_narrow_band(f.positions, o);
  uint64_t blob_particles = 0, blobs = 0;
  Points centroids, truth;
  for (size_t c = 0; c < d.header.chunks.size(); ++c) {
    const io::ChunkDesc& chunk = d.header.chunks[c];
    EXPECT_NE(chunk.layer, io::Layer::Interior);  // never in the surface set
    if (chunk.layer != io::Layer::Blobs) continue;
    for (uint64_t i = d.chunk_first[c]; i < d.chunk_first[c] + chunk.particle_count; ++i) {
      blob_particles += lod[i];
      ++blobs;
      centroids.push_back({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
    }
  }
  EXPECT_EQ(blobs, band.blobs.size());
  EXPECT_EQ(blob_particles, band.counts[size_t(io::BandLayer::Interior)]);
  for (const io::VoxelBlob& b : band.blobs) truth.push_back(b.centroid);
  ASSERT_EQ(centroids.size(), truth.size());
  EXPECT_LT(farthest_nearest(centroids, truth), 1e-4);  // quantized in their chunk's box
  // Each blob's centroid is the mean of its own particles (8 of them on this lattice).
  for (size_t i = 0; i < band.layer.size(); ++i) {
    if (band.layer[i] != io::BandLayer::Interior) continue;
    const io::VoxelBlob& b = band.blobs[band.blob_of[i]];
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(f.positions[3 * i + k], b.centroid[size_t(k)], 0.01 + 0.002);
    EXPECT_EQ(b.count, 8u);
  }
}

TEST(Layers, FilesWithoutLayersReadWholeInEverySet) {
  TempDir dir;
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  test::write_file(dir / "plain.sluice", h, {test::lattice_frame(3000, 0)}, 512, false);
  const io::ContainerReader r(dir / "plain.sluice");
  const io::FrameIndexEntry& e = r.index().frames[0];
  EXPECT_FALSE(e.layered());
  EXPECT_EQ(e.count_in(io::LayerSet::surface()), 3000u);
  EXPECT_EQ(e.count_in(io::LayerSet::particles()), 3000u);
  EXPECT_EQ(io::decode_frame(r, 0, io::LayerSet::surface()).header.particle_count, 3000u);
  const io::FrameHeader table = r.read_table(0);
  EXPECT_EQ(table.blob_voxel, 0.f);
  EXPECT_EQ(io::layers_end(table, io::LayerSet::surface(), 1), table.frame_bytes);
}

TEST(Layers, LosslessFilesAndFramesWithoutSpacingStayOneLayer) {
  TempDir dir;
  io::FileHeader lossless = test::test_header(io::PositionCoding::Float32);
  io::FileHeader unknown = test::test_header(io::PositionCoding::Quantized16);
  unknown.particle_spacing = 0;
  test::write_file(dir / "a.sluice", lossless, {test::lattice_frame(kBlock, 0)}, 512, true);
  test::write_file(dir / "b.sluice", unknown, {test::lattice_frame(kBlock, 0)}, 512, true);
  EXPECT_FALSE(io::ContainerReader(dir / "a.sluice").index().frames[0].layered());
  EXPECT_FALSE(io::ContainerReader(dir / "b.sluice").index().frames[0].layered());
}

TEST(Layers, KeepLayersDropsChunksAndRecounts) {
  io::FrameHeader h;
  for (const io::Layer l : {io::Layer::Surface, io::Layer::Blobs, io::Layer::Interior, io::Layer::All}) {
    io::ChunkDesc c;
    c.layer = l;
    c.particle_count = 10 + uint32_t(l);
    h.chunks.push_back(c);
    h.particle_count += c.particle_count;
  }
  io::FrameHeader s = h;
  io::keep_layers(s, io::LayerSet::surface());
  EXPECT_EQ(s.chunks.size(), 3u);  // surface, blobs, all
  EXPECT_EQ(s.particle_count, 11u + 13u + 10u);
  EXPECT_EQ(io::count_in(h, io::LayerSet::particles()), 11u + 12u + 10u);
  io::keep_layers(h, io::LayerSet::particles());
  EXPECT_EQ(h.chunks.size(), 3u);  // surface, interior, all
}

// Records that are checksummed but say impossible things about layers:
// rejected with a message, before any payload is trusted.
TEST(Layers, InconsistentLayerRecordsAreRejected) {
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  io::EncodedFrame frame = test::encode(test::lattice_frame(kBlock, 0), h, 512, true);
  ASSERT_GT(frame.header.blob_voxel, 0.f);

  io::FrameHeader no_side = frame.header;  // blob chunks, but no voxel side to splat them with
  no_side.blob_voxel = 0;
  std::vector<std::byte> record = io::serialize_frame_table(no_side, h.attributes.size());
  record.resize(no_side.frame_bytes);
  try {
    (void)io::parse_frame_table(record, h.attributes.size(), {"x.sluice", 0, {}});
    ADD_FAILURE() << "a blob chunk without a voxel side was accepted";
  } catch (const io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("blob voxel"), std::string::npos) << e.what();
  }
  io::FrameHeader negative = frame.header;
  negative.blob_voxel = -1;
  record = io::serialize_frame_table(negative, h.attributes.size());
  record.resize(negative.frame_bytes);
  EXPECT_THROW((void)io::parse_frame_table(record, h.attributes.size(), {"x.sluice", 0, {}}), io::Error);

  io::IndexBuilder builder(h.attributes.size());  // layer counts that do not add up to the frame's
  builder.add(frame.header, 4096);
  io::FrameIndex index = builder.index();
  index.frames[0].layer_particles[size_t(io::Layer::Blobs)] += 1;
  const std::vector<std::byte> bytes = io::serialize_index(index, h.attributes.size());
  try {
    (void)io::parse_index(bytes, h.attributes.size(), uint64_t(1) << 30, {"x.sluice", {}, {}});
    ADD_FAILURE() << "an index whose layers do not add up was accepted";
  } catch (const io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("layer counts"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sluice
