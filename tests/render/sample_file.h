// The bundled PySPH dam break (data/dam_break_3d, 13 frames) converted with
// its rho attribute, once per test program, into a temp file removed when
// the program exits.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <optional>
#include <string>

#include "sluice/import/frames.h"
#include "sluice/io/point_set.h"
#include "sluice/io/writer.h"

namespace sluice::render::testing {

struct SampleFile {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("sluice_render_sample_" + std::to_string(::getpid()) + ".sluice");
  SampleFile() {
    import::SourceOptions import;
    import.attributes = {"rho"};
    const auto source = import::open_source(std::string(SLUICE_SAMPLE_DIR) + "/*.vtu", import);
    std::optional<io::ParticleFrame> first = source->read(0);
    io::FileHeader header;
    header.particle_spacing = io::estimate_spacing(first->positions);
    header.particle_radius = header.particle_spacing * 0.5f;
    header.frame_rate = 30;
    header.attributes.push_back({"rho"});
    header.lod_id_array = source->info().id_array;
    header.lod_source = header.lod_id_array.empty() ? io::LodSource::ParticleOrder : io::LodSource::IdHash;
    io::ContainerWriter writer(path, header);
    import::convert_frames(*source, std::move(first), writer,
                           import::FramesSettings{.encode = io::EncodeOptions{}, .max_in_flight = 2});
    writer.finish();
  }
  ~SampleFile() {
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
  }
};

inline const std::filesystem::path& sample_file() {
  static const SampleFile file;
  return file.path;
}

}  // namespace sluice::render::testing
