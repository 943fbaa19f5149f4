// A container record decoded on the CPU straight into a renderer's staging
// (load.h): for tools, tests and the live source.
#include "sluice/render/load.h"

#include <vector>

#include "renderer_state.h"
#include "sluice/io/codec.h"
#include "sluice/io/reader.h"
#include "upload.h"

namespace sluice::render {

uint64_t commit_record(Renderer& renderer, std::span<const std::byte> record, const io::FrameHeader& header,
                       const io::FileHeader& file, int color_attribute, const io::ErrorLocation& where) {
  detail::RendererImpl& r = renderer_impl(renderer);
  if (file.position_coding != r.scene.coding) throw io::Error(where, "frame coding differs from the scene's");
  const uint32_t chunks = uint32_t(header.chunks.size());
  FrameStaging s = renderer.stage_frame(header.particle_count, chunks);
  const bool attr =
      color_attribute >= 0 && size_t(color_attribute) < file.attributes.size() && !s.color_attribute.empty();
  fill_chunk_table(header, {}, attr ? color_attribute : -1, s.chunks, where);
  mark_layers(r.sets[size_t(r.staged)], header);
  std::vector<uint64_t> starts(chunks);
  io::chunk_starts(header, starts);
  std::vector<uint16_t*> attributes(file.attributes.size(), nullptr);
  if (attr) attributes[size_t(color_attribute)] = s.color_attribute.data();
  // Every chunk straight into the mapped staging memory.
  io::decode_record(record, header, file, starts, s.particles, attributes, where);
  return renderer.commit_frame();
}

void load_frame(Renderer& renderer, const io::ContainerReader& reader, uint64_t frame, int color_attribute,
                io::LayerSet layers) {
  const std::vector<std::byte> record = reader.read_record(frame);
  io::FrameHeader header = reader.parse_record(frame, record);
  io::keep_layers(header, layers);
  renderer.wait_upload(
      commit_record(renderer, record, header, reader.header(), color_attribute, reader.location(frame)));
}

}  // namespace sluice::render
