// Fault injection on the container: flipped bytes, cut files and headers that
// claim absurd sizes. Every failure names the file, and the frame and chunk
// where there is one; nothing is allocated on the word of a bad header.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <new>

#include "records.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"
#include "test_util.h"

// Records the largest single allocation while `g_watch` is set, to prove that
// a header claiming a huge size is rejected before anything is allocated.
static std::atomic<bool> g_watch{false};
static std::atomic<size_t> g_largest{0};
void* operator new(size_t n) {
  if (g_watch.load(std::memory_order_relaxed) && n > g_largest.load()) g_largest = n;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

namespace test = sluice::test;
namespace io = sluice::io;
using namespace sluice::io;

namespace {

std::vector<char> slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
void spit(const std::filesystem::path& p, const std::vector<char>& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

struct Fixture : ::testing::Test {
  test::TempDir dir;
  FileHeader header = test::test_header(PositionCoding::Quantized16);
  std::filesystem::path path;
  void SetUp() override {
    std::vector<ParticleFrame> frames;
    for (int f = 0; f < 4; ++f) frames.push_back(test::lattice_frame(6000, f * 0.1, f));
    path = test::write_file(dir / "c.sluice", header, frames, 2000);
  }
  std::string open_error(const std::filesystem::path& p) {
    try {
      ContainerReader r(p);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
};

}  // namespace

TEST_F(Fixture, FlippedPayloadByteNamesFileFrameAndChunk) {
  const ContainerReader clean(path);
  const FrameHeader h = clean.parse_record(2, clean.read_record(2));
  ASSERT_GE(h.chunks.size(), 3u);
  for (size_t c = 0; c < h.chunks.size(); ++c) {
    std::vector<char> bytes = slurp(path);
    const uint64_t at = clean.index().frames[2].offset + h.chunks[c].offset + h.chunks[c].compressed_size / 2;
    bytes[at] = char(bytes[at] ^ 0x10);
    const auto bad = dir / ("flip" + std::to_string(c) + ".sluice");
    spit(bad, bytes);
    const ContainerReader r(bad);
    try {
      decode_frame(r, 2);
      FAIL() << "corruption in chunk " << c << " not detected";
    } catch (const Error& e) {
      EXPECT_EQ(e.where().file, bad.string());
      EXPECT_EQ(e.where().frame, 2u);
      EXPECT_EQ(e.where().chunk, c);
      EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
    const VerifyReport report = verify_container(bad);
    ASSERT_EQ(report.problems.size(), 1u);
    EXPECT_NE(report.problems[0].find("frame 2, chunk " + std::to_string(c)), std::string::npos) << report.problems[0];
    EXPECT_NO_THROW(decode_frame(r, 1));  // the other frames still decode
  }
}

TEST_F(Fixture, FlippedFrameTableByteIsCaught) {
  const ContainerReader clean(path);
  std::vector<char> bytes = slurp(path);
  bytes[clean.index().frames[1].offset + 80] ^= 1;  // inside the first chunk descriptor
  spit(dir / "t.sluice", bytes);
  const ContainerReader r(dir / "t.sluice");
  try {
    decode_frame(r, 1);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.where().frame, 1u);
    EXPECT_NE(std::string(e.what()).find("frame header checksum"), std::string::npos) << e.what();
  }
}

TEST_F(Fixture, FlippedHeaderOrIndexByteIsCaughtAtOpen) {
  std::vector<char> bytes = slurp(path);
  bytes[30] ^= 4;
  spit(dir / "h.sluice", bytes);
  EXPECT_NE(open_error(dir / "h.sluice").find("header checksum"), std::string::npos);
  bytes = slurp(path);
  bytes[bytes.size() - kFooterBytes - 20] ^= 4;
  spit(dir / "i.sluice", bytes);
  EXPECT_NE(open_error(dir / "i.sluice").find("frame index: checksum"), std::string::npos) << open_error(dir / "i.sluice");
}

TEST_F(Fixture, EveryFlippedByteIsCaughtSomewhere) {
  // Flip one byte at a time across the whole file (stride keeps it quick): an
  // open, decode or verify must report it; nothing may crash.
  const std::vector<char> original = slurp(path);
  int caught = 0, flips = 0;
  for (size_t at = 0; at < original.size(); at += 97, ++flips) {
    std::vector<char> bytes = original;
    bytes[at] = char(bytes[at] ^ 0x5a);
    spit(dir / "x.sluice", bytes);
    try {
      const VerifyReport report = verify_container(dir / "x.sluice");
      if (!report.ok()) ++caught;
    } catch (const Error&) {
      ++caught;
    }
  }
  // A few flips land in reserved/padding-free fields that no check covers?
  // There are none: every byte is under a checksum or validated.
  EXPECT_EQ(caught, flips);
}

TEST_F(Fixture, TruncatedFileSaysToRecover) {
  std::vector<char> bytes = slurp(path);
  bytes.resize(bytes.size() - 100);
  spit(dir / "cut.sluice", bytes);
  const std::string e = open_error(dir / "cut.sluice");
  EXPECT_NE(e.find("sluice recover"), std::string::npos) << e;
  EXPECT_NE(e.find("cut.sluice"), std::string::npos) << e;
}

TEST_F(Fixture, AbsurdSizesAreRejectedBeforeAllocation) {
  struct Case {
    const char* what;
    size_t offset;
    uint64_t value;
    int width;
    bool in_frame;  // offset relative to frame 0's record
  };
  const ContainerReader clean(path);
  const uint64_t frame0 = clean.index().frames[0].offset;
  const uint64_t index_at = clean.file_size() - kFooterBytes - clean.index().frames.size() * kIndexEntryBytes - 8 -
                            8 * header.attributes.size() - 40;
  const Case cases[] = {
      {"header bytes", 12, 0x7fffffff, 4, false},
      {"attribute count", 18, 60000, 2, false},
      {"frame bytes", 8, uint64_t(1) << 60, 8, true},
      {"chunk count", 32, 0xfffffff0u, 4, true},
      {"chunk particles", 72 + 12, 0x7fffffffu, 4, true},
      {"index frame count", index_at + 8, uint64_t(1) << 40, 8, false},
      {"footer index size", 0, uint64_t(1) << 50, 8, false},
  };
  for (const Case& c : cases) {
    std::vector<char> bytes = slurp(path);
    size_t at = c.offset + (c.in_frame ? frame0 : 0);
    if (std::string(c.what) == "footer index size") at = bytes.size() - kFooterBytes + 8;
    std::memcpy(bytes.data() + at, &c.value, size_t(c.width));
    spit(dir / "absurd.sluice", bytes);
    g_largest = 0;
    g_watch = true;
    bool failed = false;
    try {
      const VerifyReport report = verify_container(dir / "absurd.sluice");
      failed = !report.ok();
    } catch (const Error&) {
      failed = true;
    }
    g_watch = false;
    EXPECT_TRUE(failed) << c.what;
    EXPECT_LT(g_largest.load(), size_t(64) << 20) << c.what << ": allocated " << g_largest.load() << " bytes";
  }
}

TEST_F(Fixture, NotASluiceFile) {
  spit(dir / "n.sluice", std::vector<char>(1000, 'x'));
  EXPECT_NE(open_error(dir / "n.sluice").find("not a .sluice file"), std::string::npos);
  spit(dir / "s.sluice", std::vector<char>(3, 'x'));
  EXPECT_NE(open_error(dir / "s.sluice").find("too small"), std::string::npos);
  EXPECT_NE(open_error(dir / "missing.sluice").find("cannot open"), std::string::npos);
}
