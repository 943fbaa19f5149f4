#include "sluice/render/frame.h"

#include <algorithm>
#include <array>

#include "sluice/io/reader.h"

namespace sluice::render {

SceneInfo scene_info(const io::ContainerReader& reader) {
  SceneInfo s;
  const io::FileHeader& h = reader.header();
  const io::FrameIndex& index = reader.index();
  s.bounds = {{index.bounds.min[0], index.bounds.min[1], index.bounds.min[2]},
              {index.bounds.max[0], index.bounds.max[1], index.bounds.max[2]}};
  if (index.bounds.empty()) s.bounds = {{0, 0, 0}, {1, 1, 1}};
  const std::array<float, 3> up = io::up_vector(h.up);
  s.up = {up[0], up[1], up[2]};
  s.particle_spacing = h.particle_spacing;
  s.particle_radius = h.particle_radius;
  s.coding = h.position_coding;
  for (size_t a = 0; a < h.attributes.size(); ++a) {
    s.attribute_names.push_back(h.attributes[a].name);
    s.attribute_ranges.push_back(a < index.attribute_ranges.size() ? index.attribute_ranges[a]
                                                                   : std::array<float, 2>{0, 1});
  }
  for (const io::FrameIndexEntry& f : index.frames) {
    s.max_particles = std::max(s.max_particles, f.particle_count);
    s.max_chunks = std::max<uint64_t>(s.max_chunks, f.chunk_count);
  }
  return s;
}

}  // namespace sluice::render
