// sluice/io/writer.h: writes a `.sluice` file frame by frame.
//
// Memory: the writer holds one index entry per frame (96 bytes) and nothing
// else; frames are written as they are appended. A writer destroyed without
// finish() leaves a file without its index (as a crash would); `sluice
// recover` rebuilds it from the per-frame headers.
//
// Threads: one thread at a time. Encode frames in parallel with
// encode_frame(), then append them here in order.
#pragma once

#include <filesystem>

#include "sluice/io/codec.h"
#include "sluice/io/format.h"

namespace sluice::io {

class ContainerWriter {
 public:
  // Creates (or truncates) `path` and writes the file header. Throws io::Error.
  ContainerWriter(const std::filesystem::path& path, FileHeader header);
  ~ContainerWriter();
  ContainerWriter(const ContainerWriter&) = delete;
  ContainerWriter& operator=(const ContainerWriter&) = delete;

  // Appends a frame; frames are numbered in the order they are appended.
  void append(EncodedFrame frame);
  // Rewrites the file header in place with what was learnt from the frames
  // (the up axis, ...). Only fields of fixed size may change: the header's
  // size, attributes and position coding must stay. Throws io::Error.
  void update_header(const FileHeader& header);
  // Writes the frame index and the footer, flushes and closes the file.
  void finish();

  const FileHeader& header() const { return header_; }
  uint64_t frames_written() const { return index_.index().frames.size(); }
  uint64_t bytes_written() const { return offset_; }
  // A write failed (disk full, I/O error): every later append, header update
  // and finish throws, so the file never gains an index after a torn
  // record. Its complete frames can still be rebuilt by `sluice recover`.
  bool failed() const { return failed_; }

 private:
  void write_all(std::span<const std::byte> bytes);

  std::string path_;

  bool failed_ = false;
  FileHeader header_;
  IndexBuilder index_;
  int fd_ = -1;
  uint64_t offset_ = 0;
};

}  // namespace sluice::io
