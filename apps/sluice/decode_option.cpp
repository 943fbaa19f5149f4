#include "decode_option.h"

namespace sluice::app {

void add_decode_option(CLI::App& cmd, std::string& value) {
  cmd.add_option("--decode", value,
                 "Where frames are decoded: gpu (the file's bytes go to the GPU as they lie on disk and a compute\n"
                 "pass decodes them; the CPU only checks checksums and inflates zstd planes; files with no zstd\n"
                 "planes, written --gpu-decodable, are relayed into a window in device memory as they are read),\n"
                 "cpu (the CPU's decoders write particles into staging), or auto (gpu for files with 16-bit positions)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cpu", "gpu"}));
}

stream::DecodeSite decode_site(const std::string& value) {
  if (value == "cpu") return stream::DecodeSite::Cpu;
  if (value == "gpu") return stream::DecodeSite::Gpu;
  return stream::DecodeSite::Auto;
}

}  // namespace sluice::app
