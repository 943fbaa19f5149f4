// open_source(): what the user typed (a file, a glob, a .pvd, a directory)
// becomes an ordered list of frames, each made of one or more files. read()
// turns a frame's files into one ParticleFrame and repairs what it can.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <new>
#include <stdexcept>
#include <set>
#include <optional>
#include <sstream>
#include <string_view>

#include "legacy_vtk.h"
#include "text_reader.h"
#include "xml_check.h"
#include "xml_tags.h"
#include "sluice/error.h"
#include "sluice/import/source.h"
#include "sluice/import/vtk.h"
#ifdef SLUICE_WITH_VTK
#include "vtk_reader.h"
#endif

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

namespace fs = std::filesystem;

// ------------------------------------------------------------------ formats

enum class Format { kCsv, kXyz, kLegacy, kVtu, kVtp, kPvtu, kPvtp, kPvd };

constexpr const char* kSupported = ".vtk, .vtu, .vtp, .pvtu, .pvtp, .pvd (VTK), .csv, .xyz, .txt";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string extension(const std::string& path) { return lower(fs::path(path).extension().string()); }

std::optional<Format> format_of(const std::string& path) {
  static const std::map<std::string, Format> kByExtension = {
      {".csv", Format::kCsv},   {".xyz", Format::kXyz},   {".txt", Format::kXyz},
      {".vtk", Format::kLegacy}, {".vtu", Format::kVtu},   {".vtp", Format::kVtp},
      {".pvtu", Format::kPvtu}, {".pvtp", Format::kPvtp}, {".pvd", Format::kPvd}};
  const auto it = kByExtension.find(extension(path));
  if (it == kByExtension.end()) return std::nullopt;
  return it->second;
}

[[maybe_unused]] bool needs_vtk(Format f) { return f != Format::kCsv && f != Format::kXyz && f != Format::kLegacy; }

const char* format_name(Format f) {
  switch (f) {
    case Format::kCsv: return "CSV";
    case Format::kXyz: return "XYZ text";
    case Format::kLegacy: return "VTK legacy";
    case Format::kVtu: return "VTK XML unstructured grid";
    case Format::kVtp: return "VTK XML polydata";
    case Format::kPvtu: return "VTK XML parallel unstructured grid";
    case Format::kPvtp: return "VTK XML parallel polydata";
    case Format::kPvd: return "ParaView collection";
  }
  return "?";
}

// The format of `path`; throws unless this build can read it.
Format require_readable(const std::string& path) {
  const std::optional<Format> f = format_of(path);
  const std::string ext = extension(path).empty() ? "(no extension)" : extension(path);
  if (!f && ext == ".sluice") {
    throw Error({path}, "not a readable .sluice file (its first bytes are not the format's magic): damaged, or another "
                        "format under this name. `sluice recover` rebuilds a damaged one from its frames");
  }
  if (!f) throw Error({path}, "unsupported file type " + ext + "; supported: " + kSupported);
#ifndef SLUICE_WITH_VTK
  if (needs_vtk(*f)) {
    throw Error({path}, "this build of sluice has no VTK support, so it cannot read " + ext +
                            " files; install libvtk9-dev (Debian/Ubuntu) and rebuild sluice "
                            "(cmake -DSLUICE_WITH_VTK=ON), or export the data as .csv");
  }
#endif
  return *f;
}

std::string join(const std::vector<std::string>& names, const char* sep = ", ") {
  if (names.empty()) return "(none)";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : sep) + n;
  return out;
}

// ------------------------------------------------------------- one file

struct FileFrame {
  ParticleFrame frame;
  std::optional<double> time;  // stored in the file, if it has one
};

// VTK's XML readers allocate what a header declares: sizes are checked
// against the file first.
[[maybe_unused]] detail::XmlFacts check_xml(const std::string& path) {
  const Format f = require_readable(path);
  if (f != Format::kPvtu && f != Format::kPvtp) return detail::check_vtk_xml(path);
  detail::XmlFacts facts;
  detail::check_parallel_xml(path, facts);
  return facts;
}

// Legacy VTK is read by sluice itself, every count checked first (VTK's
// legacy reader trusts the file).
FileFrame read_legacy(const std::string& path, const std::vector<std::string>& attributes,
                      const std::string& id_array) {
  detail::LegacyRead r = detail::read_legacy_vtk(path, attributes, id_array);
  return {std::move(r.frame), r.time};
}

