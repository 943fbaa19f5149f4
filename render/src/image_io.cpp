// PNG files, an ffmpeg pipe, and PSNR (see image_io.h).
#include "sluice/render/image_io.h"
#include "sluice/error.h"

#include <png.h>
#include <sys/wait.h>

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>

namespace sluice::render {
namespace {

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

namespace {

// The PNG's bytes into an open file; throws on any failed write.
void write_png_to(FILE* file, const std::string& path, const Image& image) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw Error(path + ": libpng failed to start");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw Error(path + ": writing the PNG failed (disk full?)");
  }
  png_init_io(png, file);
  // Level 6 is within a few percent of 9 on renders and much faster.
  png_set_compression_level(png, 6);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (uint32_t y = 0; y < image.height; ++y) {
    png_write_row(png, image.rgba.data() + size_t(y) * image.width * 4);
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
}

}  // namespace

void write_png(const std::string& path, const Image& image) {
  if (image.rgba.size() != size_t(image.width) * image.height * 4) throw Error(path + ": image has the wrong size");
  // Written beside it and renamed when whole: a failed write (disk full)
  // never leaves an empty or cut image under the real name.
  const std::string partial = path + ".partial";
  FILE* f = std::fopen(partial.c_str(), "wb");
  if (!f) throw Error(path + ": cannot create the file (" + std::strerror(errno) + ")");
  try {
    write_png_to(f, path, image);
  } catch (...) {
    std::fclose(f);
    std::remove(partial.c_str());
    throw;
  }
  bool written = std::fflush(f) == 0 && ::fsync(::fileno(f)) == 0;
  int error = written ? 0 : errno;
  if (std::fclose(f) != 0 && written) {
    written = false;
    error = errno;
  }
  if (!written) {
    std::remove(partial.c_str());
    throw Error(path + ": writing the PNG failed (" + std::strerror(error) + ")");
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(partial.c_str());
    throw Error(path + ": cannot move the finished PNG into place (" + reason + ")");
  }
}

Image read_png(const std::string& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str())) {
    throw Error(path + ": not a readable PNG (" + img.message + ")");
  }
  // The header's size is checked before any allocation: a few bytes may claim gigapixels.
  constexpr uint32_t kMaxSide = 32768;
  if (img.width > kMaxSide || img.height > kMaxSide) {
    const std::string claim = std::to_string(img.width) + "x" + std::to_string(img.height);
    png_image_free(&img);
    throw Error(path + ": the PNG claims " + claim + " pixels, more than sluice reads (" +
                             std::to_string(kMaxSide) + " per side)");
  }
  img.format = PNG_FORMAT_RGBA;
  Image out;
  out.width = img.width;
  out.height = img.height;
  out.rgba.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.rgba.data(), 0, nullptr)) {
    png_image_free(&img);
    throw Error(path + ": PNG decode failed (" + img.message + ")");
  }
  return out;
}

double psnr(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("psnr: images differ in size");
  double sum = 0;
  const size_t n = size_t(a.width) * a.height;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      const double d = double(a.rgba[4 * i + size_t(c)]) - double(b.rgba[4 * i + size_t(c)]);
      sum += d * d;
    }
  }
  if (sum == 0) return std::numeric_limits<double>::infinity();
  const double mse = sum / double(3 * n);
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

bool ffmpeg_available() { return std::system("command -v ffmpeg > /dev/null 2>&1") == 0; }

VideoWriter::VideoWriter(const std::string& path, uint32_t width, uint32_t height, double fps)
    : path_(path), width_(width), height_(height) {
  if (!ffmpeg_available()) throw Error("writing " + path + " needs ffmpeg on PATH (apt-get install ffmpeg)");
  // yuv420p needs even sizes: pad by a pixel rather than fail.
  const std::string cmd = "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgba -s " + std::to_string(width) + "x" +
                          std::to_string(height) + " -r " + std::to_string(fps) +
                          " -i - -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -preset medium -crf 18 -pix_fmt yuv420p "
                          "-movflags +faststart -f mp4 " + shell_quote(partial_path());
  // A dying ffmpeg must surface as a write error, not kill us with SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  pipe_ = popen(cmd.c_str(), "w");
  if (!pipe_) throw Error(path + ": cannot start ffmpeg");
}

std::string VideoWriter::partial_path() const { return path_ + ".partial"; }

VideoWriter::~VideoWriter() {
  if (pipe_) pclose(pipe_);
  if (!finished_) std::remove(partial_path().c_str());  // never left looking like a video
}

void VideoWriter::add(const Image& frame) {
  if (frame.width != width_ || frame.height != height_) throw Error(path_ + ": frame size changed");
  if (std::fwrite(frame.rgba.data(), 1, frame.rgba.size(), pipe_) != frame.rgba.size()) {
    throw Error(path_ + ": ffmpeg stopped taking frames (its message is above)");
  }
  ++frames_;
}

void VideoWriter::finish() {
  if (!pipe_) return;
  const int status = pclose(pipe_);
  pipe_ = nullptr;
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw Error(path_ + ": ffmpeg failed (its message is above)");
  }
  // ffmpeg has exited 0 on a full disk with a file nothing can open: the
  // result counts only when ffprobe reads back every frame.
  const std::string probe = "ffprobe -v error -select_streams v:0 -count_packets -show_entries stream=nb_read_packets "
                            "-of csv=p=0 " + shell_quote(partial_path()) + " 2>&1";
  FILE* p = popen(probe.c_str(), "r");
  std::string said;
  if (p) {
    char line[256];
    while (std::fgets(line, sizeof line, p)) said += line;
  }
  const int probed = p ? pclose(p) : -1;
  const long frames = std::strtol(said.c_str(), nullptr, 10);
  if (probed != 0 || frames != long(frames_)) {
    while (!said.empty() && (said.back() == '\n' || said.back() == ' ')) said.pop_back();
    throw Error(path_ + ": the video ffmpeg wrote is not readable back (ffprobe: " +
                             (said.empty() ? "no answer" : said) + "; " + std::to_string(frames_) + " frames sent)");
  }
  if (std::rename(partial_path().c_str(), path_.c_str()) != 0) {
    throw Error(path_ + ": cannot move the finished video into place (" + std::strerror(errno) + ")");
  }
  finished_ = true;
}

}  // namespace sluice::render
