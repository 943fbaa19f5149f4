// The frames a stream benchmark plays: a prefix of the file, and its sizes.
#pragma once

#include <cstdint>

#include "sluice/io/reader.h"

namespace sluice::bench {

struct Slice {
  uint64_t frames = 0;
  uint64_t offset = 0, bytes = 0;  // their records in the file
  uint64_t particles = 0;          // in all of them
  uint64_t decoded = 0;            // decoded bytes of all of them
  io::LayerSet layers = io::LayerSet::particles();  // what is read of them
  uint64_t read = 0;               // bytes of the records the layers take (the read prefix of each)
  double in_per_frame() const { return double(read) / double(frames); }
  double out_per_frame() const { return double(decoded) / double(frames); }
};

// `wanted` frames from the start (0: as many as fit in `page_cache_room` bytes).
Slice slice_of(const io::ContainerReader& reader, uint64_t wanted, uint64_t page_cache_room, io::LayerSet layers);

}  // namespace sluice::bench
