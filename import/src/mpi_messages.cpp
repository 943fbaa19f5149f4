#include "mpi_messages.h"

#include "sluice/io/writer.h"

namespace sluice::import {
namespace {

template <class T>
void put_optional(WireWriter& w, const std::optional<T>& v) {
  w.put<uint8_t>(v.has_value());
  w.put<T>(v.value_or(T{}));
}
template <class T>
std::optional<T> get_optional(WireReader& r) {
  const bool has = r.get<uint8_t>() != 0;
  const T v = r.get<T>();
  return has ? std::optional<T>(v) : std::nullopt;
}

void put_floats(WireWriter& w, const std::vector<float>& v) { w.put_bytes(std::as_bytes(std::span(v))); }
std::vector<float> get_floats(WireReader& r) {
  const std::span<const std::byte> b = r.get_bytes();
  if (b.size() % sizeof(float)) throw io::Error({}, "a message between MPI ranks holds a cut float array");
  std::vector<float> v(b.size() / sizeof(float));
  std::memcpy(v.data(), b.data(), b.size());
  return v;
}

void put_shape(WireWriter& w, const io::FrameShape& s) {
  w.put(s.particles);
  w.put(s.low);
  w.put(s.high);
  for (int a = 0; a < 3; ++a) {
    put_floats(w, s.column_low[size_t(a)]);
    put_floats(w, s.column_high[size_t(a)]);
  }
}
io::FrameShape get_shape(WireReader& r) {
  io::FrameShape s;
  s.particles = r.get<uint64_t>();
  s.low = r.get<std::array<float, 3>>();
  s.high = r.get<std::array<float, 3>>();
  for (int a = 0; a < 3; ++a) {
    s.column_low[size_t(a)] = get_floats(r);
    s.column_high[size_t(a)] = get_floats(r);
  }
  return s;
}

}  // namespace

void put_error(WireWriter& w, const io::Error& e) {
  w.put_string(e.where().file);
  put_optional(w, e.where().frame);
  put_optional(w, e.where().chunk);
  w.put_string(e.message());
}

io::Error get_error(WireReader& r) {
  io::ErrorLocation where;
  where.file = r.get_string();
  where.frame = get_optional<uint64_t>(r);
  where.chunk = get_optional<uint64_t>(r);
  return io::Error(where, r.get_string());
}

void put_plan(WireWriter& w, const Plan& p) {
  w.put_bytes(io::container_head(p.header));
  w.put_string(p.source.id_array);
  w.put<uint8_t>(p.source.no_ids);
  w.put<uint64_t>(p.source.attributes.size());
  for (const std::string& a : p.source.attributes) w.put_string(a);
  w.put(p.shape_box.min);
  w.put(p.shape_box.max);
  w.put(p.time_step);
  w.put(p.from);
  w.put(p.frames);
}

Plan get_plan(WireReader& r) {
  Plan p;
  p.header = io::parse_container_head(r.get_bytes(), {"the plan rank 0 sent"});
  p.source.id_array = r.get_string();
  p.source.no_ids = r.get<uint8_t>() != 0;
  const uint64_t attributes = r.get<uint64_t>();
  if (attributes > io::kMaxAttributes) throw io::Error({}, "the plan rank 0 sent names too many attributes");
  for (uint64_t a = 0; a < attributes; ++a) p.source.attributes.push_back(r.get_string());
  p.shape_box.min = r.get<std::array<float, 3>>();
  p.shape_box.max = r.get<std::array<float, 3>>();
  p.time_step = r.get<double>();
  p.from = r.get<uint64_t>();
  p.frames = r.get<uint64_t>();
  return p;
}

void put_facts(WireWriter& w, const FrameWork& work, int rank) {
  w.put(work.frame);
  w.put(rank);
  w.put<uint8_t>(work.error.has_value());
  if (work.error) {
    put_error(w, *work.error);
    return;
  }
  w.put<uint64_t>(work.encoded.record.size());
  const io::FrameSummary summary = io::summarize_frame(work.encoded.header);
  w.put(summary.entry);
  w.put<uint64_t>(summary.attribute_ranges.size());
  for (const std::array<float, 2>& range : summary.attribute_ranges) w.put(range);
  w.put(work.input_bytes);
  w.put<uint64_t>(work.repairs.size());
  for (const std::string& repair : work.repairs) w.put_string(repair);
  w.put<uint8_t>(work.shape.has_value());
  if (work.shape) put_shape(w, *work.shape);
  w.put<uint8_t>(work.time_given);
  w.put(work.far);
}

FrameFacts get_facts(WireReader& r) {
  FrameFacts f;
  f.frame = r.get<uint64_t>();
  f.rank = r.get<int>();
  if (r.get<uint8_t>()) {
    f.error = get_error(r);
    return f;
  }
  f.record_bytes = r.get<uint64_t>();
  f.summary.entry = r.get<io::FrameIndexEntry>();
  const uint64_t ranges = r.get<uint64_t>();
  if (ranges > r.remaining() / sizeof(std::array<float, 2>)) throw io::Error({}, "a message between MPI ranks is cut short");
  for (uint64_t a = 0; a < ranges; ++a) f.summary.attribute_ranges.push_back(r.get<std::array<float, 2>>());
  f.input_bytes = r.get<uint64_t>();
  const uint64_t repairs = r.get<uint64_t>();
  for (uint64_t i = 0; i < repairs; ++i) f.repairs.push_back(r.get_string());
  if (r.get<uint8_t>()) f.shape = get_shape(r);
  f.time_given = r.get<uint8_t>() != 0;
  f.far = r.get<io::FarReport>();
  return f;
}

}  // namespace sluice::import