FileFrame read_file(const std::string& path, const std::vector<std::string>& attributes, const std::string& id_array) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error({path}, "file not found");
  switch (require_readable(path)) {
    case Format::kCsv: return {detail::read_csv(path, attributes, id_array), std::nullopt};
    case Format::kXyz: return {detail::read_xyz(path, attributes, id_array), std::nullopt};
    case Format::kPvd: throw Error({path}, "a .pvd collection cannot be a frame of another source");
    case Format::kLegacy: return read_legacy(path, attributes, id_array);
    default: break;
  }
#ifdef SLUICE_WITH_VTK
  const detail::XmlFacts facts = check_xml(path);
  try {
    detail::VtkRead r = detail::read_vtk(path, attributes, id_array, facts.non_vertex_cells());
    return {std::move(r.frame), r.time};
  } catch (const std::bad_alloc&) {
    // VTK sizes some buffers by values inside compressed blocks, which the
    // checks do not inflate.
    throw Error({path}, "VTK could not allocate the memory the file asks for: the file is damaged, or too large "
                        "for this machine");
  } catch (const std::length_error&) {
    throw Error({path}, "VTK met a size it cannot hold: the file is damaged");
  }
#else
  throw Error({path}, "no VTK support in this build");  // require_readable already threw
#endif
}

std::vector<std::string> file_arrays(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error({path}, "file not found");
  switch (require_readable(path)) {
    case Format::kCsv: return detail::csv_arrays(path);
    case Format::kXyz: return detail::xyz_arrays(path);
    case Format::kLegacy: return detail::legacy_vtk_arrays(path);
    default: break;
  }
#ifdef SLUICE_WITH_VTK
  (void)check_xml(path);
  return detail::vtk_arrays(path);
#else
  return {};
#endif
}

// ---------------------------------------------------------------- repairs

// True when every value is finite: one vectorizable pass over the bits (an
// exponent of all ones is an infinity or a NaN).
bool all_finite(const std::vector<float>& values) {
  constexpr uint32_t kExponent = 0x7f800000u;
  uint32_t most = 0;  // the largest exponent field met
  for (const float v : values) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    most = std::max(most, bits & kExponent);
  }
  return most != kExponent;
}

// Drops particles with a non-finite coordinate (with their ids and
// attributes) and zeroes non-finite attribute values of the particles kept.
// Indices in the notes are positions in the file.
void repair_values(ParticleFrame& f, const std::vector<std::string>& attribute_names) {
  // The common case, checked at memory speed: nothing to repair.
  if (all_finite(f.positions) &&
      std::all_of(f.attributes.begin(), f.attributes.end(), [](const auto& a) { return all_finite(a); })) {
    return;
  }
  const size_t n = f.count();
  std::vector<uint8_t> drop;  // stays empty in the common case of no bad position
  size_t dropped = 0;
  size_t first_dropped = 0;
  for (size_t i = 0; i < n; ++i) {
    const float* p = &f.positions[i * 3];
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) continue;
    if (drop.empty()) {
      drop.assign(n, 0);
      first_dropped = i;
    }
    drop[i] = 1;
    ++dropped;
  }
  if (dropped > 0) {
    f.repairs.push_back("dropped " + std::to_string(dropped) + " particle" + (dropped == 1 ? "" : "s") +
                        " with non-finite positions (first at index " + std::to_string(first_dropped) + ")");
  }
  for (size_t k = 0; k < f.attributes.size(); ++k) {
    std::vector<float>& a = f.attributes[k];
    size_t fixed = 0;
    size_t first = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      if (std::isfinite(a[i]) || (!drop.empty() && drop[i])) continue;
      if (fixed++ == 0) first = i;
      a[i] = 0.0f;
    }
    if (fixed > 0) {
      f.repairs.push_back("replaced " + std::to_string(fixed) + " non-finite value" + (fixed == 1 ? "" : "s") +
                          " of '" + attribute_names[k] + "' by 0 (first at index " + std::to_string(first) + ")");
    }
  }
  if (dropped == 0) return;
  size_t out = 0;
  for (size_t i = 0; i < n; ++i) {
    if (drop[i]) continue;
    std::copy_n(&f.positions[i * 3], 3, &f.positions[out * 3]);
    if (!f.ids.empty()) f.ids[out] = f.ids[i];
    for (auto& a : f.attributes) a[out] = a[i];
    ++out;
  }
  f.positions.resize(out * 3);
  if (!f.ids.empty()) f.ids.resize(out);
  for (auto& a : f.attributes) a.resize(out);
}

