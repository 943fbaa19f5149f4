// Fuzzes the VTK import path as `sluice convert` runs it: sluice's legacy
// reader, the size checks in front of VTK's XML readers, and those readers.
// The first byte picks the extension; the rest is the file. Any io::Error is
// a correct answer; a crash, a sanitizer report, a hang or an allocation
// beyond the limit is a bug.
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "sluice/io/error.h"
#include "sluice/io/import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* kExtensions[] = {".vtk", ".vtu", ".vtp", ".pvd"};
  const std::string path = "/tmp/sluice-fuzz-vtk-" + std::to_string(::getpid()) + kExtensions[data[0] % 4];
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data + 1),
                                                                 std::streamsize(size - 1));
  try {
    sluice::io::ImportOptions options;
    options.attributes = {"rho", "velocity"};
    const auto source = sluice::io::open_source(path, options);
    if (source->frame_count() > 0) (void)source->read(0);
  } catch (const sluice::io::Error&) {
  }
  try {
    const auto source = sluice::io::open_source(path, {});  // ids detected, no attributes
    if (source->frame_count() > 0) (void)source->read(0);
  } catch (const sluice::io::Error&) {
  }
  ::unlink(path.c_str());
  return 0;
}
