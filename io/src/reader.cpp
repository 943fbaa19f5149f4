#include "sluice/io/reader.h"

#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <array>
#include <cstring>

#include "file.h"
#include "records.h"

namespace sluice::io {

ContainerReader::ContainerReader(const std::filesystem::path& path) : path_(path.string()) {
  fd_ = open_or_throw(path_, O_RDONLY);
  try {
    file_size_ = file_size_or_throw(fd_, path_);
    const ErrorLocation where{path_};
    if (file_size_ < kFileHeaderFixedBytes) throw Error(where, "too small to be a .sluice file");
    std::vector<std::byte> fixed(kFileHeaderFixedBytes);
    pread_all_or_throw(fd_, fixed, 0, where);
    const uint32_t header_bytes = peek_file_header_bytes(fixed, where);
    if (header_bytes > file_size_) throw Error(where, "file is shorter than its header");
    std::vector<std::byte> head(header_bytes);
    pread_all_or_throw(fd_, head, 0, where);
    header_ = parse_file_header(head, where);

    Footer footer{};
    std::vector<std::byte> tail(kFooterBytes);
    const bool has_footer = file_size_ >= header_bytes + kFooterBytes &&
                            (pread_all_or_throw(fd_, tail, file_size_ - kFooterBytes, where), parse_footer(tail, footer));
    if (!has_footer) {
      throw Error(where, "has no frame index: the file was not finished (was the writer interrupted?). "
                         "Run `sluice recover " + path_ + "` to rebuild it from the frame headers");
    }
    const uint64_t index_end = file_size_ - kFooterBytes;
    if (footer.index_offset < header_bytes || footer.index_offset > index_end ||
        footer.index_bytes != index_end - footer.index_offset) {
      throw Error(where, "footer points outside the file: run `sluice recover` to rebuild the index");
    }
    std::vector<std::byte> index(footer.index_bytes);
    pread_all_or_throw(fd_, index, footer.index_offset, where);
    index_ = parse_index(index, header_.attributes.size(), footer.index_offset, where);
    if (!index_.frames.empty() && index_.frames.front().offset < header_bytes) {
      throw Error(where, "frame index points into the header");
    }
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

ContainerReader::~ContainerReader() {
  if (fd_ >= 0) ::close(fd_);
}

void ContainerReader::read_record(uint64_t frame, std::span<std::byte> out) const {
  if (frame >= frame_count()) throw Error(location(frame), "no such frame (the file has " + std::to_string(frame_count()) + ")");
  const FrameIndexEntry& e = index_.frames[frame];
  if (out.size() != e.bytes) throw Error(location(frame), "read buffer has the wrong size");
  pread_all_or_throw(fd_, out, e.offset, location(frame));
}

std::vector<std::byte> ContainerReader::read_record(uint64_t frame) const {
  if (frame >= frame_count()) throw Error(location(frame), "no such frame (the file has " + std::to_string(frame_count()) + ")");
  std::vector<std::byte> out(index_.frames[frame].bytes);
  read_record(frame, out);
  return out;
}

FrameHeader ContainerReader::read_table(uint64_t frame) const {
  if (frame >= frame_count()) throw Error(location(frame), "no such frame (the file has " + std::to_string(frame_count()) + ")");
  const FrameIndexEntry& e = index_.frames[frame];
  std::vector<std::byte> table(std::min<uint64_t>(e.bytes, frame_table_bytes(e.chunk_count, header_.attributes.size())));
  pread_all_or_throw(fd_, table, e.offset, location(frame));
  FrameHeader h;
  parse_table(frame, table, h, location(frame));
  return h;
}

FrameHeader ContainerReader::parse_record(uint64_t frame, std::span<const std::byte> record) const {
  FrameHeader h;
  parse_record(frame, record, h, location(frame));
  return h;
}

void ContainerReader::parse_record(uint64_t frame, std::span<const std::byte> record, FrameHeader& h,
                                   const ErrorLocation& where) const {
  parse_table(frame, record, h, where);
  if (record.size() != h.frame_bytes) throw Error(where, "frame record is truncated");
}

void ContainerReader::parse_table(uint64_t frame, std::span<const std::byte> prefix, FrameHeader& h,
                                  const ErrorLocation& where) const {
  parse_frame_table(prefix, header_.attributes.size(), where, h);
  const FrameIndexEntry& e = index_.frames.at(frame);
  if (h.frame_number != frame || h.frame_bytes != e.bytes || h.particle_count != e.particle_count ||
      h.table_records() != e.chunk_count) {
    throw Error(where, "frame header disagrees with the frame index");
  }
  std::array<uint64_t, kLayerCount> layers{};
  for (const ChunkDesc& c : h.chunks) layers[size_t(c.layer)] += c.particle_count;
  if (layers != e.layer_particles) throw Error(where, "frame's layer sizes disagree with the frame index");
}

DecodedFrame decode_frame(const ContainerReader& reader, uint64_t frame, LayerSet layers) {
  const std::vector<std::byte> record = reader.read_record(frame);
  DecodedFrame out;
  out.header = reader.parse_record(frame, record);
  keep_layers(out.header, layers);
  const FileHeader& fh = reader.header();
  const size_t n = out.header.particle_count;
  out.particles.resize(n * decoded_particle_bytes(fh.position_coding));
  out.attributes.assign(fh.attributes.size(), std::vector<uint16_t>(n));
  out.chunk_first.resize(out.header.chunks.size());
  chunk_starts(out.header, out.chunk_first);
  std::vector<uint16_t*> attributes;
  for (auto& a : out.attributes) attributes.push_back(a.data());
  decode_record(record, out.header, fh, out.chunk_first, out.particles, attributes, reader.location(frame));
  return out;
}

std::vector<float> world_positions(const DecodedFrame& frame, PositionCoding coding) {
  const size_t n = frame.header.particle_count;
  std::vector<float> xyz(3 * n);
  for (size_t c = 0; c < frame.header.chunks.size(); ++c) {
    const ChunkDesc& chunk = frame.header.chunks[c];
    for (uint64_t i = frame.chunk_first[c]; i < frame.chunk_first[c] + chunk.particle_count; ++i) {
      if (coding == PositionCoding::Quantized16) {
        uint16_t q[4];
        std::memcpy(q, frame.particles.data() + 8 * i, 8);
        for (int a = 0; a < 3; ++a) xyz[3 * i + a] = dequantize(q[a], chunk.bounds.min[a], chunk.bounds.max[a]);
      } else {
        std::memcpy(&xyz[3 * i], frame.particles.data() + 16 * i, 12);
      }
    }
  }
  return xyz;
}

std::vector<uint16_t> lod_values_of(const DecodedFrame& frame, PositionCoding coding) {
  const size_t n = frame.header.particle_count;
  const size_t stride = decoded_particle_bytes(coding);
  const size_t offset = coding == PositionCoding::Quantized16 ? 6 : 12;
  std::vector<uint16_t> lod(n);
  for (size_t i = 0; i < n; ++i) std::memcpy(&lod[i], frame.particles.data() + stride * i + offset, 2);
  return lod;
}

bool is_container(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  std::array<uint8_t, kFileMagic.size()> magic{};
  const bool whole = ::pread(fd, magic.data(), magic.size(), 0) == ssize_t(magic.size());
  ::close(fd);
  return whole && magic == kFileMagic;
}

}  // namespace sluice::io
