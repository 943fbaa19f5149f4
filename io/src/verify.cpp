#include <tbb/parallel_for.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>

#include "records.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"

namespace sluice::io {

namespace {

// Why a chunk's box breaks the file's bound (axis_over_bound), if it does.
std::optional<std::string> too_wide(const ChunkDesc& chunk, float bound) {
  const int a = axis_over_bound(chunk.bounds, bound);
  if (a < 0) return std::nullopt;
  static const char* const kAxis[] = {"x", "y", "z"};
  const double width = double(chunk.bounds.max[size_t(a)]) - double(chunk.bounds.min[size_t(a)]);
  char text[200];
  std::snprintf(text, sizeof text, "its box is %g wide along %s: positions may be off by %g, more than the file's bound %g",
                width, kAxis[a], width / 131070.0, double(bound));
  return text;
}

// Format 1.5 puts a copy of the header before frame 0 (for `recover`);
// readers never look at it, so verify does: it must be the header again.
std::optional<std::string> damaged_header_copy(const ContainerReader& reader) {
  const uint64_t header_bytes = serialize_file_header(reader.header()).size();
  const uint64_t first = reader.frame_count() ? reader.index().frames[0].offset : header_bytes;
  if (first <= header_bytes) return std::nullopt;  // older files have none
  std::vector<std::byte> head(first);
  if (::pread(reader.descriptor(), head.data(), head.size(), 0) != ssize_t(head.size())) return "the header's copy cannot be read";
  const std::span<const std::byte> header = std::span(head).first(header_bytes);
  const std::vector<std::byte> expected = serialize_header_copy(header);
  if (std::ranges::equal(std::span(head).subspan(header_bytes), expected)) return std::nullopt;
  return "the copy of the header (bytes " + std::to_string(header_bytes) + " to " + std::to_string(first) +
         ", what `sluice recover` rebuilds a damaged header from) differs from the header";
}

}  // namespace

VerifyReport verify_container(const std::filesystem::path& path, const ProgressFn& progress) {
  const ContainerReader reader(path);
  const FileHeader& fh = reader.header();
  VerifyReport report;
  report.position_bound = position_bound(fh);
  const bool bounded = fh.position_coding == PositionCoding::Quantized16 && std::isfinite(report.position_bound);
  const uint64_t frames = reader.frame_count();
  if (const auto copy = damaged_header_copy(reader)) report.problems.push_back(Error(reader.location(0), *copy).what());
  for (uint64_t f = 0; f < frames; ++f) {
    try {
      const std::vector<std::byte> record = reader.read_record(f);
      const FrameHeader h = reader.parse_record(f, record);
      report.chunks += h.chunks.size();
      report.particles += count_in(h, LayerSet::particles());
      report.blobs += h.particle_count - count_in(h, LayerSet::particles());
      report.bytes += record.size();
      std::mutex problems_mutex;  // only taken when a chunk is bad
      tbb::parallel_for(size_t(0), h.chunks.size(), [&](size_t c) {
        thread_local DecodeScratch scratch;
        const ChunkDesc& chunk = h.chunks[c];
        std::vector<std::byte> particles(chunk.particle_count * decoded_particle_bytes(fh.position_coding));
        try {
          if (bounded) {
            if (const auto wide = too_wide(chunk, report.position_bound)) throw Error(reader.location(f, c), *wide);
          }
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