// Duplicate ids are kept (the LOD value of those particles collides, no
// worse), but the user should know.
void note_duplicate_ids(ParticleFrame& f) {
  const std::vector<uint64_t>& ids = f.ids;
  // Most simulations write ids in increasing order: nothing to look for then.
  if (std::adjacent_find(ids.begin(), ids.end(), std::greater_equal<>()) == ids.end()) return;
  size_t extra = 0;
  size_t distinct = 0;
  uint64_t example = 0;
  const auto count = [&](bool again_seen_once, uint64_t id) {
    example = extra++ == 0 ? id : std::min(example, id);  // the smallest, whatever the order
    if (again_seen_once) ++distinct;
  };
  const uint64_t most = *std::max_element(ids.begin(), ids.end());
  if (most < 8 * ids.size() + 64) {
    // Dense ids (the usual case: 0..n-1 in another order): a count per id.
    std::vector<uint8_t> seen(most + 1, 0);
    for (uint64_t id : ids) {
      if (seen[id] < 2) ++seen[id];
      else seen[id] = 3;
      if (seen[id] >= 2) count(seen[id] == 2, id);
    }
  } else {
    std::vector<uint64_t> sorted = ids;
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 1; i < sorted.size(); ++i) {
      if (sorted[i] == sorted[i - 1]) count(i == 1 || sorted[i - 2] != sorted[i], sorted[i]);
    }
  }
  if (extra == 0) return;
  f.repairs.push_back(std::to_string(distinct) + " particle id" + (distinct == 1 ? " occurs" : "s occur") +
                      " more than once (" + std::to_string(extra) + " extra particles, e.g. id " +
                      std::to_string(example) + "): kept all particles");
}

void append(ParticleFrame& into, ParticleFrame&& part) {
  if (into.positions.empty() && into.ids.empty()) {
    into.positions = std::move(part.positions);
    into.ids = std::move(part.ids);
    into.attributes = std::move(part.attributes);
    return;
  }
  into.positions.insert(into.positions.end(), part.positions.begin(), part.positions.end());
  into.ids.insert(into.ids.end(), part.ids.begin(), part.ids.end());
  for (size_t k = 0; k < into.attributes.size(); ++k) {
    into.attributes[k].insert(into.attributes[k].end(), part.attributes[k].begin(), part.attributes[k].end());
  }
}

// ------------------------------------------------------------ the source

// One frame: its files (pieces of the same time step) and the time a .pvd gave.
struct FrameFiles {
  std::vector<std::string> files;
  std::optional<double> time;
};

class SeriesSource final : public FrameSource {
 public:
  SeriesSource(std::vector<FrameFiles> frames, SourceInfo info, SourceOptions options)
      : frames_(std::move(frames)), info_(std::move(info)), options_(std::move(options)) {}

  uint64_t frame_count() const override { return frames_.size(); }
  const SourceInfo& info() const override { return info_; }

  std::string frame_name(uint64_t i) const override {
    if (i >= frames_.size()) return "frame " + std::to_string(i) + " (out of range)";
    return join(frames_[i].files, " + ");
  }

  ParticleFrame read(uint64_t i) const override {
    if (i >= frames_.size()) {
      throw Error({info_.description, i}, "no such frame: the source has " + std::to_string(frames_.size()));
    }
    try {
      return read_frame(i);
    } catch (const Error& e) {
      if (e.where().frame) throw;
      throw Error({e.where().file, i, e.where().chunk}, e.message());
    }
  }

 private:
  ParticleFrame read_frame(uint64_t i) const {
    const FrameFiles& ff = frames_[i];
    const bool several = ff.files.size() > 1;
    ParticleFrame out;
    out.attributes.resize(options_.attributes.size());
    std::optional<double> file_time;
    for (const std::string& file : ff.files) {
      FileFrame part = read_file(file, options_.attributes, info_.id_array);
      repair_values(part.frame, options_.attributes);
      if (several && part.frame.count() == 0) part.frame.repairs.push_back("file has no points");
      for (auto& note : part.frame.repairs) out.repairs.push_back(several ? file + ": " + note : std::move(note));
      if (!file_time) file_time = part.time;
      append(out, std::move(part.frame));
    }
    if (out.count() == 0) {
      out.repairs.push_back(several ? "no points in any of its " + std::to_string(ff.files.size()) +
                                          " files: empty frame"
                                    : "file has no points: empty frame");
    }
    note_duplicate_ids(out);
    out.time = ff.time ? *ff.time : file_time ? *file_time : static_cast<double>(i);
    out.time_given = ff.time || file_time;
    return out;
  }

