#include "sluice/runtime/player.h"

#include <algorithm>
#include <cmath>

#include "wrap.h"

namespace sluice::runtime {

using detail::wrap;

namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

double media_rate(const io::ContainerReader& reader, double wanted) {
  if (wanted > 0) return wanted;
  return reader.header().frame_rate > 0 ? reader.header().frame_rate : 30.0;
}

}  // namespace

const char* state_name(PlayerState state) {
  switch (state) {
    case PlayerState::Paused: return "paused";
    case PlayerState::Playing: return "playing";
    case PlayerState::Ended: return "ended";
    case PlayerState::Stopped: return "stopped";
  }
  return "?";
}

Player::Player(const io::ContainerReader& reader, FrameAllocator& allocator, const Clock& clock, PlayerOptions options)
    : clock_(clock),
      options_(std::move(options)),
      frame_count_(options_.frames > 0 ? std::min(options_.frames, reader.frame_count()) : reader.frame_count()),
      pipeline_(reader, allocator, options_.pipeline),
      clock_state_(media_rate(reader, options_.frame_rate)),
      end_(options_.end) {
  demand_ = options_.pipeline.demand;
  const double now = clock_.now();
  clock_state_.set_rate(now, options_.rate);
  const uint64_t start = frame_count_ ? std::min(options_.start_frame, frame_count_ - 1) : 0;
  clock_state_.jump(now, double(start));
  shown_position_ = int64_t(start);
  schedule_.direction = 1;
  restart_from(int64_t(start), direction_for(options_.rate), stride_for(options_.rate), false);
  if (!schedule_.empty()) target_ = 0;
}

Player::~Player() = default;  // shown_ goes back before the pipeline stops (member order)

uint32_t Player::stride_for(double rate) const {
  if (options_.display_rate <= 0) return 1;
  const double per_refresh = std::abs(rate) * clock_state_.frames_per_second() / options_.display_rate;
  return std::max<uint32_t>(1, static_cast<uint32_t>(std::floor(per_refresh + 1e-9)));
}

int Player::direction_for(double rate) const { return rate < 0 ? -1 : rate > 0 ? 1 : schedule_.direction; }

// The frame shown is the one nearest the media position (its interval is
// centred on it), and the clock is anchored at a frame's centre when it
// shows: refreshes at the media rate then fall mid-interval, so one that
// comes a little early or late still shows each frame exactly once.
double Player::interval_start(int64_t position) const {
  return double(position) - 0.5 * double(schedule_.stride) * schedule_.direction;
}

bool Player::is_due(uint64_t sequence, double now) const {
  if (state_ != PlayerState::Playing) return false;
  if (anchor_on_show_) return true;  // a seek's first frame shows as soon as it is there
  const double ahead = clock_state_.position(now) - interval_start(schedule_.position_at(sequence));
  return ahead * schedule_.direction >= -1e-9;
}

void Player::restart_from(int64_t start, int direction, uint32_t stride, bool anchor_on_show) {
  schedule_ = {frame_count_, start, direction, stride, end_};
  pipeline_.restart(schedule_);
  shown_sequence_.reset();
  target_.reset();
  anchor_on_show_ = anchor_on_show;
}

std::optional<uint64_t> Player::pending_sequence() {
  if (target_) return target_;
  if (anchor_on_show_) {
    const NextEntry next = pipeline_.peek(0);
    if (!next.end) return next.sequence;
  }
  return std::nullopt;
}

uint64_t Player::current_frame() {
  if (const auto pending = pending_sequence()) {
    if (const auto f = schedule_.frame_at(*pending)) return *f;
  }
  if (!shown_.empty()) return shown_.frame();
  return static_cast<uint64_t>(std::clamp<int64_t>(shown_position_, 0, int64_t(frame_count_ ? frame_count_ - 1 : 0)));
}

