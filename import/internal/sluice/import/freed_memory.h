// sluice/import/freed_memory.h: keeping freed memory in the process while
// simulation output is imported.
//
// Importing a VTK file allocates and frees tens of bytes per particle per
// frame (VTK's arrays, the importer's frame). glibc returns large freed
// blocks to the operating system at once, so every frame faults the same
// memory back in, page by page: on the machines measured that costs more
// than reading the file (docs/import.md, "Speed"). While a KeepFreedMemory
// lives, freed blocks up to `bytes` stay in the heap for the next frame.
//
// Process-wide (glibc's malloc settings): create one around a conversion,
// not in a library's hot path. The destructor restores glibc's defaults and
// returns what was kept. No effect with another C library.
#pragma once

#include <cstddef>

namespace sluice::import {

class KeepFreedMemory {
 public:
  explicit KeepFreedMemory(size_t bytes = size_t(512) << 20);
  ~KeepFreedMemory();
  KeepFreedMemory(const KeepFreedMemory&) = delete;
  KeepFreedMemory& operator=(const KeepFreedMemory&) = delete;
};

}  // namespace sluice::import