  std::vector<FrameFiles> frames_;
  SourceInfo info_;
  SourceOptions options_;
};

// -------------------------------------------------------------- planning

struct Plan {
  std::vector<FrameFiles> frames;
  std::string description;  // without the format, which is added once the files are known
};

std::vector<FrameFiles> one_frame_per_file(const std::vector<std::string>& files) {
  std::vector<FrameFiles> frames;
  frames.reserve(files.size());
  for (const auto& f : files) frames.push_back({{f}, std::nullopt});
  return frames;
}

// The name of a numbered series: the last digit run becomes '*'
// ("dam_fluid_00100.vtu" -> "dam_fluid_*.vtu").
std::string series_key(const std::string& filename) {
  const size_t last = filename.find_last_of("0123456789");
  if (last == std::string::npos) return filename;
  size_t first = last;
  while (first > 0 && std::isdigit(static_cast<unsigned char>(filename[first - 1]))) --first;
  return filename.substr(0, first) + "*" + filename.substr(last + 1);
}

Plan plan_pvd(const std::string& path);

Plan plan_directory(const std::string& dir) {
  std::error_code ec;
  std::map<std::string, std::vector<std::string>> groups;  // series key -> files
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code fec;
    if (name.empty() || name[0] == '.' || !entry.is_regular_file(fec) || !format_of(name)) continue;
    groups[series_key(name)].push_back(entry.path().string());
  }
  if (ec) throw Error({dir}, "cannot list the directory: " + ec.message());
  if (groups.empty()) throw Error({dir}, std::string("no particle files in this directory; supported: ") + kSupported);
  // A directory with one .pvd collection that references every other
  // particle file there is that collection (it also carries the times).
  std::vector<std::string> collections, others;
  for (const auto& [key, files] : groups) {
    for (const std::string& f : files) (format_of(f) == Format::kPvd ? collections : others).push_back(f);
  }
  if (collections.size() == 1) {
    Plan plan = plan_pvd(collections[0]);
    std::set<std::string> referenced;
    for (const FrameFiles& frame : plan.frames) {
      for (const std::string& f : frame.files) referenced.insert(fs::weakly_canonical(f).string());
    }
    const bool covers_all = std::all_of(others.begin(), others.end(), [&](const std::string& f) {
      return referenced.count(fs::weakly_canonical(f).string()) > 0;
    });
    if (covers_all) return plan;
  }
  if (groups.size() > 1) {
    // Several particle sets (PySPH writes fluid and boundary side by side):
    // mixing them into one fluid is never what the user wants.
    std::vector<std::string> listed;
    std::string example;
    for (const auto& [key, files] : groups) {
      const std::string glob = (fs::path(dir) / key).string();
      listed.push_back("'" + glob + "' (" + std::to_string(files.size()) + (files.size() == 1 ? " file)" : " files)"));
      if (example.empty() || key.find("fluid") != std::string::npos) example = glob;
    }
    // A collection next to its own files is the thing to open.
    for (const auto& [key, files] : groups) {
      if (files.size() == 1 && format_of(key) == Format::kPvd) example = files[0];
    }
    throw Error({dir}, "the directory holds several particle sets: " + join(listed) +
                           "; pass the one you want (a glob in quotes), e.g. '" + example + "'");
  }
  std::vector<std::string> files = groups.begin()->second;
  if (files.size() == 1 && format_of(files[0]) == Format::kPvd) return plan_pvd(files[0]);
  std::sort(files.begin(), files.end(), natural_less);
  return {one_frame_per_file(files), std::to_string(files.size()) + " files in directory " + dir};
}

Plan plan_glob(const std::string& pattern) {
  const std::vector<std::string> files = expand_glob_natural(pattern);
  if (files.empty()) throw Error({pattern}, "no files match this pattern");
  return {one_frame_per_file(files), std::to_string(files.size()) + " files matching " + pattern};
}

// ---------------------------------------------------------- .pvd parsing

struct PvdEntry {
  double time = 0;
  double part = 0;
  std::string group;
  std::string file;  // resolved against the .pvd's directory
  uint64_t line = 0;
};

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error({path}, "cannot open the file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool parse_number(const std::string& s, double& out) {
  const std::string_view v = s;
  const size_t b = v.find_first_not_of(" \t\n\r");
  const size_t e = v.find_last_not_of(" \t\n\r");
  if (b == std::string_view::npos) return false;
  const char* first = v.data() + b + (v[b] == '+' ? 1 : 0);
  const char* last = v.data() + e + 1;
  const auto [end, ec] = std::from_chars(first, last, out);
  return ec == std::errc() && end == last && std::isfinite(out);
}

