// Recovery of files cut short at many offsets, out of place and in place.
#include <gtest/gtest.h>

#include <fstream>

#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"
#include "test_util.h"

namespace test = sluice::test;
namespace io = sluice::io;
using namespace sluice::io;

namespace {

std::vector<char> slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST(Recover, TruncationAtManyOffsetsKeepsEveryCompleteFrame) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  std::vector<ParticleFrame> frames;
  for (int f = 0; f < 5; ++f) frames.push_back(test::lattice_frame(1500 + 200 * f, f * 0.1, f));
  const auto path = test::write_file(dir / "full.sluice", h, frames, 500);
  const ContainerReader full(path);
  std::vector<std::vector<std::byte>> originals;
  for (uint64_t f = 0; f < full.frame_count(); ++f) originals.push_back(full.read_record(f));
  const std::vector<char> bytes = slurp(path);

  // Offsets: a spread over the file plus each frame boundary and its neighbours.
  std::vector<uint64_t> cuts;
  for (uint64_t at = 0; at < bytes.size(); at += bytes.size() / 61 + 1) cuts.push_back(at);
  for (const auto& e : full.index().frames) {
    for (int64_t d : {-1, 0, 1}) cuts.push_back(uint64_t(int64_t(e.offset + e.bytes) + d));
  }
  int recovered_files = 0;
  for (uint64_t cut : cuts) {
    const auto cut_path = dir / "cut.sluice";
    std::ofstream(cut_path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(cut));
    uint64_t complete = 0;
    for (const auto& e : full.index().frames) complete += (e.offset + e.bytes <= cut) ? 1 : 0;
    RecoveryReport report;
    try {
      report = recover_container(cut_path, dir / "rec.sluice");
    } catch (const Error& e) {
      // Only a cut inside the file header leaves nothing to recover.
      EXPECT_LT(cut, full.index().frames[0].offset) << e.what();
      continue;
    }
    ++recovered_files;
    ASSERT_EQ(report.frames, complete) << "cut at " << cut << ": " << report.stopped_because;
    const ContainerReader r(dir / "rec.sluice");
    ASSERT_EQ(r.frame_count(), complete);
    for (uint64_t f = 0; f < complete; ++f) ASSERT_EQ(r.read_record(f), originals[f]) << "cut " << cut;
    EXPECT_TRUE(verify_container(dir / "rec.sluice").ok());
  }
  EXPECT_GT(recovered_files, 50);
}

TEST(Recover, InPlaceRebuildsTheIndex) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Float32);
  std::vector<ParticleFrame> frames;
  for (int f = 0; f < 3; ++f) frames.push_back(test::lattice_frame(2000, f * 0.1, f));
  const auto path = test::write_file(dir / "p.sluice", h, frames);
  const uint64_t size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size - 40);  // lose the footer and part of the index
  EXPECT_THROW(ContainerReader{path}, Error);
  const RecoveryReport report = recover_container(path, path);
  EXPECT_EQ(report.frames, 3u);
  EXPECT_GT(report.bytes_dropped, 0u);
  const ContainerReader r(path);
  EXPECT_EQ(r.frame_count(), 3u);
  EXPECT_EQ(std::filesystem::file_size(path), size);
}

TEST(Recover, WriterAbandonedWithoutFinishIsRecoverable) {
  test::TempDir dir;
  const FileHeader h = test::test_header(PositionCoding::Quantized16);
  {
    ContainerWriter w(dir / "crash.sluice", h);
    for (int f = 0; f < 4; ++f) w.append(test::encode(test::lattice_frame(1000, f, f), h));
  }  // no finish(): as if the process had died
  const RecoveryReport report = recover_container(dir / "crash.sluice", dir / "ok.sluice");
  EXPECT_EQ(report.frames, 4u);
  EXPECT_EQ(report.stopped_because, "end of file");
  EXPECT_EQ(ContainerReader(dir / "ok.sluice").frame_count(), 4u);
}
