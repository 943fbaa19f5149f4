// Fuzzes sluice's own text parsers: CSV, XYZ and the .pvd collection reader.
// The first byte picks the format; the rest is the file. Any io::Error is a
// correct answer; a crash or sanitizer report is a bug.
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <string>

#include "sluice/error.h"
#include "sluice/import/source.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* kExtensions[] = {".csv", ".xyz", ".pvd"};
  const std::string path = "/tmp/sluice-fuzz-" + std::to_string(::getpid()) + kExtensions[data[0] % 3];
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data + 1),
                                                                 std::streamsize(size - 1));
  try {
    sluice::import::SourceOptions options;
    options.attributes = {"rho"};
    const auto source = sluice::import::open_source(path, options);
    for (uint64_t f = 0; f < source->frame_count() && f < 4; ++f) (void)source->read(f);
  } catch (const sluice::io::Error&) {
  }
  try {
    const auto source = sluice::import::open_source(path, {});
    if (source->frame_count() > 0) (void)source->read(0);
  } catch (const sluice::io::Error&) {
  }
  return 0;
}
