// Export tests: a synthetic container exported to .csv, .ply and .vtp (+ .pvd)
// reads back as the particles the container decodes to (bit for bit), within
// the quantization error of the simulation's own values, and converts back
// into a container holding the same particles; --lod-level thinning keeps the
// fraction asked for, uniformly and the same particles every frame; the
// --frames parser.
//
// Re-importing goes through import::open_source (CSV is read by sluice itself,
// .vtp/.pvd through VTK: only with SLUICE_WITH_VTK). The LOD value is a hash
// of the solver's particle id, which a container does not store, so a
// re-conversion cannot recompute it: LOD values are compared through the
// exported `lod` array (read back as an attribute), positions and attributes
// also through re-conversion.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "frame_range.h"
#include "sluice/import/frames.h"
#include "sluice/error.h"
#include "sluice/io/export.h"
#include "sluice/import/source.h"
#include "sluice/import/vtk.h"
#include "sluice/io/lod.h"
#include "sluice/io/reader.h"
#include "test_util.h"
#if SLUICE_WITH_RENDER
#include "sluice/render/lod.h"
#endif

namespace test = sluice::test;
namespace io = sluice::io;
namespace render = sluice::render;
namespace app = sluice::app;
using namespace sluice::io;
using namespace sluice::import;
using sluice::app::parse_frame_range;

