// --frames A:B, shared by the commands that take a range of frames.
#include "frame_range.h"

#include <algorithm>
#include <stdexcept>

namespace sluice::app {
namespace {

// A whole decimal field; `fallback` when empty.
uint64_t frame_number(const std::string& text, uint64_t fallback) {
  if (text.empty()) return fallback;
  if (text.find_first_not_of("0123456789") != std::string::npos) throw std::invalid_argument(text);
  return std::stoull(text);  // throws std::out_of_range past 2^64
}

}  // namespace

std::pair<uint64_t, uint64_t> parse_frame_range(const std::string& spec, uint64_t count) {
  if (count == 0) throw std::runtime_error("the file has no frames");
  if (spec.empty()) return {0, count - 1};
  uint64_t a = 0, b = 0;
  try {
    const size_t colon = spec.find(':');
    if (colon == std::string::npos) {
      a = b = frame_number(spec, 0);
    } else {
      a = frame_number(spec.substr(0, colon), 0);
      b = frame_number(spec.substr(colon + 1), count - 1);
    }
  } catch (const std::exception&) {
    throw std::runtime_error("--frames: expected A:B (inclusive), A, A: or :B, got '" + spec + "'");
  }
  if (a > b || b >= count) {
    throw std::runtime_error("--frames " + spec + ": the file has frames 0.." + std::to_string(count - 1));
  }
  return {a, b};
}

std::vector<uint64_t> parse_frame_list(const std::string& spec, uint64_t count) {
  std::vector<uint64_t> frames;
  size_t from = 0;
  do {
    const size_t comma = spec.find(',', from);
    const std::string piece = spec.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
    if (piece.empty() && !spec.empty()) throw std::runtime_error("--frames: an empty item in '" + spec + "'");
    const auto [a, b] = parse_frame_range(piece, count);
    for (uint64_t f = a; f <= b; ++f) frames.push_back(f);
    from = comma == std::string::npos ? std::string::npos : comma + 1;
  } while (from != std::string::npos);
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  return frames;
}

}  // namespace sluice::app
