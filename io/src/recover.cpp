// `sluice recover`: every frame whose checksums hold, wherever it lies.
// Damage costs only what it touches: a damaged header is rebuilt from its
// copy (format 1.5), a damaged frame is skipped and the scan goes on at the
// next frame record found after it.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <optional>
#include <string>

#include "file.h"
#include "records.h"
#include "sluice/io/codec.h"
#include "sluice/io/maintenance.h"

namespace sluice::io {
namespace {

constexpr uint64_t kBlock = 4u << 20;

struct KeptFrame {
  uint64_t offset, bytes;
  uint32_t number;  // as stored; renumbered when frames before it were dropped
};

struct Scan {
  FileHeader header;
  bool header_rebuilt = false;
  uint64_t header_region = 0;  // bytes before the first frame that belong to the header (and its copy)
  std::vector<KeptFrame> kept;
  std::vector<std::string> dropped;
  uint64_t end = 0;  // just past the last kept frame
  std::string stopped_because;
};

// Every offset in [from, size) where `magic` starts, block by block,
// calling found(offset) until it returns true. Returns that offset.
std::optional<uint64_t> find_magic(int fd, uint64_t size, uint64_t from, uint64_t until, uint32_t magic,
                                   const std::function<bool(uint64_t)>& found, const std::string& path) {
  std::vector<std::byte> block;
  char word[4];
  std::memcpy(word, &magic, 4);
  until = std::min(until, size);
  for (uint64_t at = from; at + 4 <= until;) {
    const uint64_t n = std::min<uint64_t>(kBlock, until - at);
    block.resize(n);
    pread_all_or_throw(fd, block, at, {path});
    const char* begin = reinterpret_cast<const char*>(block.data());
    for (const char* p = begin; (p = static_cast<const char*>(memmem(p, size_t(begin + n - p), word, 4))); ++p) {
      if (found(at + uint64_t(p - begin))) return at + uint64_t(p - begin);
    }
    if (at + n >= until) break;
    at += n - 3;  // a magic across the blocks' seam
  }
  return std::nullopt;
}

// The header: at offset 0, or (when that is damaged) its copy.
void read_header(int fd, uint64_t size, const std::string& path, Scan& scan) {
  const ErrorLocation where{path};
  const auto parse_at = [&](uint64_t offset) -> std::optional<FileHeader> {
    try {
      std::vector<std::byte> fixed(kFileHeaderFixedBytes);
      if (size < offset + fixed.size()) return std::nullopt;
      pread_all_or_throw(fd, fixed, offset, where);
      const uint32_t bytes = peek_file_header_bytes(fixed, where);
      if (bytes > size - offset) return std::nullopt;
      std::vector<std::byte> head(bytes);
      pread_all_or_throw(fd, head, offset, where);
      return parse_file_header(head, where);
    } catch (const Error&) {
      return std::nullopt;
    }
  };
  if (size < kFileHeaderFixedBytes) throw Error(where, "too small to be a .sluice file: nothing to recover");
  if (auto h = parse_at(0)) {
    scan.header = *h;
    scan.header_region = serialize_file_header(*h).size();
    return;
  }
  std::optional<FileHeader> copy;
  find_magic(fd, size, 0, kMaxHeaderBytes + 8, kHeaderCopyMagic, [&](uint64_t at) {
    copy = parse_at(at + 4);
    if (copy) scan.header_region = at + 4 + serialize_file_header(*copy).size();
    return copy.has_value();
  }, path);
  if (!copy) {
    throw Error(where, "the file header is damaged and no intact copy of it was found (files written before format 1.5 "
                       "have none): nothing can be recovered");
  }
  scan.header = *copy;
  scan.header_rebuilt = true;
}

// Checks the whole frame record at `pos` (table and every chunk); returns
// its size and number. Throws io::Error on any damage.
FramePrefix check_frame(int fd, uint64_t size, uint64_t pos, uint32_t at_least, const Scan& scan, const std::string& path,
                        std::vector<std::byte>& record, DecodeScratch& scratch) {
  const ErrorLocation at{path, at_least, {}};
  std::vector<std::byte> fixed(kFrameHeaderFixedBytes);
  if (size - pos < fixed.size()) throw Error(at, "frame is cut short");
  pread_all_or_throw(fd, fixed, pos, at);
  const FramePrefix prefix = parse_frame_prefix(fixed, at);
  if (prefix.frame_number < at_least) throw Error(at, "frame number " + std::to_string(prefix.frame_number) + " out of sequence");
  if (prefix.frame_bytes > size - pos) throw Error(at, "frame is cut short");
  record.resize(prefix.frame_bytes);
  pread_all_or_throw(fd, record, pos, at);
  const ErrorLocation here{path, prefix.frame_number, {}};
  const FrameHeader h = parse_frame_table(record, scan.header.attributes.size(), here);
  for (size_t c = 0; c < h.chunks.size(); ++c) {
    std::vector<std::byte> particles(h.chunks[c].particle_count * decoded_particle_bytes(scan.header.position_coding));
    decode_chunk(record, h.chunks[c], scan.header, {particles, {}}, scratch, {path, prefix.frame_number, c});
  }
  return prefix;
}

// The next offset after `from` where a frame record numbered at least
// `at_least` starts whose table checks out (its payloads are checked next).
std::optional<uint64_t> next_frame(int fd, uint64_t size, uint64_t from, uint32_t at_least, const Scan& scan,
                                   const std::string& path) {
  std::vector<std::byte> fixed(kFrameHeaderFixedBytes), table;
  return find_magic(fd, size, from, size, kFrameMagic, [&](uint64_t at) {
    try {
      if (size - at < fixed.size()) return false;
      pread_all_or_throw(fd, fixed, at, {path});
      const FramePrefix prefix = parse_frame_prefix(fixed, {path});
      if (prefix.frame_number < at_least || prefix.frame_bytes > size - at) return false;
      table.resize(std::min<uint64_t>(prefix.frame_bytes, frame_table_bytes(prefix.chunk_count, scan.header.attributes.size())));
      pread_all_or_throw(fd, table, at, {path});
      (void)parse_frame_table(table, scan.header.attributes.size(), {path});
      return true;
    } catch (const Error&) {
      return false;
    }
  }, path);
}

Scan scan_file(int fd, uint64_t size, const std::string& path, const ProgressFn& progress) {
  Scan scan;
  read_header(fd, size, path, scan);
  DecodeScratch scratch;
  std::vector<std::byte> record;
  uint32_t expected = 0;  // the next stored frame number
  std::optional<uint64_t> pos = next_frame(fd, size, scan.header_region, 0, scan, path);
  if (!pos) scan.stopped_because = "no frame record found after the header";
  while (pos) {
    try {
      const FramePrefix f = check_frame(fd, size, *pos, expected, scan, path, record, scratch);
      if (f.frame_number > expected) {
        scan.dropped.push_back("frames " + std::to_string(expected) + " to " + std::to_string(f.frame_number - 1) +
                               " (stored numbers) are missing");
      }
      scan.kept.push_back({*pos, f.frame_bytes, f.frame_number});
      expected = f.frame_number + 1;
      *pos += f.frame_bytes;
      scan.end = *pos;
      if (progress) progress(*pos, size);
      if (*pos == size) {
        scan.stopped_because = "end of file";
        break;
      }
    } catch (const Error& e) {
      const std::optional<uint64_t> next = next_frame(fd, size, *pos + 1, expected + 1, scan, path);
      if (!next) {
        scan.stopped_because = e.what();
        break;
      }
      scan.dropped.push_back(std::string(e.what()) + " (bytes " + std::to_string(*pos) + " to " + std::to_string(*next) +
                             " dropped)");
      pos = next;
      ++expected;
    }
  }
  return scan;
}

// The kept frames as they are (nothing dropped before the last, header
// intact): a reader of the input's prefix sees exactly the recovered file.
bool kept_as_prefix(const Scan& scan) {
  if (scan.header_rebuilt || !scan.dropped.empty()) return false;
  for (size_t i = 0; i < scan.kept.size(); ++i) {
    if (scan.kept[i].number != i) return false;
  }
  return true;
}

// Header (and its copy), each kept frame renumbered to its new place, index
// and footer into `out`.
void write_recovered(int in_fd, int out_fd, const Scan& scan, const std::string& in, const std::string& out,
                     IndexBuilder& index) {
  const std::vector<std::byte> header = serialize_file_header(scan.header);
  write_all_or_throw(out_fd, header, out);
  const std::vector<std::byte> copy = serialize_header_copy(header);
  write_all_or_throw(out_fd, copy, out);
  uint64_t offset = header.size() + copy.size();
  const size_t attributes = scan.header.attributes.size();
  EncodedFrame frame;
  for (size_t i = 0; i < scan.kept.size(); ++i) {
    const KeptFrame& k = scan.kept[i];
    frame.record.resize(k.bytes);
    pread_all_or_throw(in_fd, frame.record, k.offset, {in});
    frame.header = parse_frame_table(frame.record, attributes, {in});
    if (k.number != i) {
      set_frame_number(frame, uint32_t(i), attributes);
      frame.header.frame_number = uint32_t(i);
    }
    write_all_or_throw(out_fd, frame.record, out);
    index.add(frame.header, offset);
    offset += k.bytes;
  }
  const std::vector<std::byte> bytes = serialize_index(index.index(), attributes);
  write_all_or_throw(out_fd, bytes, out);
  write_all_or_throw(out_fd, serialize_footer({offset, bytes.size()}), out);
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
    const Scan scan = scan_file(fd, size, in, progress);
    IndexBuilder index(scan.header.attributes.size());
    if (in_place && kept_as_prefix(scan)) {
      // The cheap way: cut the tail, append the index.
      for (const KeptFrame& k : scan.kept) {
        std::vector<std::byte> table(std::min<uint64_t>(k.bytes, 1u << 20));
        pread_all_or_throw(fd, table, k.offset, {in});
        const FramePrefix prefix = parse_frame_prefix(table, {in});
        table.resize(frame_table_bytes(prefix.chunk_count, scan.header.attributes.size()));
        pread_all_or_throw(fd, table, k.offset, {in});
        index.add(parse_frame_table(table, scan.header.attributes.size(), {in}), k.offset);
      }
      const uint64_t end = scan.kept.empty() ? scan.header_region : scan.end;
      const std::vector<std::byte> bytes = serialize_index(index.index(), scan.header.attributes.size());
      if (::ftruncate(fd, static_cast<off_t>(end)) != 0) throw Error({in}, "cannot truncate for recovery");
      if (::lseek(fd, 0, SEEK_END) < 0) throw Error({in}, "cannot seek for recovery");
      write_all_or_throw(fd, bytes, in);
      write_all_or_throw(fd, serialize_footer({end, bytes.size()}), in);
      if (::fsync(fd) != 0) throw Error({in}, "could not flush the recovered file");
    } else {
      // Into a file beside the output, renamed when whole (in place too).
      const std::string partial = out + ".recovering";
      const int o = open_or_throw(partial, O_WRONLY | O_CREAT | O_TRUNC);
      try {
        write_recovered(fd, o, scan, in, partial, index);
        if (::fsync(o) != 0) throw Error({partial}, "could not flush the recovered file");
      } catch (...) {
        ::close(o);
        ::unlink(partial.c_str());
        throw;
      }
      ::close(o);
      if (::rename(partial.c_str(), out.c_str()) != 0) {
        ::unlink(partial.c_str());
        throw Error({out}, "cannot move the recovered file into place");
      }
    }
    report.frames = scan.kept.size();
    for (const KeptFrame& k : scan.kept) report.bytes_kept += k.bytes;
    report.bytes_dropped = size - report.bytes_kept - std::min(size, scan.header_region);
    report.stopped_because = scan.stopped_because;
    report.dropped = scan.dropped;
    report.header_rebuilt = scan.header_rebuilt;
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return report;
}

}  // namespace sluice::io
