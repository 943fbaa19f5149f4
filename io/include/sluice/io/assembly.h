// sluice/io/assembly.h: a `.sluice` file laid out by several writers at once
// (an MPI conversion: each process writes its own frames' records where an
// exclusive scan of the record sizes puts them). These are the bytes of each
// part, exactly those ContainerWriter writes, so a file assembled from them
// is byte for byte the one ContainerWriter would have written.
//
// Layout: head at offset 0; records one after another from head's size, in
// frame order, each numbered with set_frame_number (codec.h); tail right
// after the last record. Threads: plain functions, thread-safe.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/error.h"
#include "sluice/io/format.h"

namespace sluice::io {

// The file header and its copy: the file's first bytes.
std::vector<std::byte> container_head(const FileHeader& header);
// The header back from container_head's bytes (or a file's first bytes).
// Throws io::Error naming `where` when they do not hold one.
FileHeader parse_container_head(std::span<const std::byte> head, const ErrorLocation& where = {});

// The frame index and footer, written at `at`: the end of the last record.
std::vector<std::byte> container_tail(const FrameIndex& index, size_t attribute_count, uint64_t at);

}  // namespace sluice::io
