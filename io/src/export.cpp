// Exporters: a frame's particles to .vtp (+ .pvd), .csv and .ply, and the
// helpers that get them out of a decoded frame.
#include "sluice/io/export.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "sluice/io/codec.h"
#include "sluice/error.h"

namespace sluice::io {
namespace {

// The binary writers copy host values as they are.
static_assert(std::endian::native == std::endian::little, "the exporters assume a little-endian host");

// ------------------------------------------------------------ output files

// Writes `path`.partial and renames it onto `path` on commit(); removes the
// partial file if it is never committed (an error on the way).
class OutputFile {
 public:
  explicit OutputFile(std::string path) : path_(std::move(path)), partial_(path_ + ".partial") {
    file_ = std::fopen(partial_.c_str(), "wb");
    if (!file_) fail("cannot create " + partial_);
    buffer_.reserve(kBufferBytes);
  }
  ~OutputFile() {
    if (!file_) return;
    std::fclose(file_);
    std::remove(partial_.c_str());
  }
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(const void* data, size_t bytes) {
    const auto* p = static_cast<const char*>(data);
    if (buffer_.size() + bytes > kBufferBytes) flush();
    if (bytes >= kBufferBytes) {
      put(p, bytes);
    } else {
      buffer_.insert(buffer_.end(), p, p + bytes);
    }
  }
  void write(std::string_view s) { write(s.data(), s.size()); }
  template <class T>
  void write_value(T v) {
    write(&v, sizeof v);
  }

  // Closes the file, checks every byte reached it and moves it into place.
  uint64_t commit() {
    flush();
    std::FILE* f = file_;
    file_ = nullptr;
    if (std::fclose(f) != 0) {
      const int e = errno;
      std::remove(partial_.c_str());
      fail("write failed", e);
    }
    if (std::rename(partial_.c_str(), path_.c_str()) != 0) {
      const int e = errno;
      std::remove(partial_.c_str());
      fail("cannot rename " + partial_ + " to it", e);
    }
    return bytes_;
  }

  [[noreturn]] void fail(const std::string& what, int error = errno) const {
    throw Error({path_}, what + ": " + std::strerror(error));
  }

 private:
  static constexpr size_t kBufferBytes = size_t(1) << 20;

  void flush() {
    put(buffer_.data(), buffer_.size());
    buffer_.clear();
  }
  void put(const char* p, size_t bytes) {
    if (bytes == 0) return;
    if (std::fwrite(p, 1, bytes, file_) != bytes) fail("write failed");
    bytes_ += bytes;
  }

