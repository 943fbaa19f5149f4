// Writes fuzz_chunk seeds: real chunk payloads (each codec, with and without
// attributes) behind their 4-byte setup, one file per chunk.
//   make_chunk_seeds DIR
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "fuzz_chunk.h"
#include "sluice/io/codec.h"

using namespace sluice;

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  std::mt19937 rng(5);
  int written = 0;
  for (size_t attributes : {size_t(0), size_t(2)}) {
    for (int layout = 0; layout < 3; ++layout) {  // random cloud (packed planes), lattice (zstd), noise (stored)
      const uint32_t n = 500 + 700 * uint32_t(layout);
      std::vector<float> positions(3 * n);
      std::uniform_real_distribution<float> u(0.f, 1.f);
      for (uint32_t i = 0; i < n; ++i) {
        for (int a = 0; a < 3; ++a) {
          positions[3 * i + a] = layout == 1 ? float((i >> (3 * a)) % 8) * 0.1f + 1e-4f * u(rng) : u(rng);
        }
      }
      std::vector<uint16_t> lod(n);
      for (auto& l : lod) l = uint16_t(rng());
      std::vector<std::vector<float>> values(attributes, std::vector<float>(n));
      for (auto& v : values) for (auto& x : v) x = layout == 2 ? u(rng) : 0.5f;
      io::FileHeader header;
      header.position_coding = io::PositionCoding::Quantized16;
      io::FrameInput in;
      in.positions = positions;
      in.lod = lod;
      for (size_t a = 0; a < attributes; ++a) {
        header.attributes.push_back({"a" + std::to_string(a)});
        in.attributes.push_back(values[a]);
      }
      io::EncodeOptions options;
      options.chunk_particles = 4096;
      const io::EncodedFrame frame = io::encode_frame(in, header, options);
      // Split (format 3.0, the writers' default): the record, then its
      // fine part; read whole and read coarse.
      for (const io::ChunkDesc& c : frame.header.chunks) {
        const uint32_t count = c.particle_count - 1;
        for (const bool coarse : {false, true}) {
          const uint8_t flags = uint8_t(c.codec) | uint8_t(uint8_t(c.fine.codec) << 2) | fuzz::kSplitSetup |
                                (coarse ? fuzz::kCoarseSetup : 0);
          const uint8_t setup[fuzz::kChunkSetupBytes + 2] = {uint8_t(attributes), flags, uint8_t(count), uint8_t(count >> 8),
                                                             uint8_t(c.fine.size), uint8_t(c.fine.size >> 8)};
          std::ofstream out(std::string(argv[1]) + "/chunk_" + std::to_string(written++), std::ios::binary);
          out.write(reinterpret_cast<const char*>(setup), sizeof setup);
          out.write(reinterpret_cast<const char*>(frame.record.data() + c.offset), c.compressed_size);
          out.write(reinterpret_cast<const char*>(frame.record.data() + c.fine.offset), c.fine.size);
        }
      }
      // Whole positions (format 2.0).
      io::FileHeader whole = header;
      io::set_format_version(whole, 2);
      const io::EncodedFrame old = io::encode_frame(in, whole, options);
      for (const io::ChunkDesc& c : old.header.chunks) {
        const uint32_t count = c.particle_count - 1;
        const uint8_t setup[fuzz::kChunkSetupBytes] = {uint8_t(attributes), uint8_t(c.codec), uint8_t(count), uint8_t(count >> 8)};
        std::ofstream out(std::string(argv[1]) + "/chunk_" + std::to_string(written++), std::ios::binary);
        out.write(reinterpret_cast<const char*>(setup), sizeof setup);
        out.write(reinterpret_cast<const char*>(old.record.data() + c.offset), c.compressed_size);
      }
    }
  }
  std::printf("%d chunk seeds in %s\n", written, argv[1]);
  return 0;
}
