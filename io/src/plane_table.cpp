#include "plane_table.h"

#include <cstring>
#include <string>

#include "packed_plane.h"

namespace sluice::io {

void read_plane_table(std::span<const std::byte> payload, uint64_t payload_at, ChunkCodec codec, uint64_t n,
                      size_t planes, std::vector<PlaneSource>& out, const ErrorLocation& where) {
  out.resize(planes);
  if (codec == ChunkCodec::Stored) {
    if (payload.size() != n * planes) throw Error(where, "stored chunk has the wrong size");
    for (size_t p = 0; p < planes; ++p) out[p] = {payload_at + p * n, uint32_t(n), PlaneSource::Stored};
    return;
  }
  if (payload.size() < 4 * planes) throw Error(where, "chunk payload is smaller than its plane table");
  uint64_t at = 4 * planes;
  for (size_t p = 0; p < planes; ++p) {
    uint32_t entry;
    std::memcpy(&entry, payload.data() + 4 * p, 4);
    const bool packed = codec == ChunkCodec::Packed && (entry & kPackedPlaneFlag) != 0;
    const uint32_t size = packed ? entry & ~kPackedPlaneFlag : entry;
    if (size > payload.size() - at) throw Error(where, "plane " + std::to_string(p) + " runs past the chunk payload");
    const auto kind = packed ? PlaneSource::Packed : size == n ? PlaneSource::Stored : PlaneSource::Zstd;
    out[p] = {payload_at + at, size, kind};
    at += size;
  }
  if (at != payload.size()) throw Error(where, "chunk payload has trailing bytes");
}

}  // namespace sluice::io
