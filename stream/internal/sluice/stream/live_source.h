// sluice/stream/live_source.h (internal to stream): frames a host pushes
// from its own memory (a simulation running beside the viewer) instead of
// reading them from a file; a host pushes them through Stream::push().
//
// push() takes positions as float32 x,y,z in any order, optional stable ids
// and attributes, and turns them into exactly what a file frame is: LOD
// values from the ids (from the particle index without them), chunks in
// Morton order, positions quantized per chunk (io::encode_frame, as `sluice
// convert` does, parallel over chunks on TBB workers), decoded into the
// renderer's staging (render::commit_record in load.h, the same decode as file
// frames) and committed. The renderer draws it with the same cLOD. With a
// recording path, every pushed frame is also appended to a .sluice file, so
// what was shown can be replayed, converted back or shared.
//
// Ownership: borrows the renderer, which outlives it. Threads: the renderer's
// thread. Units: world units, seconds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/render/renderer.h"
#include "sluice/stream/stream.h"

namespace sluice::io {
class ContainerWriter;
}

namespace sluice::stream {

// The render::SceneInfo to make the render::Renderer with for live frames inside `bounds`.
render::SceneInfo live_scene(const render::Bounds& bounds, const LiveOptions& options,
                             std::vector<std::array<float, 2>> attribute_ranges = {}, uint64_t max_particles = 0);

class LiveSource {
 public:
  // Throws render::Error when the renderer's scene and the options
  // disagree (attributes), io::Error when the recording cannot be created.
  LiveSource(render::Renderer& renderer, const LiveOptions& options);
  ~LiveSource();  // without finish(), a recording is left without its index: `sluice recover` completes it
  LiveSource(const LiveSource&) = delete;
  LiveSource& operator=(const LiveSource&) = delete;

  // Encodes, decodes into staging and commits one frame; returns its upload
  // ticket (render::Renderer::upload_complete). Throws render::Error naming
  // the first bad value (sizes, a non-finite position) before anything is
  // committed or recorded.
  uint64_t push(const LiveFrame& frame);
  // Closes the recording: index and footer written, file complete.
  void finish();

  uint64_t frames_pushed() const { return pushed_; }
  // Milliseconds of the last push spent encoding (chunk, quantize, filter,
  // compress) and decoding into staging (CPU, wall clock).
  double last_encode_ms() const { return encode_ms_; }
  double last_decode_ms() const { return decode_ms_; }

 private:
  render::Renderer& renderer_;
  LiveOptions options_;
  io::FileHeader header_;
  std::unique_ptr<io::ContainerWriter> writer_;
  uint64_t pushed_ = 0;
  double encode_ms_ = 0, decode_ms_ = 0;
};

}  // namespace sluice::stream
