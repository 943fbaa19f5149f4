#include <tbb/parallel_for.h>

#include <mutex>

#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"

namespace sluice::io {

VerifyReport verify_container(const std::filesystem::path& path, const ProgressFn& progress) {
  const ContainerReader reader(path);
  const FileHeader& fh = reader.header();
  VerifyReport report;
  const uint64_t frames = reader.frame_count();
  for (uint64_t f = 0; f < frames; ++f) {
    try {
      const std::vector<std::byte> record = reader.read_record(f);
      const FrameHeader h = reader.parse_record(f, record);
      report.chunks += h.chunks.size();
      report.particles += h.particle_count;
      report.bytes += record.size();
      std::mutex problems_mutex;  // only taken when a chunk is bad
      tbb::parallel_for(size_t(0), h.chunks.size(), [&](size_t c) {
        thread_local DecodeScratch scratch;
        const ChunkDesc& chunk = h.chunks[c];
        std::vector<std::byte> particles(chunk.particle_count * decoded_particle_bytes(fh.position_coding));
        try {
          decode_chunk(record, chunk, fh, {particles, {}}, scratch, reader.location(f, c));
        } catch (const Error& e) {
          const std::lock_guard lock(problems_mutex);
          report.problems.push_back(e.what());
        }
      });
    } catch (const Error& e) {
      report.problems.push_back(e.what());
    }
    ++report.frames;
    if (progress) progress(f + 1, frames);
  }
  return report;
}

}  // namespace sluice::io
