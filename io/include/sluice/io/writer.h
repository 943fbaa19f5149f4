// sluice/io/writer.h: writes a `.sluice` file frame by frame; the parts of
// one that several writers lay out at once (MPI: assembly below); one
// writer per output (OutputLock).
//
// Memory: the writer holds one index entry per frame (96 bytes) and nothing
// else; frames are written as they are appended. A writer destroyed without
// finish() leaves a file without its index (as a crash would); `sluice
// recover` rebuilds it from the per-frame headers.
//
// Threads: one thread at a time. Encode frames in parallel with
// encode_frame(), then append them here in order.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "sluice/error.h"
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

// Assembly: a `.sluice` file laid out by several writers at once
// (an MPI conversion: each process writes its own frames' records where an
// exclusive scan of the record sizes puts them). These are the bytes of each
// part, exactly those ContainerWriter writes, so a file assembled from them
// is byte for byte the one ContainerWriter would have written.
//
// Layout: head at offset 0; records one after another from head's size, in
// frame order, each numbered with set_frame_number (codec.h); tail right
// after the last record. Threads: plain functions, thread-safe.

// The file header and its copy: the file's first bytes.
std::vector<std::byte> container_head(const FileHeader& header);
// The header back from container_head's bytes (or a file's first bytes).
// Throws io::Error naming `where` when they do not hold one.
FileHeader parse_container_head(std::span<const std::byte> head, const ErrorLocation& where = {});

// The frame index and footer, written at `at`: the end of the last record.
std::vector<std::byte> container_tail(const FrameIndex& index, size_t attribute_count, uint64_t at);

// OutputLock: one writer per output.
//
// Two `sluice convert`s to one file, or two players filling one cache
// entry, would otherwise write the same `.partial` and rename each other's
// half-written bytes. A writer holds an OutputLock on its output for as
// long as it writes (until the rename): an exclusive flock(2) on
// `OUTPUT.lock`, which holds the holder's process id for the error message
// and is removed on release. The lock is advisory (other programs are not
// stopped) and dies with its process, so a crash never leaves it held.

class OutputLock {
 public:
  enum class Wait { No, Yes };
  // Takes the lock on `output`. Wait::No: throws io::Error naming `output`
  // and the holder's process id when another holds it. Wait::Yes: blocks
  // until the holder releases it, calling `on_wait(pid)` once first (pid 0
  // when unknown). Throws io::Error when the lock file cannot be created.
  explicit OutputLock(const std::filesystem::path& output, Wait wait = Wait::No,
                      const std::function<void(const std::filesystem::path& output, long pid)>& on_wait = {});
  ~OutputLock();  // removes the lock file and releases the lock
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

  const std::filesystem::path& path() const { return path_; }  // OUTPUT.lock

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace sluice::io