PvdEntry pvd_entry(const std::string& path, const detail::XmlTag& tag) {
  const auto attr = [&](const char* key) -> const std::string* {
    const auto it = tag.attributes.find(key);
    return it == tag.attributes.end() ? nullptr : &it->second;
  };
  const auto where = [&] { return "line " + std::to_string(tag.line) + ": "; };
  PvdEntry e;
  e.line = tag.line;
  const std::string* file = attr("file");
  if (!file || file->empty()) throw Error({path}, where() + "DataSet has no file attribute");
  const std::string* timestep = attr("timestep");
  if (!timestep) throw Error({path}, where() + "DataSet has no timestep attribute");
  if (!parse_number(*timestep, e.time)) throw Error({path}, where() + "timestep '" + *timestep + "' is not a number");
  if (const std::string* part = attr("part"); part && !parse_number(*part, e.part)) e.part = 0;
  if (const std::string* group = attr("group")) e.group = *group;
  // Files beside the collection or below it: a path out of its folder is
  // what a damaged or hostile collection looks like.
  const fs::path f(*file);
  const fs::path normal = f.lexically_normal();
  if (f.is_absolute() || (!normal.empty() && *normal.begin() == "..")) {
    throw Error({path}, where() + "the listed file '" + *file +
                            "' lies outside the collection's folder; keep the .pvd beside its files, or pass the "
                            "files as a quoted glob");
  }
  if (format_of(normal.string()) == Format::kPvd) {
    throw Error({path}, where() + "the listed file '" + *file + "' is itself a .pvd collection (collections do not nest)");
  }
  e.file = (fs::path(path).parent_path() / normal).string();
  return e;
}

std::vector<PvdEntry> parse_pvd(const std::string& path) {
  const std::string text = read_text_file(path);
  detail::TagScanner scanner(text, path, "not a valid .pvd file");
  detail::XmlTag tag;
  if (!scanner.next(tag)) throw Error({path}, "empty file (not a valid .pvd file)");
  const auto type = tag.attributes.find("type");
  if (tag.name != "VTKFile" || type == tag.attributes.end() || type->second != "Collection") {
    throw Error({path}, "not a ParaView collection: expected <VTKFile type=\"Collection\">, found <" + tag.name +
                            (type == tag.attributes.end() ? "" : " type=\"" + type->second + "\"") + ">");
  }
  std::vector<PvdEntry> entries;
  while (scanner.next(tag)) {
    if (tag.name == "DataSet") entries.push_back(pvd_entry(path, tag));
  }
  if (entries.empty()) throw Error({path}, "the collection lists no DataSet");
  return entries;
}

// Throws if the collection mixes particle sets (group="fluid", "boundary").
void require_one_group(const std::string& path, const std::vector<PvdEntry>& entries) {
  std::vector<std::string> groups;
  std::vector<std::string> examples;
  for (const auto& e : entries) {
    if (std::find(groups.begin(), groups.end(), e.group) != groups.end()) continue;
    groups.push_back(e.group);
    examples.push_back((fs::path(e.file).parent_path() / series_key(fs::path(e.file).filename().string())).string());
  }
  if (groups.size() <= 1) return;
  std::vector<std::string> listed;
  for (size_t k = 0; k < groups.size(); ++k) listed.push_back("'" + groups[k] + "' (e.g. '" + examples[k] + "')");
  throw Error({path}, "the collection holds several groups (particle sets): " + join(listed) +
                          "; pass the files of one group as a quoted glob instead");
}

Plan plan_pvd(const std::string& path) {
  std::vector<PvdEntry> entries = parse_pvd(path);
  require_one_group(path, entries);
  for (const auto& e : entries) {
    std::error_code ec;
    if (!fs::is_regular_file(e.file, ec)) {
      throw Error({path}, "line " + std::to_string(e.line) + ": the listed file " + e.file + " does not exist");
    }
  }
  // Frames in time order; pieces of one time step in part order.
  std::stable_sort(entries.begin(), entries.end(), [](const PvdEntry& a, const PvdEntry& b) {
    return a.time != b.time ? a.time < b.time : a.part < b.part;
  });
  Plan plan;
  for (const auto& e : entries) {
    if (plan.frames.empty() || *plan.frames.back().time != e.time) plan.frames.push_back({{}, e.time});
    plan.frames.back().files.push_back(e.file);
  }
  plan.description = path + ": " + std::to_string(plan.frames.size()) + " time steps in " +
                     std::to_string(entries.size()) + " files";
  return plan;
}