  std::string path_, partial_;
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
  uint64_t bytes_ = 0;
};

// ------------------------------------------------------------ validation

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Array sizes agree and `names` (as the format will write them) neither
// repeat nor take the writers' own column names.
void check_frame(const std::string& path, const ExportFrame& frame, const std::vector<std::string>& names) {
  const uint64_t n = frame.count();
  if (frame.positions.size() != 3 * n) {
    throw Error({path}, "export frame has " + std::to_string(frame.positions.size()) + " coordinates for " +
                            std::to_string(n) + " LOD values");
  }
  if (frame.attribute_names.size() != frame.attributes.size()) {
    throw Error({path}, "export frame has " + std::to_string(frame.attributes.size()) + " attribute arrays but " +
                            std::to_string(frame.attribute_names.size()) + " names");
  }
  for (size_t a = 0; a < frame.attributes.size(); ++a) {
    if (frame.attributes[a].size() != n) {
      throw Error({path}, "attribute '" + frame.attribute_names[a] + "' has " +
                              std::to_string(frame.attributes[a].size()) + " values for " + std::to_string(n) +
                              " particles");
    }
  }
  for (size_t a = 0; a < names.size(); ++a) {
    const std::string l = lower(names[a]);
    if (names[a].empty()) throw Error({path}, "an attribute has an empty name");
    if (l == "x" || l == "y" || l == "z" || l == "lod") {
      throw Error({path}, "attribute '" + names[a] + "' clashes with the exported column of that name");
    }
    for (size_t b = 0; b < a; ++b) {
      if (names[b] == names[a]) throw Error({path}, "attribute name '" + names[a] + "' appears twice");
    }
  }
}

// ------------------------------------------------------------ text helpers

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

// Shortest text that parses back to exactly `v`.
template <class T>
std::string shortest(T v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// A CSV header field, quoted (quotes doubled) when it holds a delimiter,
// a quote or white space.
std::string csv_field(const std::string& name) {
  if (name.find_first_of(",\"\t\r\n ") == std::string::npos) return name;
  std::string out = "\"";
  for (char c : name) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string ply_name(const std::string& name) {
  std::string out = name;
  for (char& c : out) {
    if (std::isspace(static_cast<unsigned char>(c)) || !std::isprint(static_cast<unsigned char>(c))) c = '_';
  }
  return out;
}

// ------------------------------------------------------------ .vtp pieces

// One block of the appended section: its XML declaration and its bytes.
struct AppendedArray {
  std::string type;  // VTK type name
  std::string name;
  int components = 1;
  uint64_t bytes = 0;
};

std::string data_array_xml(const AppendedArray& a, uint64_t offset, const char* indent, bool tuples) {
  std::string s = std::string(indent) + "<DataArray type=\"" + a.type + "\" Name=\"" + xml_escape(a.name) + "\"";
  if (a.components != 1) s += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
  if (tuples) s += " NumberOfTuples=\"1\"";
  return s + " format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
}

// Writes `count` Int64 values f(0), f(1), ... without holding them all.
template <class F>
void write_int64_sequence(OutputFile& out, uint64_t count, F f) {
  std::array<int64_t, 8192> block;
  for (uint64_t first = 0; first < count; first += block.size()) {
    const size_t n = size_t(std::min<uint64_t>(block.size(), count - first));
    for (size_t k = 0; k < n; ++k) block[k] = f(int64_t(first + k));
    out.write(block.data(), n * sizeof(int64_t));
  }
}

}  // namespace

// ------------------------------------------------------------ decoded -> plain

ExportFrame to_export_frame(const DecodedFrame& frame, const FileHeader& header, std::span<const size_t> attributes) {
  ExportFrame out;
  out.positions = world_positions(frame, header.position_coding);
  out.lod = lod_values_of(frame, header.position_coding);
  out.time = frame.header.time;
  for (const size_t a : attributes) {
    if (a >= header.attributes.size() || a >= frame.attributes.size()) {
      throw Error({}, "attribute " + std::to_string(a) + " requested; the file has " +
                          std::to_string(header.attributes.size()));
    }
    std::vector<float> values(out.lod.size());
    for (size_t c = 0; c < frame.header.chunks.size(); ++c) {
      const ChunkDesc& chunk = frame.header.chunks[c];
      const auto [lo, hi] = chunk.attribute_ranges[a];
      for (uint64_t i = frame.chunk_first[c]; i < frame.chunk_first[c] + chunk.particle_count; ++i) {
        values[i] = dequantize(frame.attributes[a][i], lo, hi);
      }
    }
    out.attribute_names.push_back(header.attributes[a].name);
    out.attributes.push_back(std::move(values));
  }
  return out;
}

// ------------------------------------------------------------ thinning

bool lod_keeps(uint16_t value, float level) {
  // render::lod_keep(level, 1.0f, lod_uniform(value)), operation for operation.
  const float u = (float(value) + 0.5f) * (1.0f / 65536.0f);
  const float threshold = level > 0 ? -std::log(std::min(level, 1.0f)) : 1e30f;
  return 1.0f * -std::log(1.0f - u) >= threshold;
}

void thin_by_lod(ExportFrame& frame, float level) {
  // One decision per possible value, then a stable compaction.
  std::vector<uint8_t> keeps(65536);
  for (uint32_t v = 0; v < 65536; ++v) keeps[v] = lod_keeps(uint16_t(v), level) ? 1 : 0;
  const uint64_t n = frame.count();
  uint64_t kept = 0;
  for (uint64_t i = 0; i < n; ++i) {
    if (!keeps[frame.lod[i]]) continue;
    if (kept != i) {
      std::copy_n(&frame.positions[3 * i], 3, &frame.positions[3 * kept]);
      frame.lod[kept] = frame.lod[i];
      for (auto& a : frame.attributes) a[kept] = a[i];
    }
    ++kept;
  }
  frame.positions.resize(3 * kept);
  frame.lod.resize(kept);
  for (auto& a : frame.attributes) a.resize(kept);
}

// ------------------------------------------------------------ formats

std::optional<ExportFormat> export_format_of(const std::string& path) {
  const size_t dot = path.find_last_of("./");
  if (dot == std::string::npos || path[dot] != '.') return std::nullopt;
  const std::string ext = lower(path.substr(dot));
  if (ext == ".vtp") return ExportFormat::Vtp;
  if (ext == ".csv") return ExportFormat::Csv;
  if (ext == ".ply") return ExportFormat::Ply;
  return std::nullopt;
}

uint64_t write_vtp(const std::string& path, const ExportFrame& frame) {
  check_frame(path, frame, frame.attribute_names);
  const uint64_t n = frame.count();
  // Appended blocks in the order they are written: field data, point data,
  // points, verts. Each is a UInt64 byte count followed by the bytes.
  std::vector<AppendedArray> blocks = {{"Float64", "TimeValue", 1, 8}, {"UInt16", "lod", 1, 2 * n}};
  for (const auto& name : frame.attribute_names) blocks.push_back({"Float32", name, 1, 4 * n});
  blocks.push_back({"Float32", "Points", 3, 12 * n});
  blocks.push_back({"Int64", "connectivity", 1, 8 * n});
  blocks.push_back({"Int64", "offsets", 1, 8 * n});
  std::vector<uint64_t> offsets;
  uint64_t offset = 0;
  for (const auto& b : blocks) {
    offsets.push_back(offset);
    offset += 8 + b.bytes;
  }
  const size_t points = blocks.size() - 3;
  // What ParaView colours by when the file opens.
  const std::string active = frame.attribute_names.empty() ? "lod" : frame.attribute_names.front();

  std::string xml =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      "  <PolyData>\n"
      "    <FieldData>\n" +
      data_array_xml(blocks[0], offsets[0], "      ", true) +
      "    </FieldData>\n"
      "    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfVerts=\"" + std::to_string(n) +
      "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n"
      "      <PointData Scalars=\"" + xml_escape(active) + "\">\n";
  for (size_t k = 1; k < points; ++k) xml += data_array_xml(blocks[k], offsets[k], "        ", false);
  xml += "      </PointData>\n      <Points>\n" + data_array_xml(blocks[points], offsets[points], "        ", false) +
         "      </Points>\n      <Verts>\n" + data_array_xml(blocks[points + 1], offsets[points + 1], "        ", false) +
         data_array_xml(blocks[points + 2], offsets[points + 2], "        ", false) +
         "      </Verts>\n    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";

  OutputFile out(path);
  out.write(xml);
  size_t k = 0;
  out.write_value(blocks[k++].bytes);
  out.write_value(frame.time);
  out.write_value(blocks[k++].bytes);
  out.write(frame.lod.data(), 2 * n);
  for (const auto& a : frame.attributes) {
    out.write_value(blocks[k++].bytes);
    out.write(a.data(), 4 * n);
  }
  out.write_value(blocks[k++].bytes);
  out.write(frame.positions.data(), 12 * n);
  out.write_value(blocks[k++].bytes);
  write_int64_sequence(out, n, [](int64_t i) { return i; });      // vertex i is point i
  out.write_value(blocks[k++].bytes);
  write_int64_sequence(out, n, [](int64_t i) { return i + 1; });  // end of each one-point cell
  out.write("\n  </AppendedData>\n</VTKFile>\n");
  return out.commit();
}

uint64_t write_csv(const std::string& path, const ExportFrame& frame) {
  check_frame(path, frame, frame.attribute_names);
  OutputFile out(path);
  std::string header = "x,y,z,lod";
  for (const auto& name : frame.attribute_names) header.append(",").append(csv_field(name));
  out.write(header.append("\n"));
  // Rows are formatted into a block of text and written a block at a time.
  std::string block;
  char buf[64];
  const auto field = [&](auto v, char after) {
    const auto r = std::to_chars(buf, buf + sizeof buf - 1, v);
    *r.ptr = after;
    block.append(buf, r.ptr + 1);
  };
  for (uint64_t i = 0; i < frame.count(); ++i) {
    for (int a = 0; a < 3; ++a) field(frame.positions[3 * i + a], ',');
    field(frame.lod[i], frame.attributes.empty() ? '\n' : ',');
    for (size_t a = 0; a < frame.attributes.size(); ++a) {
      field(frame.attributes[a][i], a + 1 == frame.attributes.size() ? '\n' : ',');
    }
    if (block.size() > (size_t(1) << 20)) {
      out.write(block);
      block.clear();
    }
  }
  out.write(block);
  return out.commit();
}

uint64_t write_ply(const std::string& path, const ExportFrame& frame) {
  std::vector<std::string> names;
  for (const auto& name : frame.attribute_names) names.push_back(ply_name(name));
  check_frame(path, frame, names);
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by sluice export\ncomment time " +
                       shortest(frame.time) + "\nelement vertex " + std::to_string(frame.count()) +
                       "\nproperty float x\nproperty float y\nproperty float z\nproperty ushort lod\n";
  for (const auto& name : names) header += "property float " + name + "\n";
  header += "end_header\n";

  OutputFile out(path);
  out.write(header);
  // Vertices are interleaved records, packed: 12 + 2 + 4 per attribute bytes.
  const size_t record = 14 + 4 * frame.attributes.size();
  std::vector<char> block;
  block.reserve(record * 4096);
  for (uint64_t i = 0; i < frame.count(); ++i) {
    const size_t at = block.size();
    block.resize(at + record);
    char* p = block.data() + at;
    std::memcpy(p, &frame.positions[3 * i], 12);
    std::memcpy(p + 12, &frame.lod[i], 2);
    for (size_t a = 0; a < frame.attributes.size(); ++a) std::memcpy(p + 14 + 4 * a, &frame.attributes[a][i], 4);
    if (block.size() + record > block.capacity()) {
      out.write(block.data(), block.size());
      block.clear();
    }
  }
  out.write(block.data(), block.size());
  return out.commit();
}

uint64_t write_export(const std::string& path, const ExportFrame& frame, ExportFormat format) {
  switch (format) {
    case ExportFormat::Vtp: return write_vtp(path, frame);
    case ExportFormat::Csv: return write_csv(path, frame);
    case ExportFormat::Ply: return write_ply(path, frame);
  }
  throw Error({path}, "unknown export format");
}

uint64_t write_pvd(const std::string& path, std::span<const PvdEntry> entries) {
  std::string xml =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const PvdEntry& e : entries) {
    xml += "    <DataSet timestep=\"" + shortest(e.time) + "\" part=\"0\" file=\"" + xml_escape(e.file) + "\"/>\n";
  }
  xml += "  </Collection>\n</VTKFile>\n";
  OutputFile out(path);
  out.write(xml);
  return out.commit();
}

}  // namespace sluice::io
