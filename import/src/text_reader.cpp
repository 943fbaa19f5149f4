// CSV and XYZ particle files. Files are read whole and parsed in place with
// std::from_chars: millions of rows take well under a second per million.
#include "text_reader.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <string_view>

#include "sluice/error.h"

namespace sluice::import::detail {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

// ---------------------------------------------------------------- text basics

std::string read_whole_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw Error({path}, std::string("cannot open: ") + std::strerror(errno));
  std::string text;
  char buf[1 << 16];
  size_t got = 0;
  while ((got = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, got);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw Error({path}, "read error");
  return text;
}

// Splits text into lines without copying; strips a trailing '\r'.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") text_.remove_prefix(3);  // UTF-8 BOM
  }
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    line = text_.substr(pos_, end - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end + 1;
    ++number_;
    return true;
  }
  uint64_t number() const { return number_; }  // 1-based number of the last line returned

 private:
  std::string_view text_;
  size_t pos_ = 0;
  uint64_t number_ = 0;
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

std::string_view unquote(std::string_view s) {
  s = trim(s);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

bool is_blank(std::string_view line) { return trim(line).empty(); }

// A number as a whole field; from_chars rejects a leading '+', we accept it.
bool parse_double(std::string_view s, double& out) {
  s = unquote(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && end == s.data() + s.size();
}

// A particle id: a non-negative integer, also written as an integral float.
bool parse_id(std::string_view s, uint64_t& out) {
  s = unquote(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  if (ec == std::errc() && end == s.data() + s.size()) return true;
  double d = 0;
  if (!parse_double(s, d)) return false;
  if (!(d >= 0.0 && d < 18446744073709551616.0) || std::floor(d) != d) return false;
  out = static_cast<uint64_t>(d);
  return true;
}

std::string join(const std::vector<std::string>& names) {
  if (names.empty()) return "(none)";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

[[noreturn]] void fail_line(const std::string& path, uint64_t line, const std::string& msg) {
  throw Error({path}, "line " + std::to_string(line) + ": " + msg);
}

// ----------------------------------------------------------- column roles

// What a column feeds (the id column may also be a requested attribute).
// Attributes may span several columns (vector components), whose squares
// are summed and rooted.
struct ColumnRole {
  int axis = -1;       // 0..2 for x, y, z
  int attribute = -1;  // index among the requested attributes
  bool id = false;
};

struct ArrayColumns {
  std::string name;
  std::vector<size_t> columns;  // one per component
};

struct Layout {
  std::vector<ColumnRole> roles;  // one per column
  std::vector<int> components;    // per requested attribute
};

// Maps requested names onto columns; throws listing what exists.
Layout make_layout(const std::string& path, size_t ncols, const size_t pos_cols[3],
                   const std::vector<ArrayColumns>& arrays, const std::vector<std::string>& attributes,
                   const std::string& id_array) {
  Layout layout;
  layout.roles.resize(ncols);
  for (int axis = 0; axis < 3; ++axis) layout.roles[pos_cols[axis]].axis = axis;
  const auto find = [&](const std::string& name) -> const ArrayColumns* {
    for (const auto& a : arrays) {
      if (a.name == name) return &a;
    }
    return nullptr;
  };
  const auto names = [&] {
    std::vector<std::string> out;
    for (const auto& a : arrays) out.push_back(a.name);
    return out;
  };
  if (!id_array.empty()) {
    const ArrayColumns* a = find(id_array);
    if (!a) throw Error({path}, "no id column '" + id_array + "'; columns: " + join(names()));
    if (a->columns.size() != 1) throw Error({path}, "id array '" + id_array + "' has several components");
    layout.roles[a->columns[0]].id = true;
  }
  for (size_t k = 0; k < attributes.size(); ++k) {
    const ArrayColumns* a = find(attributes[k]);
    if (!a) throw Error({path}, "no array '" + attributes[k] + "'; arrays: " + join(names()));
    for (size_t c : a->columns) layout.roles[c].attribute = static_cast<int>(k);
    layout.components.push_back(static_cast<int>(a->columns.size()));
  }
  return layout;
}

// Accumulates one row at a time into the frame.
class RowSink {
 public:
  RowSink(const Layout& layout, bool with_ids, size_t nattr)
      : layout_(layout), with_ids_(with_ids), acc_(nattr, 0.0) {
    frame_.attributes.resize(nattr);
  }
  // Feeds field `col` of the current row; returns false if it is not a number.
  bool field(size_t col, std::string_view text) {
    const ColumnRole& role = layout_.roles[col];
    if (role.id && !parse_id(text, id_)) return false;
    if (role.axis < 0 && role.attribute < 0) return true;
    double v = 0;
    if (!parse_double(text, v)) return false;
    if (role.axis >= 0) {
      xyz_[role.axis] = v;
    } else if (layout_.components[role.attribute] == 1) {
      acc_[role.attribute] = v;
    } else {
      acc_[role.attribute] += v * v;
    }
    return true;
  }
  void end_row() {
    for (double v : xyz_) frame_.positions.push_back(static_cast<float>(v));
    if (with_ids_) frame_.ids.push_back(id_);
    for (size_t k = 0; k < acc_.size(); ++k) {
      const double v = layout_.components[k] == 1 ? acc_[k] : std::sqrt(acc_[k]);
      frame_.attributes[k].push_back(static_cast<float>(v));
      acc_[k] = 0.0;
    }
  }
  void reserve(size_t rows) {
    frame_.positions.reserve(rows * 3);
    if (with_ids_) frame_.ids.reserve(rows);
    for (auto& a : frame_.attributes) a.reserve(rows);
  }
  ParticleFrame take() { return std::move(frame_); }

 private:
  const Layout& layout_;
  bool with_ids_;
  double xyz_[3] = {0, 0, 0};
  uint64_t id_ = 0;
  std::vector<double> acc_;
  ParticleFrame frame_;
};

std::string describe_bad_field(const Layout& layout, const std::vector<std::string>& column_names, size_t col,
                               std::string_view text) {
  const bool is_id = layout.roles[col].id;
  return "'" + std::string(trim(text)) + "' in column '" + column_names[col] + "' is not " +
         (is_id ? "a non-negative integer id" : "a number");
}

// ------------------------------------------------------------------- CSV

struct CsvHeader {
  char delimiter = ',';
  std::vector<std::string> columns;
  size_t pos_cols[3] = {0, 0, 0};
  std::vector<ArrayColumns> arrays;  // non-position columns, vectors grouped
};

// Next field of a delimited line starting at `pos`; a quoted field may
// contain the delimiter. Advances `pos` past the delimiter.
std::string_view next_field(std::string_view line, size_t& pos, char delim) {
  const size_t start = pos;
  size_t scan = pos;
  while (scan < line.size() && is_space(line[scan])) ++scan;
  if (scan < line.size() && line[scan] == '"') {
    const size_t close = line.find('"', scan + 1);
    if (close != std::string_view::npos) scan = close + 1;
  }
  size_t end = line.find(delim, scan);
  if (end == std::string_view::npos) end = line.size();
  pos = end + 1;
  return line.substr(start, end - start);
}

std::vector<std::string> split_fields(std::string_view line, char delim) {
  std::vector<std::string> out;
  size_t pos = 0;
  while (pos <= line.size()) out.emplace_back(unquote(next_field(line, pos, delim)));
  return out;
}

// "velocity:2" -> ("velocity", 2); other names -> (name, -1).
std::pair<std::string, long> split_component(const std::string& name) {
  const size_t colon = name.rfind(':');
  if (colon == std::string::npos || colon + 1 == name.size()) return {name, -1};
  long comp = 0;
  const char* first = name.data() + colon + 1;
  const char* last = name.data() + name.size();
  const auto [end, ec] = std::from_chars(first, last, comp);
  if (ec != std::errc() || end != last) return {name, -1};
  return {name.substr(0, colon), comp};
}

bool find_positions(const std::vector<std::string>& columns, size_t out[3]) {
  static const char* const kNames[2][3] = {{"x", "y", "z"}, {"points:0", "points:1", "points:2"}};
  for (const auto& names : kNames) {
    int found = 0;
    for (int axis = 0; axis < 3; ++axis) {
      for (size_t c = 0; c < columns.size(); ++c) {
        if (lower(columns[c]) == names[axis]) {
          out[axis] = c;
          ++found;
          break;
        }
      }
    }
    if (found == 3) return true;
  }
  return false;
}

// Groups non-position columns into arrays, keeping first-appearance order:
// ParaView's component columns name:0, name:1, ... form one array `name`.
std::vector<ArrayColumns> group_arrays(const std::vector<std::string>& columns, const size_t pos_cols[3]) {
  std::vector<ArrayColumns> arrays;
  std::vector<bool> is_vector;  // per entry of `arrays`
  for (size_t c = 0; c < columns.size(); ++c) {
    if (c == pos_cols[0] || c == pos_cols[1] || c == pos_cols[2]) continue;
    const auto [base, comp] = split_component(columns[c]);
    const bool component = comp >= 0;
    size_t k = 0;
    while (k < arrays.size() && !(component && is_vector[k] && arrays[k].name == base)) ++k;
    if (k == arrays.size()) {
      arrays.push_back({base, {}});
      is_vector.push_back(component);
    }
    arrays[k].columns.push_back(c);
  }
  return arrays;
}

CsvHeader parse_header(const std::string& path, std::string_view line, uint64_t line_no) {
  CsvHeader h;
  h.delimiter = line.find(',') != std::string_view::npos ? ',' : (line.find('\t') != std::string_view::npos ? '\t' : ',');
  h.columns = split_fields(line, h.delimiter);
  if (!find_positions(h.columns, h.pos_cols)) {
    fail_line(path, line_no,
              "no position columns in the header (looked for x, y, z or Points:0, Points:1, Points:2); columns: " +
                  join(h.columns));
  }
  h.arrays = group_arrays(h.columns, h.pos_cols);
  return h;
}

std::vector<std::string> array_names(const std::vector<ArrayColumns>& arrays) {
  std::vector<std::string> out;
  for (const auto& a : arrays) out.push_back(a.name);
  return out;
}

// Reads lines of a file until `want` accepts one; for the cheap array listing.
template <class Want>
bool first_line_where(const std::string& path, Want want, std::string& line, uint64_t& line_no) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error({path}, std::string("cannot open: ") + std::strerror(errno));
  line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (want(line)) return true;
  }
  return false;
}

// ------------------------------------------------------------------- XYZ

// Drops a `#` comment.
std::string_view strip_comment(std::string_view line) {
  const size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

// Next whitespace-separated token at or after `pos`; empty at the end.
std::string_view next_token(std::string_view line, size_t& pos) {
  while (pos < line.size() && is_space(line[pos])) ++pos;
  const size_t start = pos;
  while (pos < line.size() && !is_space(line[pos])) ++pos;
  return line.substr(start, pos - start);
}

size_t count_tokens(std::string_view line) {
  size_t pos = 0;
  size_t n = 0;
  while (!next_token(line, pos).empty()) ++n;
  return n;
}

std::vector<ArrayColumns> xyz_columns(size_t ncols) {
  std::vector<ArrayColumns> arrays;
  for (size_t c = 3; c < ncols; ++c) arrays.push_back({"col" + std::to_string(c + 1), {c}});
  return arrays;
}

}  // namespace

// --------------------------------------------------------------- public API

std::vector<std::string> csv_arrays(const std::string& path) {
  std::string line;
  uint64_t line_no = 0;
  if (!first_line_where(path, [](const std::string& l) { return !is_blank(l); }, line, line_no)) return {};
  return array_names(parse_header(path, line, line_no).arrays);
}

ParticleFrame read_csv(const std::string& path, const std::vector<std::string>& attributes,
                       const std::string& id_array) {
  const std::string text = read_whole_file(path);
  LineCursor lines(text);
  std::string_view line;
  while (lines.next(line) && is_blank(line)) {
  }
  if (is_blank(line)) return ParticleFrame{};  // an empty file: no points
  const CsvHeader header = parse_header(path, line, lines.number());
  const size_t ncols = header.columns.size();
  const Layout layout = make_layout(path, ncols, header.pos_cols, header.arrays, attributes, id_array);
  RowSink sink(layout, !id_array.empty(), attributes.size());
  sink.reserve(static_cast<size_t>(std::count(text.begin(), text.end(), '\n')));
  while (lines.next(line)) {
    if (is_blank(line)) continue;
    size_t pos = 0;
    size_t col = 0;
    while (pos <= line.size()) {
      const std::string_view field = next_field(line, pos, header.delimiter);
      if (col < ncols && !sink.field(col, field)) {
        fail_line(path, lines.number(), describe_bad_field(layout, header.columns, col, field));
      }
      ++col;
    }
    if (col != ncols) {
      fail_line(path, lines.number(),
                std::to_string(col) + " fields, but the header has " + std::to_string(ncols) + " columns");
    }
    sink.end_row();
  }
  return sink.take();
}

std::vector<std::string> xyz_arrays(const std::string& path) {
  std::string line;
  uint64_t line_no = 0;
  const auto is_data = [](const std::string& l) { return !is_blank(strip_comment(l)); };
  if (!first_line_where(path, is_data, line, line_no)) return {};
  return array_names(xyz_columns(count_tokens(strip_comment(line))));
}

ParticleFrame read_xyz(const std::string& path, const std::vector<std::string>& attributes,
                       const std::string& id_array) {
  const std::string text = read_whole_file(path);
  LineCursor lines(text);
  std::string_view line;
  size_t ncols = 0;
  std::vector<std::string> column_names;
  std::optional<Layout> layout;
  std::optional<RowSink> sink;
  while (lines.next(line)) {
    line = strip_comment(line);
    if (is_blank(line)) continue;
    if (!layout) {
      // The first data line fixes the column count.
      ncols = count_tokens(line);
      if (ncols < 3) {
        fail_line(path, lines.number(), "expected at least 3 numbers (x y z), found " + std::to_string(ncols));
      }
      for (size_t c = 0; c < ncols; ++c) column_names.push_back("col" + std::to_string(c + 1));
      const size_t pos_cols[3] = {0, 1, 2};
      layout = make_layout(path, ncols, pos_cols, xyz_columns(ncols), attributes, id_array);
      sink.emplace(*layout, !id_array.empty(), attributes.size());
      sink->reserve(static_cast<size_t>(std::count(text.begin(), text.end(), '\n')));
    }
    size_t pos = 0;
    size_t col = 0;
    for (std::string_view tok = next_token(line, pos); !tok.empty(); tok = next_token(line, pos), ++col) {
      if (col < ncols && !sink->field(col, tok)) {
        std::string msg = describe_bad_field(*layout, column_names, col, tok);
        if (lines.number() == 1) msg += " (XYZ files have no header; use .csv for named columns)";
        fail_line(path, lines.number(), msg);
      }
    }
    if (col != ncols) {
      fail_line(path, lines.number(),
                std::to_string(col) + " columns, but the first data line has " + std::to_string(ncols));
    }
    sink->end_row();
  }
  return sink ? sink->take() : ParticleFrame{};
}

}  // namespace sluice::import::detail
