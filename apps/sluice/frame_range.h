// --frames A:B (or a list: 0,25,50) for the commands that take frames of a file.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace sluice::app {

// Parses `spec` against a file of `count` frames: "A:B" (inclusive), "A",
// "A:" (to the last) or ":B" (from the first); empty means every frame.
// Returns {first, last}, inclusive. Throws std::runtime_error with a message
// for the user (naming the option and the file's range) when the spec is
// malformed, empty (A > B) or beyond the file, or the file has no frames.
std::pair<uint64_t, uint64_t> parse_frame_range(const std::string& spec, uint64_t count);

// A comma-separated list of such ranges ("0,25,50", "0:9,40:"): the frames,
// ascending, each once. The same errors, naming the piece at fault.
std::vector<uint64_t> parse_frame_list(const std::string& spec, uint64_t count);

}  // namespace sluice::app