bool has_glob_chars(const std::string& s) { return s.find_first_of("*?[") != std::string::npos; }

Plan plan_frames(const std::string& spec) {
  std::error_code ec;
  const fs::file_status st = fs::status(spec, ec);
  if (fs::is_directory(st)) return plan_directory(spec);
  if (fs::exists(st)) {
    if (format_of(spec) == Format::kPvd) return plan_pvd(spec);
    return {one_frame_per_file({spec}), spec};
  }
  if (has_glob_chars(spec)) return plan_glob(spec);
  throw Error({spec}, "no such file or directory");
}

// "(VTK XML unstructured grid)", or the mix.
std::string formats_of(const std::vector<FrameFiles>& frames) {
  std::vector<std::string> names;
  for (const auto& frame : frames) {
    for (const auto& file : frame.files) {
      const std::string name = format_name(require_readable(file));
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
  }
  return "(" + join(names, " + ") + ")";
}

std::string resolve_id_array(const SourceOptions& options, const std::vector<std::string>& arrays,
                             const std::string& file) {
  if (options.no_ids) return "";
  if (options.id_array.empty()) return detect_id_array(arrays);
  if (std::find(arrays.begin(), arrays.end(), options.id_array) == arrays.end()) {
    throw Error({file}, "no id array '" + options.id_array + "'; arrays in the file: " + join(arrays));
  }
  return options.id_array;
}

void require_attributes(const SourceOptions& options, const std::vector<std::string>& arrays,
                        const std::string& file) {
  for (const auto& name : options.attributes) {
    if (std::find(arrays.begin(), arrays.end(), name) == arrays.end()) {
      throw Error({file}, "no point array '" + name + "' (attribute); arrays in the file: " + join(arrays));
    }
  }
}

// The file whose point arrays stand for the series': the first of the
// first frames (at most 16) whose arrays read. A damaged first file is then
// frame 0's error when that frame is read, where --skip-bad can leave it
// out, instead of the whole input's; when none reads, the first one's error.
struct SeriesArrays {
  std::string file;
  std::vector<std::string> names;
};
SeriesArrays series_arrays(const std::vector<FrameFiles>& frames) {
  constexpr size_t kTries = 16;
  std::optional<Error> first_error;
  for (size_t f = 0; f < std::min(frames.size(), kTries); ++f) {
    try {
      const std::string& file = frames[f].files.front();
      return {file, file_arrays(file)};
    } catch (const Error& e) {
      if (!first_error) first_error = e;
    }
  }
  if (!first_error) throw Error({}, "the input holds no frames");
  throw *first_error;
}

}  // namespace

std::unique_ptr<FrameSource> open_source(const std::string& spec, const SourceOptions& options) {
  Plan plan = plan_frames(spec);
  SourceInfo info;
  info.description = plan.description + " " + formats_of(plan.frames);  // also checks every format
  for (const auto& frame : plan.frames) {
    for (const auto& file : frame.files) info.third_party_reader = info.third_party_reader || needs_vtk(require_readable(file));
  }
  SeriesArrays arrays = series_arrays(plan.frames);
  info.arrays = std::move(arrays.names);
  info.id_array = resolve_id_array(options, info.arrays, arrays.file);
  require_attributes(options, info.arrays, arrays.file);
  return std::make_unique<SeriesSource>(std::move(plan.frames), std::move(info), options);
}

void check_vtk_file(const std::string& path) {
  switch (require_readable(path)) {
    case Format::kLegacy: (void)detail::legacy_vtk_arrays(path); return;
    case Format::kVtu:
    case Format::kVtp:
    case Format::kPvtu:
    case Format::kPvtp: (void)check_xml(path); return;
    default: throw Error({path}, "not a VTK dataset file (.vtk, .vtu, .vtp, .pvtu, .pvtp)");
  }
}

std::string detect_id_array(const std::vector<std::string>& arrays) {
  static const char* const kCandidates[] = {"id",  "ids", "Id",          "ID",         "Idp",       "idp",
                                            "gid", "particle_id", "ParticleId", "ParticleID", "particleId"};
  for (const char* name : kCandidates) {
    if (std::find(arrays.begin(), arrays.end(), name) != arrays.end()) return name;
  }
  return "";
}

}  // namespace sluice::import
