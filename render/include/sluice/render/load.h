// sluice/render/load.h: a frame of a .sluice file into a renderer without
// the streaming runtime, decoded on the CPU (chunks in parallel, TBB)
// straight into the renderer's staging: for tools, tests and benches. A
// player streams instead (render/stream.h).
//
// Threads: the renderer's thread. Errors: io::Error naming the file, frame
// and chunk on a bad record; render::Error for a frame the scene cannot take.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/render/renderer.h"

namespace sluice::io {
class ContainerReader;
}  // namespace sluice::io

namespace sluice::render {

// Decodes a container frame record (`header` parsed from it, `file` the file
// header it belongs to) into staging and commits it; returns the upload
// ticket. `color_attribute` < 0 skips attributes. Errors at `where` (the
// chunk filled in).
uint64_t commit_record(Renderer& renderer, std::span<const std::byte> record, const io::FrameHeader& header,
                       const io::FileHeader& file, int color_attribute, const io::ErrorLocation& where);

// Reads `frame`'s chunks of `layers` (all of a file without layers),
// commit_record()s them and waits for the copy.
void load_frame(Renderer& renderer, const io::ContainerReader& reader, uint64_t frame, int color_attribute,
                io::LayerSet layers = io::LayerSet::particles());

}  // namespace sluice::render
