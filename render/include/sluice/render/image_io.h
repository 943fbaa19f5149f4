// sluice/render/image_io.h: writing what the renderer produced: PNG files
// (libpng), an MP4 through an `ffmpeg` child process, and image comparison
// for golden tests. Images are RGBA8, rows top first, tightly packed.
//
// Errors throw render::Error naming the file. Not thread-safe per object.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace sluice::render {

struct Image {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgba;  // width * height * 4
};

void write_png(const std::string& path, const Image& image);
Image read_png(const std::string& path);  // converted to RGBA8; at most 32768 per side, checked before allocating

// Peak signal-to-noise ratio over R, G and B in dB (infinity when equal).
// Throws if the sizes differ.
double psnr(const Image& a, const Image& b);

// True when an `ffmpeg` executable is on PATH.
bool ffmpeg_available();

// Streams raw RGBA frames into `ffmpeg` (H.264, yuv420p) writing
// `path`.partial, renamed to `path` by finish() once ffmpeg has exited 0 and
// `ffprobe` reads back every frame; otherwise nothing is left at either name.
class VideoWriter {
 public:
  VideoWriter(const std::string& path, uint32_t width, uint32_t height, double fps);
  ~VideoWriter();  // closes (finish() reports errors; the destructor does not)
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  void add(const Image& frame);
  void finish();  // waits for ffmpeg; throws if it failed or its file does not read back

 private:
  std::string partial_path() const;

  std::string path_;
  uint32_t width_, height_;
  FILE* pipe_ = nullptr;
  uint64_t frames_ = 0;
  bool finished_ = false;
};

}  // namespace sluice::render