void Player::show(FrameHandle frame, double now) {
  const uint64_t sequence = frame.sequence();
  shown_ = std::move(frame);  // gives the previous frame back
  shown_position_ = schedule_.position_at(sequence);
  shown_sequence_ = sequence;
  changed_ = true;
  stat_shown_.fetch_add(1, kRelaxed);
  stat_frame_.store(shown_.frame(), kRelaxed);
  if (state_ != PlayerState::Playing) return;
  if (anchor_on_show_) {
    clock_state_.jump(now, double(shown_position_));  // media time starts with the first frame
    anchor_on_show_ = false;
  } else if (options_.policy == RealTimePolicy::HoldLastFrame && is_due(sequence + 1, now)) {
    clock_state_.jump(now, double(shown_position_));  // late: media time waits rather than skip
  }
}

bool Player::handle_failure(FrameHandle failed, double now) {
  errors_.push_back(*failed.error());
  stat_errors_.fetch_add(1, kRelaxed);
  if (options_.on_error == ErrorPolicy::SkipFrame) return false;
  state_ = PlayerState::Stopped;
  clock_state_.pause(now);
  PlaybackSchedule idle = schedule_;  // nothing more to read
  idle.end = EndMode::Stop;
  idle.start = -1;
  schedule_ = idle;
  pipeline_.restart(idle);
  shown_sequence_.reset();
  target_.reset();
  anchor_on_show_ = false;
  return true;
}

bool Player::check_end(const NextEntry& next, double now) {
  if (!next.end) return false;
  if (const auto fatal = pipeline_.fatal_error()) {
    errors_.push_back(*fatal);
    stat_errors_.fetch_add(1, kRelaxed);
    state_ = PlayerState::Stopped;
    clock_state_.pause(now);
  } else if (is_due(next.sequence, now)) {  // the last frame has had its time
    state_ = PlayerState::Ended;
    clock_state_.pause(now);
  }
  return true;
}

void Player::set_demand(const ViewDemand& demand) {
  demand_ = demand;
  pipeline_.set_demand(demand);
}

void Player::refine() {
  if (target_ || shown_.empty() || !pipeline_.short_of(shown_, demand_)) return;
  // The frame stays on screen until its new read is shown (tick_paused).
  restart_from(shown_position_, schedule_.direction, schedule_.stride, false);
  target_ = 0;
  stat_refinements_.fetch_add(1, kRelaxed);
}

void Player::tick_paused(double now) {
  if (!target_) return refine();
  const NextEntry next = pipeline_.peek(0);
  if (next.end || next.sequence != *target_) {
    if (next.end) target_.reset();
    return;
  }
  if (next.status == EntryStatus::Ready) {
    target_.reset();
    show(pipeline_.take(), now);
    refine();  // the demand may have grown while it was read
  } else if (next.status == EntryStatus::Failed) {
    target_.reset();
    handle_failure(pipeline_.take(), now);
  }
}

void Player::tick_hold(double now) {
  while (true) {
    const NextEntry next = pipeline_.peek(0);
    if (check_end(next, now) || !is_due(next.sequence, now)) return;
    switch (next.status) {
      case EntryStatus::Ready: show(pipeline_.take(), now); return;
      case EntryStatus::Failed:
        if (handle_failure(pipeline_.take(), now)) return;
        continue;  // the next frame may be due as well
      default:
        if (!anchor_on_show_) stat_stalls_.fetch_add(1, kRelaxed);  // waiting for a seek is not a stall
        return;
    }
  }
}

bool Player::catch_up(double now) {
  const NextEntry head = pipeline_.peek(0);
  if (head.end) return false;
  const double behind = (clock_state_.position(now) - interval_start(schedule_.position_at(head.sequence))) *
                        schedule_.direction / schedule_.stride;
  if (behind < double(std::max<uint32_t>(pipeline_.window(), 2))) return false;
  const uint64_t due = head.sequence + static_cast<uint64_t>(behind);
  if (!schedule_.frame_at(due)) return false;  // near the end: the normal path drops and ends
  stat_drops_.fetch_add(due - head.sequence, kRelaxed);
  restart_from(schedule_.position_at(due), schedule_.direction, schedule_.stride, false);
  return true;
}

