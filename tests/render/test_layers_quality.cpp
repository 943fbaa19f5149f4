// The narrow band's picture on real solver output: the bundled PySPH dam
// break, converted with layers, drawn from its surface and voxel blobs and
// from all its particles from five viewpoints (bench/src/layers_bench.cpp):
// PSNR at least 40 dB and the same fluid pixels within 0.1%, wherever the
// near-camera cull leaves the surface whole; no validation error. The same
// with the narrow band classified on the GPU (RendererOptions::classify_unlayered),
// and with the asymmetry F2 test (`convert --band-f2 asymmetry`).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "sluice/bench/layers_bench.h"
#include "sluice/import/frames.h"
#include "sluice/import/source.h"
#include "sluice/io/point_set.h"
#include "sluice/io/writer.h"

namespace sluice {
namespace {

namespace fs = std::filesystem;

fs::path convert_sample_with_layers(const fs::path& out, io::F2Test f2) {
  const auto source = import::open_source(std::string(SLUICE_SAMPLE_DIR) + "/*.vtu", {});
  std::optional<io::ParticleFrame> first = source->read(0);
  io::FileHeader header;
  header.particle_spacing = io::estimate_spacing(first->positions);
  header.particle_radius = header.particle_spacing * 0.5f;
  header.lod_id_array = source->info().id_array;
  header.lod_source = header.lod_id_array.empty() ? io::LodSource::ParticleOrder : io::LodSource::IdHash;
  io::ContainerWriter writer(out, header);
  import::FramesSettings settings;
  settings.encode.layers = true;
  settings.encode.band_f2 = f2;
  import::convert_frames(*source, std::move(first), writer, settings);
  writer.finish();
  return out;
}

// The narrow band against every particle: `gpu` classifies the frame (read
// whole, its layers forgotten) on the GPU when it is first drawn; `f2` is
// the file's F2 test.
void expect_same_picture(bool gpu, io::F2Test f2 = io::F2Test::All) {
  const fs::path file = fs::temp_directory_path() /
                        ("sluice_layers_quality_" + std::to_string(::getpid()) + (gpu ? "_gpu" : "") +
                         (f2 == io::F2Test::Asymmetry ? "_asymmetry" : "") + ".sluice");
  convert_sample_with_layers(file, f2);
  bench::LayersBenchOptions o;
  o.input = file.string();
  o.frames = {0, 6, 12};
  o.width = 640;
  o.height = 360;
  o.repeats = 1;
  o.validation = true;
  o.gpu = gpu;
  const std::vector<bench::LayersRow> rows = bench::compare_layers(o);
  fs::remove(file);
  ASSERT_EQ(rows.size(), 3u * 6);
  size_t judged = 0;
  for (const bench::LayersRow& r : rows) {
    std::printf("frame %2llu %-9s PSNR %6.1f dB, fluid %6.2f%% vs %6.2f%%, drawn %llu vs %llu, largest splat %4.0f px (limit %.0f)\n",
                (unsigned long long)r.frame, r.view.c_str(), r.psnr, 100 * r.coverage_all, 100 * r.coverage_surface,
                (unsigned long long)r.drawn_all, (unsigned long long)r.drawn_surface, r.largest_splat_px, r.splat_limit_px);
    EXPECT_EQ(r.validation_errors, 0u) << r.view << " frame " << r.frame;
    EXPECT_GT(r.coverage_all, 0.05) << r.view << " frame " << r.frame << ": the view misses the fluid";
    EXPECT_LE(std::abs(r.coverage_surface - r.coverage_all), 0.001 * r.coverage_all) << r.view << " frame " << r.frame;
    if (!gpu) {
      EXPECT_LT(r.bytes_surface, r.bytes_all);
    }
    if (r.near_cull()) continue;
    ++judged;
    EXPECT_LT(r.drawn_surface, r.drawn_all) << r.view << " frame " << r.frame << ": the interior is left out";
    EXPECT_GE(r.psnr, 40.0) << r.view << " frame " << r.frame;
  }
  EXPECT_GE(judged, rows.size() - 3);  // at most one near-culled view per frame
  if (gpu) {  // once per frame, when it is first drawn
    EXPECT_EQ(std::count_if(rows.begin(), rows.end(), [](const bench::LayersRow& r) { return r.classify_ms > 0; }), 3);
    for (const bench::LayersRow& r : rows) {
      if (!r.classification.empty()) {
        EXPECT_EQ(r.classification.rfind("classified on the GPU: ", 0), 0u) << r.classification;
      }
    }
  }
}

TEST(LayersQuality, SurfaceAndBlobsLookLikeEveryParticle) {
#if !SLUICE_WITH_VTK
  GTEST_SKIP() << "needs the VTK importer to convert the sample";
#endif
  expect_same_picture(false);
}

TEST(LayersQuality, SurfaceByTheAsymmetryTestAndBlobsLookLikeEveryParticle) {
#if !SLUICE_WITH_VTK
  GTEST_SKIP() << "needs the VTK importer to convert the sample";
#endif
  expect_same_picture(false, io::F2Test::Asymmetry);
}

TEST(LayersQuality, SurfaceAndBlobsClassifiedOnTheGpuLookLikeEveryParticle) {
#if !SLUICE_WITH_VTK
  GTEST_SKIP() << "needs the VTK importer to convert the sample";
#endif
  expect_same_picture(true);
}

}  // namespace
}  // namespace sluice
