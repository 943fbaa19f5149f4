#include "sluice/io/export.h"

#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

namespace sluice::io {
namespace {

namespace fs = std::filesystem;

// A printf pattern with one integer conversion ("shot_%04d.vtp"), split so
// it is expanded without handing user text to printf.
struct FramePattern {
  std::string before, after;  // literal text ("%%" already undone)
  bool zero_pad = false;
  int width = 0;
};

FramePattern parse_pattern(const std::string& out) {
  FramePattern p;
  bool seen = false;
  const auto bad = [&] {
    return Error({out}, "a pattern needs exactly one integer conversion such as %05d (and %% for '%')");
  };
  for (size_t i = 0; i < out.size(); ++i) {
    std::string& text = seen ? p.after : p.before;
    if (out[i] != '%') {
      text += out[i];
      continue;
    }
    if (i + 1 < out.size() && out[i + 1] == '%') {
      text += '%';
      ++i;
      continue;
    }
    if (seen) throw bad();
    seen = true;
    size_t j = i + 1;
    if (j < out.size() && out[j] == '0') p.zero_pad = true, ++j;
    while (j < out.size() && std::isdigit(static_cast<unsigned char>(out[j]))) p.width = p.width * 10 + (out[j++] - '0');
    while (j < out.size() && out[j] == 'l') ++j;
    if (j >= out.size() || (out[j] != 'd' && out[j] != 'i' && out[j] != 'u') || p.width > 20) throw bad();
    i = j;
  }
  if (!seen) throw bad();
  return p;
}

std::string expand(const FramePattern& p, uint64_t frame) {
  std::string number = std::to_string(frame);
  if (int(number.size()) < p.width) number.insert(0, size_t(p.width) - number.size(), p.zero_pad ? '0' : ' ');
  return p.before + number + p.after;
}

// Refuses to replace files unless forced; creates the directories needed.
void prepare_outputs(const SeriesPlan& plan, bool force) {
  std::vector<std::string> all;
  for (const auto& [f, path] : plan.files) all.push_back(path);
  if (!plan.pvd.empty()) all.push_back(plan.pvd);
  std::vector<std::string> existing;
  for (const std::string& path : all) {
    if (fs::exists(path)) existing.push_back(path);
  }
  if (!existing.empty() && !force) throw OutputsExist(existing);
  for (const std::string& path : all) {
    const fs::path dir = fs::path(path).parent_path();
    if (!dir.empty()) fs::create_directories(dir);
  }
}

// The indices of the requested attributes; every one when none is named.
std::vector<size_t> attribute_indices(const ContainerReader& reader, const std::vector<std::string>& names) {
  const FileHeader& header = reader.header();
  std::vector<size_t> out;
  if (names.empty()) {
    for (size_t a = 0; a < header.attributes.size(); ++a) out.push_back(a);
    return out;
  }
  for (const std::string& name : names) {
    size_t a = 0;
    while (a < header.attributes.size() && header.attributes[a].name != name) ++a;
    if (a == header.attributes.size()) {
      std::string have;
      for (const auto& info : header.attributes) have += (have.empty() ? "" : ", ") + info.name;
      throw Error({reader.path()}, "no attribute '" + name + "'; the file has: " + (have.empty() ? "(none)" : have));
    }
    out.push_back(a);
  }
  return out;
}

// `file` as a .pvd at `pvd` names it: relative to the .pvd's directory.
std::string pvd_member(const std::string& pvd, const std::string& file) {
  return fs::absolute(file).lexically_relative(fs::absolute(pvd).parent_path()).generic_string();
}

// Frames decoded at once: one per core (small frames), but within a memory
// budget for big ones (a frame is decoded, then copied out as floats).
size_t frames_in_flight(const ContainerReader& reader, std::span<const uint64_t> frames, size_t attributes) {
  constexpr double kBudgetBytes = 4e9;
  uint64_t largest = 1;
  for (uint64_t f : frames) largest = std::max(largest, reader.index().frames[f].particle_count);
  const double per_particle = double(decoded_particle_bytes(reader.header().position_coding)) + 14.0 +
                              2.0 * double(reader.header().attributes.size()) + 4.0 * double(attributes);
  const double fit = kBudgetBytes / (per_particle * double(largest));
  return size_t(std::clamp(fit, 1.0, double(tbb::info::default_concurrency())));
}

struct FrameWritten {
  uint64_t frame = 0;
  double time = 0;
  uint64_t particles = 0, kept = 0, bytes_in = 0, bytes_out = 0;
};

// Decodes frame `f`, thins it to `lod_level` and writes its file.
FrameWritten export_frame(const ContainerReader& reader, uint64_t f, const std::vector<size_t>& attributes,
                          float lod_level, const SeriesPlan& plan) {
  FrameWritten w;
  w.frame = f;
  w.bytes_in = reader.index().frames[f].bytes;
  ExportFrame frame = to_export_frame(decode_frame(reader, f), reader.header(), attributes);
  w.time = frame.time;
  w.particles = frame.count();
  if (lod_level < 1) thin_by_lod(frame, lod_level);
  w.kept = frame.count();
  w.bytes_out = write_export(plan.files.at(f), frame, plan.format);
  return w;
}

std::string outputs_exist_text(const std::vector<std::string>& paths) {
  const std::string more = paths.size() > 1 ? " (and " + std::to_string(paths.size() - 1) + " more outputs)" : "";
  return "exists" + more;
}

}  // namespace

OutputsExist::OutputsExist(std::vector<std::string> paths)
    : Error({paths.empty() ? std::string() : paths.front()}, outputs_exist_text(paths)), paths_(std::move(paths)) {}

SeriesPlan plan_series(const std::string& out, std::span<const uint64_t> frames) {
  const auto format = export_format_of(out);
  if (!format) throw Error({out}, "the format comes from the extension: .vtp, .csv or .ply");
  SeriesPlan plan{*format, {}, {}};
  const bool several = frames.size() > 1;
  std::string series_name;  // the .pvd's path without the extension
  if (out.find('%') != std::string::npos) {
    const FramePattern pattern = parse_pattern(out);
    for (uint64_t f : frames) plan.files[f] = expand(pattern, f);
    // "frames/shot_%04d.vtp" -> "frames/shot"; a pattern with no name before the number -> "series".
    const fs::path prefix(pattern.before);
    std::string name = prefix.filename().string();
    while (!name.empty() && std::string("_-. ").find(name.back()) != std::string::npos) name.pop_back();
    series_name = (prefix.parent_path() / (name.empty() ? "series" : name)).string();
  } else {
    const fs::path p(out);
    series_name = (p.parent_path() / p.stem()).string();
    for (uint64_t f : frames) {
      char number[32];
      std::snprintf(number, sizeof number, "_%05llu", (unsigned long long)f);
      plan.files[f] = several ? series_name + number + p.extension().string() : out;
    }
  }
  if (several && plan.format == ExportFormat::Vtp) plan.pvd = series_name + ".pvd";
  return plan;
}

SeriesSummary export_series(const ContainerReader& reader, const SeriesOptions& options,
                            const std::function<void(const SeriesProgress&)>& progress) {
  std::vector<uint64_t> frames = options.frames;
  if (frames.empty()) {
    for (uint64_t f = 0; f < reader.frame_count(); ++f) frames.push_back(f);
  }
  for (const uint64_t f : frames) {
    if (f >= reader.frame_count()) {
      throw Error(reader.location(f), "no such frame (the file has " + std::to_string(reader.frame_count()) + ")");
    }
  }
  if (!(options.lod_level > 0 && options.lod_level <= 1)) {
    throw Error({reader.path()}, "LOD level " + std::to_string(options.lod_level) + " is out of range: give a fraction in (0, 1]");
  }
  const std::vector<size_t> attributes = attribute_indices(reader, options.attributes);
  SeriesSummary total;
  total.plan = plan_series(options.out, frames);
  const SeriesPlan& plan = total.plan;
  prepare_outputs(plan, options.force);

  std::vector<PvdEntry> entries;
  size_t next = 0;
  tbb::parallel_pipeline(
      frames_in_flight(reader, frames, attributes.size()),
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next == frames.size()) {
                                           fc.stop();
                                           return 0;
                                         }
                                         return frames[next++];
                                       }) &
          tbb::make_filter<uint64_t, FrameWritten>(
              tbb::filter_mode::parallel,
              [&](uint64_t f) { return export_frame(reader, f, attributes, options.lod_level, plan); }) &
          tbb::make_filter<FrameWritten, void>(tbb::filter_mode::serial_in_order, [&](const FrameWritten& w) {
            if (!plan.pvd.empty()) entries.push_back({w.time, pvd_member(plan.pvd, plan.files.at(w.frame))});
            ++total.frames;
            total.particles += w.particles;
            total.kept += w.kept;
            total.bytes_in += w.bytes_in;
            total.bytes_out += w.bytes_out;
            if (progress) progress({total.frames, frames.size(), total.bytes_in, total.bytes_out});
          }));
  if (!plan.pvd.empty()) total.bytes_out += write_pvd(plan.pvd, entries);
  return total;
}

}  // namespace sluice::io