void Player::tick_skip(double now) {
  if (anchor_on_show_) return tick_hold(now);  // a seek's first frame: the clock starts when it shows
  if (catch_up(now)) return;
  constexpr size_t kNone = ~size_t(0);
  size_t newest = kNone;
  for (size_t i = 0;; ++i) {
    const NextEntry n = pipeline_.peek(i);
    if (n.status == EntryStatus::None || !is_due(n.sequence, now)) break;
    if (n.status == EntryStatus::Ready) newest = i;
  }
  if (newest == kNone) {
    const NextEntry next = pipeline_.peek(0);
    if (check_end(next, now) || !is_due(next.sequence, now)) return;
    if (next.status == EntryStatus::Failed) handle_failure(pipeline_.take(), now);
    else stat_stalls_.fetch_add(1, kRelaxed);
    return;
  }
  for (size_t i = 0; i < newest; ++i) {
    if (pipeline_.peek(0).status == EntryStatus::Failed) {
      if (handle_failure(pipeline_.take(), now)) return;
    } else {
      pipeline_.drop();
      stat_drops_.fetch_add(1, kRelaxed);
    }
  }
  show(pipeline_.take(), now);
}

Tick Player::update() {
  const double now = clock_.now();
  changed_ = false;
  switch (state_) {
    case PlayerState::Paused: tick_paused(now); break;
    case PlayerState::Playing:
      if (options_.policy == RealTimePolicy::HoldLastFrame) tick_hold(now);
      else tick_skip(now);
      break;
    default: break;
  }
  pipeline_.ready_count();  // refreshes the stat
  stat_state_.store(state_, kRelaxed);
  return {shown_.empty() ? nullptr : &shown_, changed_};
}

void Player::wait_for_due() {
  if (state_ == PlayerState::Paused && target_) {
    pipeline_.wait_next();
    return;
  }
  if (state_ != PlayerState::Playing) return;
  const NextEntry next = pipeline_.peek(0);
  if (next.end || !is_due(next.sequence, clock_.now())) return;
  pipeline_.wait_next();
}

void Player::play() {
  if (state_ == PlayerState::Playing || frame_count_ == 0) return;
  const double now = clock_.now();
  const double rate = clock_state_.rate();
  const int direction = direction_for(rate);
  const uint32_t stride = stride_for(rate);
  if (state_ == PlayerState::Ended) {
    const int64_t first = direction > 0 ? 0 : int64_t(frame_count_) - 1;
    clock_state_.jump(now, double(first));
    restart_from(first, direction, stride, true);
  } else if (target_) {  // a seek, step or scrub target still on its way: it comes first
    if (schedule_.direction != direction || schedule_.stride != stride) {
      restart_from(schedule_.position_at(*target_), direction, stride, true);
    } else {
      target_.reset();
      anchor_on_show_ = true;
    }
  } else {
    clock_state_.jump(now, double(shown_position_));
    const bool continues = state_ != PlayerState::Stopped && schedule_.direction == direction &&
                           schedule_.stride == stride && shown_sequence_ &&
                           pipeline_.peek(0).sequence == *shown_sequence_ + 1;
    if (!continues) restart_from(shown_position_ + int64_t(direction) * stride, direction, stride, false);
  }
  state_ = PlayerState::Playing;
  clock_state_.play(now);
  stat_state_.store(state_, kRelaxed);
}

void Player::pause() {
  if (state_ != PlayerState::Playing) return;
  clock_state_.pause(clock_.now());
  state_ = PlayerState::Paused;
  if (anchor_on_show_) {  // a seek target not shown yet: still show it
    anchor_on_show_ = false;
    const NextEntry next = pipeline_.peek(0);
    if (!next.end) target_ = next.sequence;
  }
  stat_state_.store(state_, kRelaxed);
}

void Player::set_rate(double rate) {
  const double now = clock_.now();
  clock_state_.set_rate(now, rate);
  const int direction = direction_for(rate);
  const uint32_t stride = stride_for(rate);
  if ((direction == schedule_.direction && stride == schedule_.stride) || state_ == PlayerState::Stopped) return;
  if (const auto pending = pending_sequence()) {  // keep the frame on its way first, then go the new way
    const bool anchor = anchor_on_show_;
    const bool paused = target_.has_value();
    restart_from(schedule_.position_at(*pending), direction, stride, anchor);
    if (paused) target_ = 0;
    return;
  }
  restart_from(shown_position_ + int64_t(direction) * stride, direction, stride, false);
  clock_state_.jump(now, double(shown_position_));
}

