// Fuzzes one chunk's payload through decode_chunk: the plane table, zstd
// frames, bit-packed planes with their escapes, stored planes, and the
// unfilters; then through the GPU decoder's CPU side (plan_gpu_decode,
// stage_frame) and its reference decode (decode_plan_on_cpu, what the
// kernel computes), and the same chunk planned from its payload alone
// (plan_gpu_frame, plan_gpu_chunk). Any io::Error is a correct answer; a crash, a sanitizer
// report or a read or write outside the chunk's buffers is a bug, and so is
// a plan the CPU accepts whose decode differs from decode_chunk's.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "bytes.h"
#include "fuzz_chunk.h"
#include "sluice/io/codec.h"
#include "sluice/error.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/gpu_decode_reference.h"

using namespace sluice;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < fuzz::kChunkSetupBytes) return 0;
  const fuzz::ChunkSetup setup = fuzz::chunk_setup(data, size);
  io::FileHeader header;
  header.position_coding = io::PositionCoding::Quantized16;
  for (size_t a = 0; a < setup.attributes; ++a) header.attributes.push_back({"a" + std::to_string(a)});
  // The payload in a buffer of its own size, so reading past it is caught.
  const std::vector<std::byte> record(reinterpret_cast<const std::byte*>(data) + setup.bytes,
                                      reinterpret_cast<const std::byte*>(data) + size);
  io::ChunkDesc chunk;
  chunk.offset = 0;
  chunk.compressed_size = static_cast<uint32_t>(record.size());
  if (setup.split) {  // format 3.0: the payload's tail is the record's fine part
    const uint32_t fine = setup.fine_bytes;
    chunk.compressed_size -= fine;
    chunk.fine.offset = chunk.compressed_size;
    chunk.fine.size = fine;
    chunk.fine.codec = static_cast<io::ChunkCodec>(setup.fine_codec);
    chunk.fine.checksum = io::checksum(std::span(record).subspan(chunk.compressed_size));
    chunk.fine.index = 1;
    chunk.fine.dropped = setup.coarse;
  }
  chunk.particle_count = setup.particles;
  chunk.codec = static_cast<io::ChunkCodec>(setup.codec);
  chunk.bounds.extend(0, 0, 0);
  chunk.bounds.extend(1, 1, 1);
  chunk.attribute_ranges.assign(setup.attributes, {0.f, 1.f});
  chunk.checksum = io::checksum(std::span(record).first(chunk.compressed_size));
  std::vector<std::byte> particles(size_t(setup.particles) * 8);
  std::vector<std::vector<uint16_t>> attributes(setup.attributes, std::vector<uint16_t>(setup.particles));
  std::vector<uint16_t*> attribute_ptrs;
  for (auto& a : attributes) attribute_ptrs.push_back(a.data());
  thread_local io::DecodeScratch scratch;
  bool decoded = false;
  try {
    io::decode_chunk(record, chunk, header, {particles, attribute_ptrs}, scratch, {"fuzz.sluice", 0, 0});
    decoded = true;
  } catch (const io::Error&) {
  }

  io::FrameHeader frame;
  frame.particle_count = setup.particles;
  frame.frame_bytes = record.size();
  frame.chunks.push_back(chunk);
  const int color = setup.attributes > 0 ? 0 : -1;
  io::GpuDecodePlan plan;
  bool whole_planned = false;
  try {
    io::plan_gpu_decode(record, frame, header, {.color_attribute = color}, plan, {"fuzz.sluice", 0, 0});
    whole_planned = true;
    std::vector<std::byte> staged(plan.staged_bytes());
    io::stage_frame(record, frame, plan, staged, true, {"fuzz.sluice", 0, 0});
    std::vector<uint64_t> gpu_particles(setup.particles);
    std::vector<uint16_t> gpu_attribute(setup.particles);
    io::decode_plan_on_cpu(staged, plan, gpu_particles, gpu_attribute);
    // A chunk both decoders accept decodes to the same particles.
    if (decoded && std::memcmp(gpu_particles.data(), particles.data(), particles.size()) != 0) std::abort();
    if (decoded && color == 0 && gpu_attribute != attributes[0]) std::abort();
  } catch (const io::Error&) {
  }
  // The same chunk planned as a relaying reader plans it (the payload
  // alone, in a buffer of its own size): accepted only where the whole
  // record's plan is, to the same planes, or refused for a zstd plane.
  io::GpuDecodePlan steps;
  try {
    io::plan_gpu_frame(frame, header, {.color_attribute = color}, steps, {"fuzz.sluice", 0, 0});
    const io::ChunkDesc& c = frame.chunks[0];
    if (c.offset > record.size() || c.compressed_size > record.size() - c.offset) return 0;
    const std::vector<std::byte> payload(record.begin() + long(c.offset), record.begin() + long(c.offset + c.compressed_size));
    bool planned = io::plan_gpu_chunk(payload, frame, header, {.color_attribute = color}, 0, steps, {"fuzz.sluice", 0, 0});
    if (planned && c.fine.read()) {
      const std::vector<std::byte> fine(record.begin() + long(c.fine.offset), record.begin() + long(c.fine.offset + c.fine.size));
      planned = io::plan_gpu_fine(fine, frame, 0, steps, {"fuzz.sluice", 0, 0});
    }
    if (planned && (!whole_planned || plan.chunks.size() != 1 || plan.zstd_planes != 0 ||
                    std::memcmp(&plan.chunks[0], &steps.chunks[0], sizeof(io::GpuChunkPlan)) != 0)) {
      std::abort();
    }
  } catch (const io::Error&) {
  }
  return 0;
}
