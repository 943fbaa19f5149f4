// Fuzzes one chunk's payload through decode_chunk: the plane table, zstd
// frames, bit-packed planes with their escapes, stored planes, and the
// unfilters. Any io::Error is a correct answer; a crash, a sanitizer report
// or a read or write outside the chunk's buffers is a bug.
#include <cstdint>
#include <vector>

#include "bytes.h"
#include "fuzz_chunk.h"
#include "sluice/io/codec.h"
#include "sluice/io/error.h"

using namespace sluice;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < fuzz::kChunkSetupBytes) return 0;
  const fuzz::ChunkSetup setup = fuzz::chunk_setup(data);
  io::FileHeader header;
  header.position_coding = io::PositionCoding::Quantized16;
  for (size_t a = 0; a < setup.attributes; ++a) header.attributes.push_back({"a" + std::to_string(a)});
  // The payload in a buffer of its own size, so reading past it is caught.
  const std::vector<std::byte> record(reinterpret_cast<const std::byte*>(data) + fuzz::kChunkSetupBytes,
                                      reinterpret_cast<const std::byte*>(data) + size);
  io::ChunkDesc chunk;
  chunk.offset = 0;
  chunk.compressed_size = static_cast<uint32_t>(record.size());
  chunk.particle_count = setup.particles;
  chunk.codec = static_cast<io::ChunkCodec>(setup.codec);
  chunk.bounds.extend(0, 0, 0);
  chunk.bounds.extend(1, 1, 1);
  chunk.attribute_ranges.assign(setup.attributes, {0.f, 1.f});
  chunk.checksum = io::checksum(record);
  std::vector<std::byte> particles(size_t(setup.particles) * 8);
  std::vector<std::vector<uint16_t>> attributes(setup.attributes, std::vector<uint16_t>(setup.particles));
  std::vector<uint16_t*> attribute_ptrs;
  for (auto& a : attributes) attribute_ptrs.push_back(a.data());
  thread_local io::DecodeScratch scratch;
  try {
    io::decode_chunk(record, chunk, header, {particles, attribute_ptrs}, scratch, {"fuzz.sluice", 0, 0});
  } catch (const io::Error&) {
  }
  return 0;
}
