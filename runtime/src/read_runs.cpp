#include "read_runs.h"

#include <algorithm>

namespace sluice::runtime::detail {
namespace {

uint64_t round_up(uint64_t n, uint64_t to) { return (n + to - 1) / to * to; }

// Splits [from, to) into pieces of about equal length, at most `piece` each
// (aligned), so that a large run is read by several threads at once.
void add_pieces(uint64_t from, uint64_t to, uint64_t need, uint64_t align, uint64_t piece, std::vector<ByteRun>& out) {
  const uint64_t most = std::max(align, round_up(std::max<uint64_t>(piece, 1), align));
  const uint64_t count = (to - from + most - 1) / most;
  const uint64_t each = round_up((to - from + count - 1) / count, align);
  for (uint64_t at = from; at < to; at += each) {
    const uint64_t length = std::min(each, to - at);
    out.push_back({at, length, at < need ? std::min(length, need - at) : 0});
  }
}

}  // namespace

size_t plan_runs(std::span<const io::RecordPart> records, uint64_t record_at, uint64_t size, uint64_t need,
                 uint64_t skip, const RunLimits& limits, std::vector<ByteRun>& out) {
  out.clear();
  const uint64_t align = std::max<uint64_t>(limits.align, 1);
  size_t runs = 0;
  uint64_t from = 0, to = 0;  // the open run, buffer offsets (unaligned)
  auto close = [&] {
    const uint64_t begin = std::max(from / align * align, skip);
    const uint64_t end = std::min(round_up(to, align), size);
    if (to <= from || end <= begin) return;
    add_pieces(begin, end, need, align, limits.piece, out);
    ++runs;
  };
  for (const io::RecordPart& c : records) {
    const uint64_t begin = record_at + c.offset, end = begin + c.size;
    if (to > from && joins_run(from, to, begin, limits.gap)) {
      to = std::max(to, end);
      continue;
    }
    close();
    from = begin;
    to = end;
  }
  close();
  return runs;
}

}  // namespace sluice::runtime::detail
