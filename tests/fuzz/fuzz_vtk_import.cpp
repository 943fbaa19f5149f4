// Fuzzes the VTK import path as `sluice convert` runs it: sluice's legacy
// reader, the size checks in front of VTK's XML readers, and those readers.
// The first byte picks the extension; the rest is the file. Any io::Error is
// a correct answer; a crash, a sanitizer report, a hang or an allocation
// beyond the limit is a bug.
//
// A frame that reads is then given an outlier (a finite far value, picked by
// the input's last bytes) and encoded: the oracle is the file's position
// bound, which every chunk's quantization step must keep whatever lies far.
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <string>

#include <cmath>
#include <cstdlib>
#include <cstdio>

#include "sluice/io/codec.h"
#include "sluice/error.h"
#include "sluice/import/source.h"
#include "sluice/io/lod.h"
#include "sluice/io/point_set.h"

namespace {

// Encodes `frame` with one particle moved far away and aborts if a chunk's
// quantization step exceeds the bound the header states.
void check_bound_with_outlier(sluice::io::ParticleFrame frame, const uint8_t* data, size_t size) {
  using namespace sluice::io;
  const size_t n = frame.count();
  if (n == 0 || n > 200000 || size < 4) return;
  static const float kFar[] = {1e3f, 1e6f, 1e30f, -1e6f, 3.4e38f, -3.4e38f, 65504.f, 1e-30f};
  const uint8_t* tail = data + size - 3;
  const size_t i = (size_t(tail[0]) << 8 | tail[1]) % n;
  frame.positions[3 * i + tail[2] % 3] = kFar[(tail[2] / 3) % 8];
  FileHeader h;
  h.particle_spacing = estimate_spacing(frame.positions);
  if (!(h.particle_spacing > 0) || !std::isfinite(h.particle_spacing)) h.particle_spacing = 1.0f;
  h.precision_bits = kDefaultPrecisionBits;
  // A spacing so small that the stated bound underflows to 0 promises what
  // no encoding can keep (found by this target, 2026-12-05: a frame with a
  // 1e-30 coordinate). The converter no longer states such a spacing
  // (ImportConvert.ASpacingWhoseBoundUnderflowsIsNotStated, the input in
  // tests/data/fuzz/findings/), so the property is checked where it can hold.
  if (!(position_bound(h) > 0)) return;
  const std::vector<uint16_t> lod = lod_values(frame.ids, n);
  FrameInput in;
  in.positions = frame.positions;
  in.lod = lod;
  EncodeOptions options;
  options.layers = (tail[2] & 1) != 0;
  const EncodedFrame e = encode_frame(in, h, options);
  const float bound = position_bound(h);
  for (const ChunkDesc& c : e.header.chunks) {
    if (const int a = axis_over_bound(c.bounds, bound); a >= 0) {
      std::fprintf(stderr, "chunk box %g .. %g on axis %d breaks the bound %g\n", double(c.bounds.min[size_t(a)]),
                   double(c.bounds.max[size_t(a)]), a, double(bound));
      std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* kExtensions[] = {".vtk", ".vtu", ".vtp", ".pvd"};
  const std::string path = "/tmp/sluice-fuzz-vtk-" + std::to_string(::getpid()) + kExtensions[data[0] % 4];
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data + 1),
                                                                 std::streamsize(size - 1));
  try {
    sluice::import::SourceOptions options;
    options.attributes = {"rho", "velocity"};
    const auto source = sluice::import::open_source(path, options);
    if (source->frame_count() > 0) (void)source->read(0);
  } catch (const sluice::io::Error&) {
  }
  try {
    const auto source = sluice::import::open_source(path, {});  // ids detected, no attributes
    if (source->frame_count() > 0) check_bound_with_outlier(source->read(0), data, size);
  } catch (const sluice::io::Error&) {
  }
  ::unlink(path.c_str());
  return 0;
}
