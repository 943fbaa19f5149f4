// Fuzzes everything that reads a .sluice file: open (header, footer, index),
// every frame table and chunk (verify decodes all of them) and the recovery
// scan. Any io::Error is a correct answer; a crash, a sanitizer report, a
// hang or a huge allocation is a bug.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include "sluice/error.h"
#include "sluice/io/maintenance.h"

namespace {

// An anonymous in-memory file reachable by path, rewritten for every input.
struct MemFile {
  int fd = ::memfd_create("sluice-fuzz", 0);
  std::string path = "/proc/self/fd/" + std::to_string(fd);
  void set(const uint8_t* data, size_t size) {
    if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != ssize_t(size)) __builtin_trap();
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static MemFile input, output;
  input.set(data, size);
  try {
    (void)sluice::io::verify_container(input.path);
  } catch (const sluice::io::Error&) {
  }
  try {
    (void)sluice::io::recover_container(input.path, output.path);
  } catch (const sluice::io::Error&) {
  }
  return 0;
}
