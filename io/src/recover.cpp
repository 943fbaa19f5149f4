#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <optional>

#include "file.h"
#include "records.h"
#include "sluice/io/codec.h"
#include "sluice/io/maintenance.h"

namespace sluice::io {
namespace {

struct Scan {
  uint32_t header_bytes = 0;
  FileHeader header;
  std::optional<IndexBuilder> index;  // set once the header says how many attributes
  uint64_t end = 0;  // just past the last good frame
  std::string stopped_because;
};

// Walks the frame records from the header on; stops at the first that is
// incomplete or fails a check.
Scan scan_frames(int fd, uint64_t size, const std::string& path, const ProgressFn& progress) {
  Scan scan;
  const ErrorLocation where{path};
  std::vector<std::byte> fixed(kFileHeaderFixedBytes);
  if (size < fixed.size()) throw Error(where, "too small to be a .sluice file: nothing to recover");
  pread_all_or_throw(fd, fixed, 0, where);
  scan.header_bytes = peek_file_header_bytes(fixed, where);
  if (scan.header_bytes > size) throw Error(where, "file is shorter than its header: nothing to recover");
  std::vector<std::byte> head(scan.header_bytes);
  pread_all_or_throw(fd, head, 0, where);
  scan.header = parse_file_header(head, where);
  const size_t attributes = scan.header.attributes.size();
  scan.index.emplace(attributes);

  DecodeScratch scratch;
  std::vector<std::byte> record;
  uint64_t pos = scan.header_bytes;
  for (;;) {
    const auto number = static_cast<uint32_t>(scan.index->index().frames.size());
    const ErrorLocation at{path, number, {}};
    if (size - pos < kFrameHeaderFixedBytes) {
      scan.stopped_because = size == pos ? "end of file" : "frame " + std::to_string(number) + " is cut short";
      break;
    }
    try {
      pread_all_or_throw(fd, fixed = std::vector<std::byte>(kFrameHeaderFixedBytes), pos, at);
      const FramePrefix prefix = parse_frame_prefix(fixed, at);
      if (prefix.frame_number != number) throw Error(at, "frame number " + std::to_string(prefix.frame_number) + " out of sequence");
      if (prefix.frame_bytes > size - pos) throw Error(at, "frame is cut short");
      record.resize(prefix.frame_bytes);
      pread_all_or_throw(fd, record, pos, at);
      const FrameHeader h = parse_frame_table(record, attributes, at);
      for (size_t c = 0; c < h.chunks.size(); ++c) {
        std::vector<std::byte> particles(h.chunks[c].particle_count * decoded_particle_bytes(scan.header.position_coding));
        decode_chunk(record, h.chunks[c], scan.header, {particles, {}}, scratch, {path, number, c});
      }
      scan.index->add(h, pos);
      pos += prefix.frame_bytes;
      if (progress) progress(pos, size);
    } catch (const Error& e) {
      scan.stopped_because = e.what();
      break;
    }
  }
  scan.end = pos;
  return scan;
}

void copy_range(int from, int to, uint64_t bytes, const std::string& in, const std::string& out) {
  std::vector<std::byte> buffer(std::min<uint64_t>(bytes, 8u << 20));
  for (uint64_t done = 0; done < bytes;) {
    const auto n = std::min<uint64_t>(buffer.size(), bytes - done);
    pread_all_or_throw(from, std::span(buffer).first(n), done, {in});
    write_all_or_throw(to, std::span(buffer).first(n), out);
    done += n;
  }
}

}  // namespace

RecoveryReport recover_container(const std::filesystem::path& input, const std::filesystem::path& output,
                                 const ProgressFn& progress) {
  const std::string in = input.string(), out = output.string();
  const bool in_place = std::filesystem::exists(output) && std::filesystem::equivalent(input, output);
  const int fd = open_or_throw(in, in_place ? O_RDWR : O_RDONLY);
  RecoveryReport report;
  try {
    const uint64_t size = file_size_or_throw(fd, in);
    const Scan scan = scan_frames(fd, size, in, progress);
    const std::vector<std::byte> index = serialize_index(scan.index->index(), scan.header.attributes.size());
    const std::vector<std::byte> footer = serialize_footer({scan.end, index.size()});
    if (in_place) {
      if (::ftruncate(fd, static_cast<off_t>(scan.end)) != 0) throw Error({in}, "cannot truncate for recovery");
      if (::lseek(fd, 0, SEEK_END) < 0) throw Error({in}, "cannot seek for recovery");
      write_all_or_throw(fd, index, in);
      write_all_or_throw(fd, footer, in);
      if (::fsync(fd) != 0) throw Error({in}, "could not flush the recovered file");
    } else {
      const int o = open_or_throw(out, O_WRONLY | O_CREAT | O_TRUNC);
      try {
        copy_range(fd, o, scan.end, in, out);
        write_all_or_throw(o, index, out);
        write_all_or_throw(o, footer, out);
        if (::fsync(o) != 0) throw Error({out}, "could not flush the recovered file");
      } catch (...) {
        ::close(o);
        throw;
      }
      ::close(o);
    }
    report.frames = scan.index->index().frames.size();
    report.bytes_kept = scan.end;
    report.bytes_dropped = size - scan.end;
    report.stopped_because = scan.stopped_because;
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return report;
}

}  // namespace sluice::io