namespace {

constexpr uint64_t kParticles = 20000;
const std::vector<double> kTimes = {0.0, 0.125, 1.0 / 3.0};  // 1/3: no short decimal, must still round-trip
const std::vector<std::string> kReimported = {"lod", "rho", "speed"};  // the exported arrays, as attributes

SourceOptions reimport_options() {
  SourceOptions o;
  o.attributes = kReimported;
  return o;
}

float ulp(float v) { return std::nextafter(std::fabs(v), INFINITY) - std::fabs(v); }

// Three frames of the test lattice (the last with half the particles, the
// first half of the same ids) with a second attribute.
std::vector<ParticleFrame> source_frames() {
  std::vector<ParticleFrame> frames;
  for (size_t f = 0; f < kTimes.size(); ++f) {
    ParticleFrame p = test::lattice_frame(f == 2 ? kParticles / 2 : kParticles, kTimes[f], uint32_t(f + 1));
    std::vector<float> speed;
    for (uint64_t i = 0; i < p.count(); ++i) speed.push_back(0.5f + 3.f * std::fabs(p.positions[3 * i + 2]));
    p.attributes.push_back(std::move(speed));
    frames.push_back(std::move(p));
  }
  return frames;
}

// Per exported particle: half a quantization step of its chunk, per axis and
// per attribute, plus float rounding (two ulps of the range's magnitude).
struct Bounds {
  std::vector<std::array<float, 3>> position;
  std::vector<std::vector<float>> attribute;  // [attribute][particle]
  std::vector<std::array<float, 3>> position_half_step;  // without the rounding allowance
  std::vector<std::vector<float>> attribute_half_step;
};

Bounds quantization_bounds(const DecodedFrame& d) {
  Bounds b;
  b.position.resize(d.header.particle_count);
  b.attribute.assign(d.attributes.size(), std::vector<float>(d.header.particle_count));
  b.position_half_step = b.position;
  b.attribute_half_step = b.attribute;
  for (size_t c = 0; c < d.header.chunks.size(); ++c) {
    const ChunkDesc& chunk = d.header.chunks[c];
    for (uint64_t i = d.chunk_first[c]; i < d.chunk_first[c] + chunk.particle_count; ++i) {
      for (int a = 0; a < 3; ++a) {
        const float lo = chunk.bounds.min[a], hi = chunk.bounds.max[a];
        b.position_half_step[i][a] = 0.5f * (hi - lo) / 65535.f;
        b.position[i][a] = b.position_half_step[i][a] + 2 * ulp(std::max(std::fabs(lo), std::fabs(hi)));
      }
      for (size_t a = 0; a < d.attributes.size(); ++a) {
        const auto [lo, hi] = chunk.attribute_ranges[a];
        b.attribute_half_step[a][i] = 0.5f * (hi - lo) / 65535.f;
        b.attribute[a][i] = b.attribute_half_step[a][i] + 2 * ulp(std::max(std::fabs(lo), std::fabs(hi)));
      }
    }
  }
  return b;
}

// The source particle each exported particle stands for: the one with the
// same LOD value nearest to it, one to one. Returns source indices.
std::vector<size_t> match_source(const ExportFrame& e, const ParticleFrame& src) {
  const std::vector<uint16_t> lod = lod_values(src.ids, src.count());
  std::multimap<uint16_t, size_t> by_lod;
  for (size_t i = 0; i < src.count(); ++i) by_lod.emplace(lod[i], i);
  std::vector<size_t> match(e.count(), SIZE_MAX);
  std::vector<int> used(src.count(), 0);
  for (size_t i = 0; i < e.count(); ++i) {
    double best_d = INFINITY;
    auto [lo, hi] = by_lod.equal_range(e.lod[i]);
    for (auto it = lo; it != hi; ++it) {
      double dist = 0;
      for (int a = 0; a < 3; ++a) dist += std::pow(double(e.positions[3 * i + a]) - src.positions[3 * it->second + a], 2);
      if (dist < best_d) best_d = dist, match[i] = it->second;
    }
    EXPECT_NE(match[i], SIZE_MAX) << "exported LOD value " << e.lod[i] << " is not in the source";
    if (match[i] != SIZE_MAX) EXPECT_EQ(used[match[i]]++, 0) << "two exported particles match one source particle";
  }
  return match;
}

// A re-imported frame (arrays kReimported) holds exactly the exported particles.
void expect_identical(const ExportFrame& want, const ParticleFrame& got) {
  ASSERT_EQ(got.count(), want.count());
  ASSERT_EQ(got.attributes.size(), 1 + want.attributes.size());
  for (size_t i = 0; i < 3 * want.count(); ++i) ASSERT_EQ(got.positions[i], want.positions[i]) << "coordinate " << i;
  for (size_t i = 0; i < want.count(); ++i) ASSERT_EQ(got.attributes[0][i], float(want.lod[i])) << "lod of " << i;
  for (size_t a = 0; a < want.attributes.size(); ++a) {
    for (size_t i = 0; i < want.count(); ++i) ASSERT_EQ(got.attributes[1 + a][i], want.attributes[a][i]) << a << " " << i;
  }
}

// One particle for set comparisons: x, y, z, lod, rho, speed.
using Row = std::array<float, 6>;

std::vector<Row> rows_of(const ExportFrame& e) {
  std::vector<Row> rows;
  for (size_t i = 0; i < e.count(); ++i) {
    rows.push_back({e.positions[3 * i], e.positions[3 * i + 1], e.positions[3 * i + 2], float(e.lod[i]),
                    e.attributes[0][i], e.attributes[1][i]});
  }
  std::sort(rows.begin(), rows.end());
  return rows;
}

// Converts `spec` (exported files) back into a lossless container (float32
// positions, the three arrays as attributes), as `sluice convert --lossless
// -a lod,rho,speed` does, and returns it.
std::unique_ptr<ContainerReader> reconvert(const std::string& spec, const std::filesystem::path& out) {
  const auto source = open_source(spec, reimport_options());
  FileHeader h;
  h.position_coding = PositionCoding::Float32;
  h.particle_spacing = 0.01f;
  for (const auto& a : kReimported) h.attributes.push_back({a});
  h.lod_source = LodSource::ParticleOrder;
  {
    ContainerWriter w(out, h);
    FramesSettings settings;
    settings.encode.chunk_particles = 3000;  // other chunks than the original's
    convert_frames(*source, std::nullopt, w, settings);
    w.finish();
  }
  return std::make_unique<ContainerReader>(out);
}

// A re-converted frame holds the exported particles: positions exact
// (lossless), the arrays (lod included: 16-bit quantization of a range of
// integers is not exact) within the re-conversion's own quantization.
// Particles are matched by position.
void expect_reconverted(const ExportFrame& want, const ContainerReader& r, uint64_t frame) {
  const DecodedFrame d = decode_frame(r, frame);
  const ExportFrame got = to_export_frame(d, r.header(), std::vector<size_t>{0, 1, 2});
  const Bounds b = quantization_bounds(d);
  ASSERT_EQ(got.count(), want.count());
  std::vector<std::pair<Row, std::array<float, 3>>> have;  // row, bounds of lod, rho, speed
  for (size_t i = 0; i < got.count(); ++i) {
    have.push_back({{got.positions[3 * i], got.positions[3 * i + 1], got.positions[3 * i + 2], got.attributes[0][i],
                     got.attributes[1][i], got.attributes[2][i]},
                    {b.attribute[0][i], b.attribute[1][i], b.attribute[2][i]}});
  }
  std::sort(have.begin(), have.end());
  const std::vector<Row> rows = rows_of(want);
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& [row, bound] = have[i];
    for (int a = 0; a < 3; ++a) ASSERT_EQ(row[a], rows[i][a]) << "particle " << i << " axis " << a;
    for (int a = 0; a < 3; ++a) ASSERT_LE(std::fabs(row[3 + a] - rows[i][3 + a]), bound[a]) << "particle " << i;
  }
}

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Export : public ::testing::Test {
 protected:
  void SetUp() override {
    header = test::test_header(PositionCoding::Quantized16);
    header.attributes.push_back({"speed"});
    frames = source_frames();
    reader = std::make_unique<ContainerReader>(test::write_file(dir / "src.sluice", header, frames));
  }
  ExportFrame exported(uint64_t f) const {
    return to_export_frame(decode_frame(*reader, f), reader->header(), std::vector<size_t>{0, 1});
  }

  test::TempDir dir;
  FileHeader header;
  std::vector<ParticleFrame> frames;
  std::unique_ptr<ContainerReader> reader;
};

}  // namespace

