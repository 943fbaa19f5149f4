#include "layers_option.h"

#include "human.h"

namespace sluice::app {

void add_layers_option(CLI::App& cmd, std::string& value) {
  cmd.add_option("--layers", value,
                 "What to read and draw of a file with layers: surface (the narrow band, with voxel blobs for the\n"
                 "interior's thickness: the same picture from less data) or all (every particle). Files without\n"
                 "layers are drawn whole either way")
      ->capture_default_str()
      ->check(CLI::IsMember({"surface", "all"}));
}

io::LayerSet layer_set(const std::string& value) {
  return value == "all" ? io::LayerSet::particles() : io::LayerSet::surface();
}

std::string layers_text(const io::ContainerReader& reader, uint64_t frame, io::LayerSet set) {
  if (frame >= reader.frame_count()) return "";
  const io::FrameIndexEntry& e = reader.index().frames[frame];
  const std::string all = human_count(double(e.count_in(io::LayerSet::particles())));
  if (!e.layered()) return "all " + all + " particles (the file has no layers)";
  if (set == io::LayerSet::particles()) return "all " + all + " particles";
  return "surface " + human_count(double(e.layer_particles[size_t(io::Layer::Surface)])) + " of " + all +
         " particles + " + human_count(double(e.layer_particles[size_t(io::Layer::Blobs)])) + " blobs";
}

}  // namespace sluice::app