void Player::set_end_mode(EndMode end) {
  if (end == end_) return;
  end_ = end;
  if (state_ == PlayerState::Stopped || frame_count_ == 0) return;
  // The unwrapped axis starts again from the frame number.
  const auto frame = static_cast<int64_t>(current_frame());
  const bool pending = pending_sequence().has_value();
  const bool paused = target_.has_value();
  const bool anchor = anchor_on_show_;
  const int direction = schedule_.direction;
  if (pending) {
    restart_from(frame, direction, schedule_.stride, anchor);
    if (paused) target_ = 0;
    return;
  }
  shown_position_ = frame;
  restart_from(frame + int64_t(direction) * schedule_.stride, direction, schedule_.stride, false);
  clock_state_.jump(clock_.now(), double(frame));
}

void Player::seek(uint64_t frame) {
  if (frame_count_ == 0) return;
  frame = std::min(frame, frame_count_ - 1);
  const double rate = clock_state_.rate();
  clock_state_.jump(clock_.now(), double(frame));
  if (state_ == PlayerState::Ended || state_ == PlayerState::Stopped) state_ = PlayerState::Paused;
  restart_from(int64_t(frame), direction_for(rate), stride_for(rate), state_ == PlayerState::Playing);
  if (state_ != PlayerState::Playing) target_ = 0;
  stat_state_.store(state_, kRelaxed);
}

void Player::step(int64_t frames) {
  if (frames == 0 || frame_count_ == 0) return;
  pause();
  if (state_ != PlayerState::Paused) state_ = PlayerState::Paused;  // from Ended or Stopped
  const auto from = static_cast<int64_t>(current_frame());
  const auto n = static_cast<int64_t>(frame_count_);
  const int64_t to = end_ == EndMode::Loop ? wrap(from + frames, n) : std::clamp<int64_t>(from + frames, 0, n - 1);
  if (to != from || target_) move_to(uint64_t(to), frames > 0 ? 1 : -1, clock_.now());
  stat_state_.store(state_, kRelaxed);
}

void Player::scrub(uint64_t frame) {
  if (frame_count_ == 0) return;
  pause();
  if (state_ != PlayerState::Paused) state_ = PlayerState::Paused;
  frame = std::min(frame, frame_count_ - 1);
  const uint64_t from = current_frame();
  const int direction = frame > from ? 1 : frame < from ? -1 : schedule_.direction;
  if (frame != from || target_) move_to(frame, direction, clock_.now());
  stat_state_.store(state_, kRelaxed);
}

void Player::move_to(uint64_t frame, int direction, double now) {
  // Already fetched (or next to fetch) in this direction: skip ahead to it,
  // keeping what was prefetched (dropped frames stay cached behind).
  if (schedule_.direction == direction && schedule_.stride == 1) {
    const uint32_t look = pipeline_.window();
    for (size_t i = 0; i <= look; ++i) {
      const NextEntry n = pipeline_.peek(i);
      if (n.end) break;
      if (n.frame == frame) {
        for (size_t d = 0; d < i; ++d) pipeline_.drop();
        target_ = n.sequence;
        return;
      }
      if (n.status == EntryStatus::None) break;  // not fetched yet past here
    }
  }
  clock_state_.jump(now, double(frame));
  restart_from(int64_t(frame), direction, 1, false);
  target_ = 0;
}

std::optional<FrameError> Player::pop_error() {
  if (errors_.empty()) return std::nullopt;
  FrameError e = std::move(errors_.front());
  errors_.pop_front();
  return e;
}

PlaybackStats Player::stats() const {
  PlaybackStats s;
  s.state = stat_state_.load(kRelaxed);
  s.frame = stat_frame_.load(kRelaxed);
  s.frames_shown = stat_shown_.load(kRelaxed);
  s.stalls = stat_stalls_.load(kRelaxed);
  s.drops = stat_drops_.load(kRelaxed);
  s.errors = stat_errors_.load(kRelaxed);
  s.refinements = stat_refinements_.load(kRelaxed);
  s.pipeline = pipeline_.stats();
  return s;
}

}  // namespace sluice::runtime