// ---------------------------------------------------------------- the plain form

TEST_F(Export, PlainFrameIsTheDecodedFrame) {
  const DecodedFrame d = decode_frame(*reader, 1);
  const ExportFrame e = exported(1);
  EXPECT_EQ(e.count(), kParticles);
  EXPECT_EQ(e.time, kTimes[1]);
  EXPECT_EQ(e.positions, world_positions(d, PositionCoding::Quantized16));
  EXPECT_EQ(e.lod, lod_values_of(d, PositionCoding::Quantized16));
  EXPECT_EQ(e.attribute_names, (std::vector<std::string>{"rho", "speed"}));

  // A subset, in the order asked for.
  const ExportFrame only = to_export_frame(d, reader->header(), std::vector<size_t>{1});
  EXPECT_EQ(only.attribute_names, std::vector<std::string>{"speed"});
  EXPECT_EQ(only.attributes[0], e.attributes[1]);
  EXPECT_THROW(to_export_frame(d, reader->header(), std::vector<size_t>{2}), Error);
}

// The figures docs/export.md quotes: what the container's quantization costs
// (the exporters themselves add nothing, see the tests below).
TEST_F(Export, ParticlesMatchTheSourceWithinHalfAQuantizationStep) {
  double worst_pos = 0, worst_pos_abs = 0, worst_attr = 0, worst_attr_abs = 0;
  for (uint64_t f = 0; f < frames.size(); ++f) {
    const DecodedFrame d = decode_frame(*reader, f);
    const ExportFrame e = exported(f);
    const Bounds b = quantization_bounds(d);
    const std::vector<size_t> match = match_source(e, frames[f]);
    for (size_t i = 0; i < e.count(); ++i) {
      const size_t s = match[i];
      ASSERT_NE(s, SIZE_MAX);
      for (int a = 0; a < 3; ++a) {
        const float err = std::fabs(e.positions[3 * i + a] - frames[f].positions[3 * s + a]);
        ASSERT_LE(err, b.position[i][a]) << "frame " << f << " particle " << i << " axis " << a;
        if (b.position_half_step[i][a] > 0) worst_pos = std::max(worst_pos, double(err) / b.position_half_step[i][a]);
        worst_pos_abs = std::max(worst_pos_abs, double(err));
      }
      for (size_t a = 0; a < 2; ++a) {
        const float err = std::fabs(e.attributes[a][i] - frames[f].attributes[a][s]);
        ASSERT_LE(err, b.attribute[a][i]) << "frame " << f << " particle " << i << " attribute " << a;
        if (b.attribute_half_step[a][i] > 0) worst_attr = std::max(worst_attr, double(err) / b.attribute_half_step[a][i]);
        worst_attr_abs = std::max(worst_attr_abs, double(err));
      }
    }
  }
  std::printf("[measured] position error: max %.3g world units (spacing 0.01), %.4f half-steps of the chunk box\n",
              worst_pos_abs, worst_pos);
  std::printf("[measured] attribute error: max %.3g (rho ~1000, speed ~1), %.4f half-steps of the chunk range\n",
              worst_attr_abs, worst_attr);
  RecordProperty("max_position_error", std::to_string(worst_pos_abs));
  RecordProperty("max_attribute_error", std::to_string(worst_attr_abs));
}

// ---------------------------------------------------------------- CSV

