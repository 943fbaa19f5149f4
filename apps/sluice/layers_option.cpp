#include "layers_option.h"

#include "human.h"

namespace sluice::app {

void add_layers_option(CLI::App& cmd, std::string& value) {
  cmd.add_option("--layers", value,
                 "What to read and draw: surface (the narrow band, with voxel blobs for the interior's thickness:\n"
                 "the same picture from less data) or all (every particle). Files without layers are read whole;\n"
                 "with surface the GPU classifies each frame when it is first drawn")
      ->capture_default_str()
      ->check(CLI::IsMember({"surface", "all"}));
}

io::LayerSet layer_set(const std::string& value) {
  return value == "all" ? io::LayerSet::particles() : io::LayerSet::surface();
}

bool classify_unlayered(const std::string& value) { return value != "all"; }

std::string layers_text(const io::ContainerReader& reader, uint64_t frame, io::LayerSet set) {
  if (frame >= reader.frame_count()) return "";
  const io::FrameIndexEntry& e = reader.index().frames[frame];
  const std::string all = human_count(double(e.count_in(io::LayerSet::particles())));
  if (!e.layered()) {
    return set == io::LayerSet::particles() ? "all " + all + " particles (the file has no layers)"
                                            : "surface of " + all + " particles, classified on the GPU (the file has no layers)";
  }
  if (set == io::LayerSet::particles()) return "all " + all + " particles";
  return "surface " + human_count(double(e.layer_particles[size_t(io::Layer::Surface)])) + " of " + all +
         " particles + " + human_count(double(e.layer_particles[size_t(io::Layer::Blobs)])) + " blobs";
}

}  // namespace sluice::app
