#include "read_ahead.h"

#include <algorithm>

#include "convert_steps.h"

namespace sluice::import {
namespace {

bool same_but_ids(const SourceOptions& a, const SourceOptions& b) {
  return a.id_array == b.id_array && a.attributes == b.attributes;
}

}  // namespace

ReadAhead::ReadAhead(const ConvertOptions& o, uint64_t first, uint64_t count) : first_(first) {
  try {
    source_ = open_source(o, options_);
  } catch (const io::Error&) {
    return;  // the conversion opens it again, where the error counts
  }
  const uint64_t end = std::min(source_->frame_count(), first + count);
  frames_.resize(end > first ? end - first : 0);
  for (size_t i = 0; i < frames_.size(); ++i) {
    reads_.emplace_back([this, i] {
      try {
        frames_[i] = source_->read(first_ + i);
      } catch (...) {
        // read again in its turn, where what it throws counts
      }
    });
  }
}

ReadAhead::~ReadAhead() { finish(); }

void ReadAhead::finish() {
  for (std::thread& t : reads_) {
    if (t.joinable()) t.join();
  }
}

ReadAhead::Taken ReadAhead::take(const SourceOptions& used) {
  finish();
  Taken out;
  if (!source_ || !same_but_ids(options_, used)) return out;
  for (size_t i = 0; i < frames_.size(); ++i) {
    if (!frames_[i]) continue;
    if (used.no_ids && !options_.no_ids) frames_[i]->ids.clear();  // as the conversion does to frame 0
    out.frames.emplace(first_ + i, std::move(*frames_[i]));
  }
  frames_.clear();
  if (used.no_ids == options_.no_ids) out.source = std::move(source_);
  source_.reset();
  return out;
}

}  // namespace sluice::import