TEST_F(Export, CsvReadsBackExactly) {
  const ExportFrame e = exported(0);
  const auto path = dir / "f.csv";
  const uint64_t bytes = write_csv(path.string(), e);
  EXPECT_EQ(bytes, std::filesystem::file_size(path));
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".partial"));
  const std::string text = read_text(path);
  EXPECT_EQ(text.substr(0, text.find('\n')), "x,y,z,lod,rho,speed");
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), std::ptrdiff_t(e.count() + 1));
  const ParticleFrame back = open_source(path.string(), reimport_options())->read(0);
  expect_identical(e, back);
}

TEST_F(Export, CsvSeriesConvertsBack) {
  for (uint64_t f = 0; f < frames.size(); ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "s_%05llu.csv", (unsigned long long)f);
    write_csv((dir / name).string(), exported(f));
  }
  const auto r = reconvert((dir / "s_*.csv").string(), dir / "back_csv.sluice");
  ASSERT_EQ(r->frame_count(), frames.size());
  for (uint64_t f = 0; f < frames.size(); ++f) expect_reconverted(exported(f), *r, f);
}

// ---------------------------------------------------------------- PLY

TEST_F(Export, PlyIsBinaryLittleEndianWithTheExpectedLayout) {
  ExportFrame e = exported(2);
  e.attribute_names[1] = "flow speed";  // white space becomes '_'
  const auto path = dir / "f.ply";
  write_ply(path.string(), e);
  const std::string bytes = read_text(path);
  const std::string end = "end_header\n";
  const size_t body = bytes.find(end) + end.size();
  ASSERT_NE(body, std::string::npos + end.size());
  EXPECT_EQ(bytes.substr(0, body),
            "ply\nformat binary_little_endian 1.0\ncomment written by sluice export\ncomment time 0.3333333333333333\n"
            "element vertex " + std::to_string(e.count()) +
                "\nproperty float x\nproperty float y\nproperty float z\nproperty ushort lod\n"
                "property float rho\nproperty float flow_speed\nend_header\n");
  constexpr size_t kRecord = 12 + 2 + 4 + 4;
  ASSERT_EQ(bytes.size() - body, kRecord * e.count());
  for (size_t i = 0; i < e.count(); ++i) {
    const char* p = bytes.data() + body + kRecord * i;
    float xyz[3], rho, speed;
    uint16_t lod;
    std::memcpy(xyz, p, 12);
    std::memcpy(&lod, p + 12, 2);
    std::memcpy(&rho, p + 14, 4);
    std::memcpy(&speed, p + 18, 4);
    for (int a = 0; a < 3; ++a) ASSERT_EQ(xyz[a], e.positions[3 * i + a]);
    ASSERT_EQ(lod, e.lod[i]);
    ASSERT_EQ(rho, e.attributes[0][i]);
    ASSERT_EQ(speed, e.attributes[1][i]);
  }
}

// ---------------------------------------------------------------- VTK

#if SLUICE_WITH_VTK
TEST_F(Export, VtpReadsBackExactlyThroughVtk) {
  ASSERT_TRUE(has_vtk_support());
  const ExportFrame e = exported(2);
  const auto path = dir / "f.vtp";
  write_vtp(path.string(), e);
  EXPECT_EQ(read_with_vtk(path.string()), e.count());  // VTK's reader, every array
  const ParticleFrame back = open_source(path.string(), reimport_options())->read(0);
  EXPECT_TRUE(back.repairs.empty()) << back.repairs.front();  // vertex cells only
  EXPECT_EQ(back.time, kTimes[2]);                            // FieldData TimeValue
  expect_identical(e, back);
}

TEST_F(Export, PvdSeriesKeepsTimesAndConvertsBack) {
  std::vector<PvdEntry> entries;
  std::filesystem::create_directories(dir / "out");
  for (uint64_t f = 0; f < frames.size(); ++f) {
    const std::string name = "out_0000" + std::to_string(f) + ".vtp";
    write_vtp((dir / "out" / name).string(), exported(f));
    entries.push_back({kTimes[f], name});
  }
  const std::string pvd = (dir / "out" / "out.pvd").string();
  write_pvd(pvd, entries);

  const auto source = open_source(pvd, reimport_options());
  ASSERT_EQ(source->frame_count(), frames.size());
  for (uint64_t f = 0; f < frames.size(); ++f) {
    const ParticleFrame back = source->read(f);
    EXPECT_EQ(back.time, kTimes[f]) << "frame " << f;
    expect_identical(exported(f), back);
  }
  const auto r = reconvert(pvd, dir / "back_vtp.sluice");
  ASSERT_EQ(r->frame_count(), frames.size());
  for (uint64_t f = 0; f < frames.size(); ++f) {
    EXPECT_EQ(r->index().frames[f].time, kTimes[f]) << "frame " << f;
    expect_reconverted(exported(f), *r, f);
  }
}

