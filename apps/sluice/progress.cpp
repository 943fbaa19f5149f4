#include "progress.h"

#include <unistd.h>

#include <cstdio>

#include "human.h"

namespace sluice::app {

ProgressBar::ProgressBar(std::string unit, uint64_t total, bool quiet)
    : unit_(std::move(unit)), total_(total), quiet_(quiet), tty_(::isatty(STDERR_FILENO) != 0) {}

double ProgressBar::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressBar::update(uint64_t done, uint64_t bytes_in, uint64_t bytes_out) {
  const std::lock_guard lock(mutex_);
  done_ = done, in_ = bytes_in, out_ = bytes_out;
  draw(false);
}

void ProgressBar::print(const std::string& line) {
  const std::lock_guard lock(mutex_);
  if (tty_ && drawn_) std::fputs("\r\033[K", stderr);
  std::fprintf(stderr, "%s\n", line.c_str());
  if (tty_ && drawn_) draw(true);
}

void ProgressBar::finish() {
  const std::lock_guard lock(mutex_);
  draw(true);
  if (tty_ && drawn_ && !quiet_) std::fputc('\n', stderr);
}

void ProgressBar::draw(bool force) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  const double t = std::chrono::duration<double>(now - start_).count();
  const int decile = total_ ? int(10 * done_ / total_) : 10;
  if (tty_ && !force && now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
  // A log gets a line when another tenth is done, at most one a second, and
  // the last one: a short job writes one line, a long one at most eleven.
  if (!tty_ && !force && (decile == last_decile_ || now - last_draw_ < std::chrono::seconds(1))) return;
  if (!tty_ && force && done_ == last_done_ && drawn_) return;
  last_draw_ = now;
  last_decile_ = decile;
  last_done_ = done_;
  const double fraction = total_ ? double(done_) / double(total_) : 1.0;
  std::string bar;
  const int width = 28;
  for (int i = 0; i < width; ++i) bar += i < int(fraction * width) ? "#" : (i == int(fraction * width) ? ">" : ".");
  std::string line = "[" + bar + "] " + std::to_string(done_) + "/" + std::to_string(total_) + " " + unit_;
  if (t > 0) {
    line += "  " + fixed(double(done_) / t, 1) + " " + unit_ + "/s";
    if (in_) line += "  in " + human_bytes(double(in_) / t) + "/s";
    if (out_) line += "  out " + human_bytes(double(out_) / t) + "/s";
  }
  if (done_ > 0 && done_ < total_) line += "  ETA " + human_duration(t / double(done_) * double(total_ - done_));
  else line += "  " + human_duration(t);
  if (tty_) std::fprintf(stderr, "\r\033[K%s", line.c_str());
  else std::fprintf(stderr, "%s\n", line.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace sluice::app
