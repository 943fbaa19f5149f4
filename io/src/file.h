// Thin POSIX file helpers that turn failures into io::Error.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "sluice/error.h"

namespace sluice::io {

int open_or_throw(const std::string& path, int flags, int mode = 0644);
void write_all_or_throw(int fd, std::span<const std::byte> bytes, const std::string& path);
// Reads exactly bytes.size() bytes at offset; a short read is an error.
void pread_all_or_throw(int fd, std::span<std::byte> bytes, uint64_t offset, const ErrorLocation& where);
uint64_t file_size_or_throw(int fd, const std::string& path);

}  // namespace sluice::io