TEST_F(Export, EmptyVtpIsValid) {
  ExportFrame e = exported(0);
  thin_by_lod(e, 0.f);
  ASSERT_EQ(e.count(), 0u);
  const auto path = dir / "empty.vtp";
  write_vtp(path.string(), e);
  EXPECT_EQ(read_with_vtk(path.string()), 0u);
  EXPECT_EQ(open_source(path.string(), reimport_options())->read(0).count(), 0u);
}
#endif

// ---------------------------------------------------------------- errors

TEST_F(Export, IoFailureNamesTheOutputAndLeavesNothing) {
  const ExportFrame e = exported(0);
  const std::string path = (dir / "missing" / "f.csv").string();
  for (ExportFormat format : {ExportFormat::Vtp, ExportFormat::Csv, ExportFormat::Ply}) {
    try {
      write_export(path, e, format);
      FAIL() << "no error";
    } catch (const Error& err) {
      EXPECT_EQ(err.where().file, path);
      EXPECT_NE(err.message().find("No such file or directory"), std::string::npos) << err.message();
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
  std::vector<PvdEntry> none;
  EXPECT_THROW(write_pvd(path, none), Error);
}

TEST_F(Export, RejectsNamesTheWritersUse) {
  ExportFrame e = exported(0);
  e.attribute_names[0] = "lod";
  EXPECT_THROW(write_csv((dir / "a.csv").string(), e), Error);
  e.attribute_names[0] = "Z";
  EXPECT_THROW(write_vtp((dir / "a.vtp").string(), e), Error);
  e.attribute_names = {"a b", "a_b"};  // the same once PLY has replaced the space
  EXPECT_THROW(write_ply((dir / "a.ply").string(), e), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "a.ply"));
}

TEST(ExportFormatOf, TheExtension) {
  EXPECT_EQ(export_format_of("a/b.vtp"), ExportFormat::Vtp);
  EXPECT_EQ(export_format_of("B.CSV"), ExportFormat::Csv);
  EXPECT_EQ(export_format_of("shot_%04d.ply"), ExportFormat::Ply);
  EXPECT_EQ(export_format_of("a.vtu"), std::nullopt);
  EXPECT_EQ(export_format_of("dir.vtp/file"), std::nullopt);
  EXPECT_EQ(export_format_of("vtp"), std::nullopt);
}

// ---------------------------------------------------------------- thinning

// Over every possible LOD value, the rule keeps the fraction `level`.
TEST(LodThinning, RuleKeepsTheFractionLevel) {
  for (float level : {0.f, 0.01f, 0.1f, 0.25f, 0.5f, 0.75f, 0.9f, 1.f}) {
    uint32_t kept = 0;
    for (uint32_t v = 0; v < 65536; ++v) kept += lod_keeps(uint16_t(v), level);
    EXPECT_NEAR(double(kept) / 65536.0, level, 2.0 / 65536.0) << "level " << level;
    // The kept values are the top ones: a threshold on the value.
    for (uint32_t v = 1; v < 65536; ++v) ASSERT_LE(lod_keeps(uint16_t(v - 1), level), lod_keeps(uint16_t(v), level));
  }
}

#if SLUICE_WITH_RENDER
// The renderer's cLOD decision for a particle of importance 1.
TEST(LodThinning, SameDecisionAsTheRenderer) {
  for (float level : {0.f, 0.001f, 0.1f, 0.25f, 0.3f, 0.5f, 0.9f, 0.999f, 1.f}) {
    for (uint32_t v = 0; v < 65536; ++v) {
      ASSERT_EQ(lod_keeps(uint16_t(v), level), render::lod_keep(level, 1.0f, render::lod_uniform(uint16_t(v))))
          << "level " << level << " value " << v;
    }
  }
}
#endif

TEST_F(Export, ThinningKeepsAQuarterUniformlyAndTheSameParticles) {
  constexpr float kLevel = 0.25f;
  std::vector<std::set<uint64_t>> kept_ids(frames.size());
  for (uint64_t f = 0; f < frames.size(); ++f) {
    const ExportFrame all = exported(f);
    ExportFrame thin = all;
    thin_by_lod(thin, kLevel);
    // The kept particles are the unthinned ones whose value passes, in order, intact.
    size_t k = 0;
    for (size_t i = 0; i < all.count(); ++i) {
      if (!lod_keeps(all.lod[i], kLevel)) continue;
      ASSERT_LT(k, thin.count());
      ASSERT_EQ(thin.lod[k], all.lod[i]);
      for (int a = 0; a < 3; ++a) ASSERT_EQ(thin.positions[3 * k + a], all.positions[3 * i + a]);
      for (size_t a = 0; a < 2; ++a) ASSERT_EQ(thin.attributes[a][k], all.attributes[a][i]);
      ++k;
    }
    ASSERT_EQ(k, thin.count());

    const double fraction = double(thin.count()) / double(all.count());
    std::printf("[measured] frame %llu: --lod-level %.2f kept %llu of %llu particles (%.4f)\n", (unsigned long long)f,
                double(kLevel), (unsigned long long)thin.count(), (unsigned long long)all.count(), fraction);
    EXPECT_NEAR(fraction, kLevel, 0.015);

    // Uniform in space: about the same fraction in each octant of the frame.
    std::array<double, 3> mid{};
    for (int a = 0; a < 3; ++a) {
      mid[a] = 0.5 * (double(reader->index().frames[f].bounds.min[a]) + reader->index().frames[f].bounds.max[a]);
    }
    const auto octant = [&](const ExportFrame& e, size_t i) {
      int o = 0;
      for (int a = 0; a < 3; ++a) o |= (e.positions[3 * i + a] > mid[a]) << a;
      return o;
    };
    std::array<double, 8> total{}, kept{};
    for (size_t i = 0; i < all.count(); ++i) total[octant(all, i)] += 1;
    for (size_t i = 0; i < thin.count(); ++i) kept[octant(thin, i)] += 1;
    for (int o = 0; o < 8; ++o) {
      if (total[o] > 500) EXPECT_NEAR(kept[o] / total[o], kLevel, 0.05) << "frame " << f << " octant " << o;
    }

    // Which simulation particles survived, by id.
    const std::vector<size_t> match = match_source(thin, frames[f]);
    for (size_t s : match) kept_ids[f].insert(frames[f].ids.at(s));
  }
  // Frames 0 and 1 hold the same ids; frame 2 the first half of them.
  EXPECT_EQ(kept_ids[0], kept_ids[1]);
  std::set<uint64_t> first_half;
  for (uint64_t id : kept_ids[0]) {
    if (id < 1000 + kParticles / 2) first_half.insert(id);
  }
  EXPECT_EQ(kept_ids[2], first_half);
}

// ---------------------------------------------------------------- --frames

TEST(FrameRange, Forms) {
  using app::parse_frame_range;
  using Range = std::pair<uint64_t, uint64_t>;
  EXPECT_EQ(parse_frame_range("", 5), Range(0, 4));
  EXPECT_EQ(parse_frame_range("2:4", 5), Range(2, 4));
  EXPECT_EQ(parse_frame_range("3", 5), Range(3, 3));
  EXPECT_EQ(parse_frame_range("2:", 5), Range(2, 4));
  EXPECT_EQ(parse_frame_range(":1", 5), Range(0, 1));
  EXPECT_EQ(parse_frame_range(":", 5), Range(0, 4));
  EXPECT_EQ(parse_frame_range("4:4", 5), Range(4, 4));
}

TEST(FrameRange, Errors) {
  using app::parse_frame_range;
  for (const char* bad : {"4:2", "5", "0:5", "a", "1:b", "-1", "+1", " 1", "1:2:3", "1.5", "99999999999999999999"}) {
    try {
      parse_frame_range(bad, 5);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("--frames"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(parse_frame_range("", 0), std::runtime_error);
}

TEST(FrameRange, Lists) {
  using app::parse_frame_list;
  using List = std::vector<uint64_t>;
  EXPECT_EQ(parse_frame_list("", 3), List({0, 1, 2}));
  EXPECT_EQ(parse_frame_list("0,25,50", 51), List({0, 25, 50}));
  EXPECT_EQ(parse_frame_list("50,0,25,0", 51), List({0, 25, 50}));  // sorted, each once
  EXPECT_EQ(parse_frame_list("0:2,48:", 51), List({0, 1, 2, 48, 49, 50}));
  for (const char* bad : {"0,,2", "0,", ",1", "0,51", "0,4:2"}) {
    try {
      parse_frame_list(bad, 51);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("--frames"), std::string::npos) << e.what();
    }
  }
}
