// Legacy VTK files: the structure is walked once, keyword by keyword; each
// data section's size is checked against what remains of the file before it
// is read, skipped or allocated. Wanted arrays are kept as host-endian typed
// values and converted into the frame at the end.
#include "legacy_vtk.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <set>
#include <string_view>
#include <type_traits>

#include "byte_stream.h"
#include "cell_types.h"
#include "values.h"

namespace sluice::import::detail {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

// ------------------------------------------------------------------ types

enum class Scalar { kBit, kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64 };

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// Bytes of one value in a binary file (a bit array packs 8 per byte).
uint64_t value_bytes(Scalar s) {
  switch (s) {
    case Scalar::kBit:
    case Scalar::kI8:
    case Scalar::kU8: return 1;
    case Scalar::kI16:
    case Scalar::kU16: return 2;
    case Scalar::kI32:
    case Scalar::kU32:
    case Scalar::kF32: return 4;
    case Scalar::kI64:
    case Scalar::kU64:
    case Scalar::kF64: return 8;
  }
  return 1;
}

// Calls f(T{}) with the C++ type values of `s` are held as (bits as uint8).
template <class F>
decltype(auto) visit(Scalar s, F&& f) {
  switch (s) {
    case Scalar::kI8: return f(int8_t{});
    case Scalar::kBit:
    case Scalar::kU8: return f(uint8_t{});
    case Scalar::kI16: return f(int16_t{});
    case Scalar::kU16: return f(uint16_t{});
    case Scalar::kI32: return f(int32_t{});
    case Scalar::kU32: return f(uint32_t{});
    case Scalar::kI64: return f(int64_t{});
    case Scalar::kU64: return f(uint64_t{});
    case Scalar::kF32: return f(float{});
    case Scalar::kF64: return f(double{});
  }
  return f(uint8_t{});
}

// A typed, host-endian run of values. float32 values (points and most
// arrays) are read straight into `floats`, which the frame then takes over;
// other types into `bytes`.
struct Values {
  Scalar type = Scalar::kF32;
  uint64_t count = 0;
  std::vector<float> floats;         // type kF32
  std::vector<unsigned char> bytes;  // other types: count values of the type's C++ type

  template <class T>
  const T* as() const {
    if constexpr (std::is_same_v<T, float>) {
      if (type == Scalar::kF32) return floats.data();
    }
    return reinterpret_cast<const T*>(bytes.data());
  }
  unsigned char* storage() {
    return type == Scalar::kF32 ? reinterpret_cast<unsigned char*>(floats.data()) : bytes.data();
  }
  void allocate(Scalar t, uint64_t n) {
    type = t;
    count = n;
    if (t == Scalar::kF32) floats.resize(n);
    else bytes.resize(n * value_bytes(t));
  }
};

// A point (or field) array of the file.
struct Array {
  std::string name;
  uint64_t components = 1;
  uint64_t tuples = 0;
  Values values;  // filled only when the array was wanted
};

// A word of the file as a message quotes it: at most 40 characters, bytes
// that are not printable shown as '?'.
std::string shown(std::string_view w) {
  std::string out(w.substr(0, 40));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  }
  return out;
}

// Names in legacy files encode special characters as %XX.
std::string decode_name(std::string_view s) {
  std::string out;
  for (size_t k = 0; k < s.size(); ++k) {
    if (s[k] == '%' && k + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[k + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[k + 2]))) {
      out += static_cast<char>(std::stoi(std::string(s.substr(k + 1, 2)), nullptr, 16));
      k += 2;
    } else {
      out += s[k];
    }
  }
  return out;
}

template <class T>
T byteswap(T v) {
  if constexpr (sizeof(T) == 1) {
    return v;
  } else {
    std::array<unsigned char, sizeof(T)> b;
    std::memcpy(b.data(), &v, sizeof(T));
    std::reverse(b.begin(), b.end());
    std::memcpy(&v, b.data(), sizeof(T));
    return v;
  }
}

// Big-endian file values to host order, in place.
template <class T>
void to_host(unsigned char* bytes, uint64_t count) {
  if constexpr (sizeof(T) > 1 && std::endian::native == std::endian::little) {
    T* v = reinterpret_cast<T*>(bytes);
    for (uint64_t k = 0; k < count; ++k) v[k] = byteswap(v[k]);
  }
}

std::string join(const std::vector<std::string>& names) {
  if (names.empty()) return "(none)";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

std::string type_word(Scalar s) {
  switch (s) {
    case Scalar::kBit: return "bit";
    case Scalar::kI8: return "char";
    case Scalar::kU8: return "unsigned_char";
    case Scalar::kI16: return "short";
    case Scalar::kU16: return "unsigned_short";
    case Scalar::kI32: return "int";
    case Scalar::kU32: return "unsigned_int";
    case Scalar::kI64: return "vtktypeint64";
    case Scalar::kU64: return "vtktypeuint64";
    case Scalar::kF32: return "float";
    case Scalar::kF64: return "double";
  }
  return "?";
}

// -------------------------------------------------------------- the parser

class Parser {
 public:
  // `wanted`: point arrays whose values are kept; `read_values`: false when only
  // the names are wanted (positions are not read either).
  Parser(const std::string& path, std::vector<std::string> wanted, bool read_values)
      : in_(path), wanted_(std::move(wanted)), read_values_(read_values) {}

  void run() {
    header();
    body();
    finish();
  }

  // ---------------------------------------------------------- results
  std::vector<std::string> point_arrays;
  std::vector<Array> kept;  // wanted point arrays found, in file order
  std::optional<double> time;
  uint64_t point_count = 0;
  std::set<int64_t> ignored_cell_types;
  std::vector<std::string> ignored_sections;  // POLYDATA sections other than VERTICES

  // Positions, as float xyz (float32 points are handed over, not copied).
  std::vector<float> take_positions() {
    if (points_.type == Scalar::kF32 && points_.count == point_count * 3 && dataset_ != "structured_points" &&
        dataset_ != "rectilinear_grid") {
      return std::move(points_.floats);
    }
    std::vector<float> out(point_count * 3);
    if (point_count == 0) return out;
    if (dataset_ == "structured_points") {
      generate_image(out);
    } else if (dataset_ == "rectilinear_grid") {
      generate_rectilinear(out);
    } else {
      visit(points_.type, [&](auto t) { convert_values(points_.as<decltype(t)>(), out.size(), out.data()); });
    }
    return out;
  }

  const std::string& path() const { return in_.path(); }

 private:
  [[noreturn]] void fail(const std::string& section, const std::string& what) const {
    throw Error({in_.path()}, section + ": " + what);
  }

  // "line 12" in text files, "byte 4096" in binary ones.
  std::string here() const {
    return binary_ ? "byte " + std::to_string(in_.offset()) : "line " + std::to_string(in_.line_number());
  }

  // The next word, which must be there: the end of the file here means it
  // was cut short.
  std::string_view need(const std::string& section) {
    const std::string_view w = in_.word();
    if (w.empty()) fail(section, "the file ends at byte " + std::to_string(in_.offset()) + " (cut short)");
    return w;
  }

  // ------------------------------------------------------------ header
  void header() {
    const std::string first(in_.line());
    if (lower(first).rfind("# vtk datafile", 0) != 0) {
      throw Error({in_.path()}, "not a legacy VTK file: the first line must be '# vtk DataFile Version x.y', found '" +
                                    shown(first) + "'");
    }
    const size_t version = lower(first).find("version");
    if (version != std::string::npos) {
      const char* p = first.data() + version + 7;
      while (*p == ' ') ++p;
      std::from_chars(p, first.data() + first.size(), major_);
    }
    (void)in_.line();  // the title
    const std::string mode = lower(need("header"));
    if (mode != "ascii" && mode != "binary") fail("header", "line 3 must say ASCII or BINARY, found '" + mode + "'");
    binary_ = mode == "binary";
    if (lower(need("header")) != "dataset") fail("header", "expected 'DATASET type' after " + mode);
    dataset_ = lower(need("header"));
    static const std::set<std::string> kDatasets = {"polydata", "unstructured_grid", "structured_grid",
                                                    "structured_points", "rectilinear_grid"};
    if (!kDatasets.count(dataset_)) {
      fail("DATASET", "'" + dataset_ +
                          "' is not a dataset with points (expected POLYDATA, UNSTRUCTURED_GRID, STRUCTURED_GRID, "
                          "STRUCTURED_POINTS or RECTILINEAR_GRID)");
    }
  }

  // -------------------------------------------------------------- body
  void body() {
    for (;;) {
      const std::string_view word = in_.word();
      if (word.empty()) return;
      const std::string key = lower(word);
      if (key == "points") points();
      else if (key == "dimensions") dimensions();
      else if (key == "origin") text_numbers("ORIGIN", origin_);
      else if (key == "spacing" || key == "aspect_ratio") text_numbers("SPACING", spacing_);
      else if (key == "x_coordinates" || key == "y_coordinates" || key == "z_coordinates") coordinates(key);
      else if (key == "vertices" || key == "lines" || key == "polygons" || key == "triangle_strips" ||
               key == "cells") cells(key);
      else if (key == "cell_types") cell_types();
      else if (key == "point_data") attribute_section(true);
      else if (key == "cell_data") attribute_section(false);
      else if (key == "field") field(section_ == Section::kDataset ? "FIELD" : section_name() + " FIELD");
      else if (key == "metadata") metadata();
      else if (section_ != Section::kDataset && attribute(key)) continue;
      else fail(here(), "unexpected '" + shown(word) + "' (not a legacy VTK keyword here)");
    }
  }

  // A count written as text: a non-negative integer.
  uint64_t count(const std::string& section, const char* what) {
    const std::string_view w = need(section);
    uint64_t v = 0;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
    if (w.empty() || ec != std::errc() || end != w.data() + w.size()) {
      fail(section, std::string("expected ") + what + " (a non-negative integer), found '" +
                        shown(w) + "'" + (w.empty() ? " (end of file)" : ""));
    }
    return v;
  }

  Scalar scalar(const std::string& section) {
    const std::string w = lower(need(section));
    static const std::pair<const char*, Scalar> kTypes[] = {
        {"bit", Scalar::kBit},          {"char", Scalar::kI8},           {"signed_char", Scalar::kI8},
        {"unsigned_char", Scalar::kU8}, {"short", Scalar::kI16},         {"unsigned_short", Scalar::kU16},
        {"int", Scalar::kI32},          {"unsigned_int", Scalar::kU32},  {"vtkidtype", Scalar::kI32},
        {"long", Scalar::kI64},         {"unsigned_long", Scalar::kU64}, {"vtktypeint64", Scalar::kI64},
        {"vtktypeuint64", Scalar::kU64}, {"float", Scalar::kF32},        {"double", Scalar::kF64}};
    for (const auto& [name, s] : kTypes) {
      if (w == name) return s;
    }
    if (w == "string" || w == "utf8_string" || w == "variant") {
      fail(section, w + " arrays are not read from legacy files; save the file as .vtu (ParaView: File > Save Data) "
                    "and import that");
    }
    fail(section, "unknown data type '" + shown(w) + "'");
  }

  // Reads `count` values of `type` (host order into `into`), or skips them
  // when `into` is null. Checks first that the file can hold them.
  void values(const std::string& section, Scalar type, uint64_t count, Values* into) {
    if (binary_) {
      (void)in_.line();  // the rest of the keyword line; the data follows its newline
      const uint64_t size = value_bytes(type);
      const uint64_t bytes = type == Scalar::kBit ? count / 8 + (count % 8 != 0) : count * size;
      if ((type != Scalar::kBit && count > in_.remaining() / size) || bytes > in_.remaining()) {
        fail(section, std::to_string(count) + " values of " + type_word(type) + " need " +
                          (count > std::numeric_limits<uint64_t>::max() / size ? std::string("more than 2^64")
                                                                               : std::to_string(bytes)) +
                          " bytes, but the file has " + std::to_string(in_.remaining()) + " bytes after byte " +
                          std::to_string(in_.offset()) + " (cut short, or the count is wrong)");
      }
      if (!into) return in_.skip(bytes);
      into->allocate(type, count);
      if (type == Scalar::kBit) {
        std::vector<unsigned char> packed(bytes);
        in_.read(packed.data(), bytes);
        for (uint64_t k = 0; k < count; ++k) into->bytes[k] = (packed[k / 8] >> (7 - k % 8)) & 1;
        return;
      }
      in_.read(into->storage(), bytes);
      visit(type, [&](auto t) { to_host<decltype(t)>(into->storage(), count); });
      return;
    }
    // Text: every value takes at least two bytes but the last.
    if (count > in_.remaining() / 2 + 1) {
      fail(section, std::to_string(count) + " values declared, but only " + std::to_string(in_.remaining()) +
                        " bytes remain after " + here() + " (cut short, or the count is wrong)");
    }
    if (into) into->allocate(type, count);
    visit(type, [&](auto t) {
      using T = decltype(t);
      T* out = into ? reinterpret_cast<T*>(into->storage()) : nullptr;
      for (uint64_t k = 0; k < count; ++k) {
        const std::string_view w = in_.word();
        if (w.empty()) {
          fail(section, "the file ends after " + std::to_string(k) + " of " + std::to_string(count) + " values (cut short)");
        }
        T v{};
        if (!parse_text<T>(w, type, v)) {
          fail(section, "value " + std::to_string(k + 1) + " of " + std::to_string(count) + " is '" +
                            shown(w) + "', not " + (std::is_floating_point_v<T> ? "a number" : "an integer of type " + type_word(type)) +
                            " (" + here() + ")");
        }
        if (out) out[k] = v;
      }
    });
  }

  template <class T>
  static bool parse_text(std::string_view w, Scalar type, T& v) {
    const char* first = w.data() + (w.size() > 1 && w[0] == '+' ? 1 : 0);
    const char* last = w.data() + w.size();
    if constexpr (std::is_floating_point_v<T>) {
      double d = 0;
      const auto [end, ec] = std::from_chars(first, last, d);
      if (end != last || (ec != std::errc() && ec != std::errc::result_out_of_range)) return false;
      if (ec == std::errc::result_out_of_range) d = std::strtod(std::string(w).c_str(), nullptr);  // 0 or inf, as VTK reads it
      v = static_cast<T>(d);
      return true;
    } else {
      const auto [end, ec] = std::from_chars(first, last, v);
      if (ec != std::errc() || end != last) return false;
      return type != Scalar::kBit || v <= 1;
    }
  }

  // Three numbers written as text (ORIGIN, SPACING).
  void text_numbers(const std::string& section, std::array<double, 3>& out) {
    for (double& v : out) {
      const std::string_view w = need(section);
      if (!parse_text<double>(w, Scalar::kF64, v) || !std::isfinite(v)) {
        fail(section, "expected 3 numbers, found '" + shown(w) + "'");
      }
    }
  }

  // ------------------------------------------------------- geometry
  void points() {
    if (has_points_) fail("POINTS", "a second POINTS section");
    const uint64_t n = count("POINTS", "the number of points");
    const Scalar type = scalar("POINTS");
    if (n > std::numeric_limits<uint64_t>::max() / 3) fail("POINTS", std::to_string(n) + " points cannot be stored");
    if (dataset_ == "structured_grid" && has_dims_ && n != dims_count()) {
      fail("POINTS", "declares " + std::to_string(n) + " points but DIMENSIONS make " + std::to_string(dims_count()));
    }
    values("POINTS (" + std::to_string(n) + " points)", type, 3 * n, read_values_ ? &points_ : nullptr);
    has_points_ = true;
    point_count = n;
  }

  void dimensions() {
    for (uint64_t& d : dims_) d = count("DIMENSIONS", "3 sizes");
    has_dims_ = true;
    // Points are generated from the sizes: keep damaged sizes from allocating.
    const uint64_t kMost = uint64_t(1) << 31;
    const bool too_many = dims_[0] > kMost || dims_[1] > kMost || dims_[2] > kMost ||
                          dims_[0] * dims_[1] > kMost || dims_[0] * dims_[1] * dims_[2] > kMost;
    if (too_many) {
      fail("DIMENSIONS", std::to_string(dims_[0]) + " x " + std::to_string(dims_[1]) + " x " +
                             std::to_string(dims_[2]) + " points is more than sluice reads from one file (2^31)");
    }
    if (dataset_ != "structured_grid") point_count = dims_count();
  }

  uint64_t dims_count() const { return dims_[0] * dims_[1] * dims_[2]; }

  void coordinates(const std::string& key) {
    const int axis = key[0] - 'x';
    const std::string section = upper(key);
    const uint64_t n = count(section, "the number of coordinates");
    const Scalar type = scalar(section);
    if (has_dims_ && n != dims_[axis]) {
      fail(section, std::to_string(n) + " coordinates, but DIMENSIONS say " + std::to_string(dims_[axis]));
    }
    values(section, type, n, &coords_[axis]);
  }

  void cells(const std::string& key) {
    const std::string section = upper(key);
    const uint64_t a = count(section, "the number of cells");
    const uint64_t b = count(section, "the size of the cell list");
    uint64_t cells = a;
    if (major_ >= 5) {
      if (lower(need(section)) != "offsets") fail(section, "expected OFFSETS (file version 5 cell list)");
      const Scalar offsets_type = scalar(section + " OFFSETS");
      values(section + " OFFSETS", offsets_type, a, nullptr);
      if (lower(need(section)) != "connectivity") fail(section, "expected CONNECTIVITY after the offsets");
      const Scalar connectivity_type = scalar(section + " CONNECTIVITY");
      values(section + " CONNECTIVITY", connectivity_type, b, nullptr);
      cells = a > 0 ? a - 1 : 0;
    } else {
      if (b < a) fail(section, std::to_string(a) + " cells cannot fit in a list of " + std::to_string(b) + " values");
      values(section, Scalar::kI32, b, nullptr);
    }
    if (key != "vertices" && key != "cells" && cells > 0) ignored_sections.push_back(section);
  }

  void cell_types() {
    const uint64_t n = count("CELL_TYPES", "the number of cells");
    Values types;
    values("CELL_TYPES", Scalar::kI32, n, &types);
    const auto* t = types.as<int32_t>();
    for (uint64_t k = 0; k < n; ++k) {
      if (t[k] != 1 && t[k] != 2 && t[k] != 0) ignored_cell_types.insert(t[k]);
    }
  }

  static std::string upper(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    return s;
  }

  // ------------------------------------------------------ attributes
  enum class Section { kDataset, kPoints, kCells };

  std::string section_name() const { return section_ == Section::kPoints ? "POINT_DATA" : "CELL_DATA"; }

  void attribute_section(bool points) {
    const char* name = points ? "POINT_DATA" : "CELL_DATA";
    tuples_ = count(name, "the number of values per array");
    section_ = points ? Section::kPoints : Section::kCells;
    if (points && tuples_ != point_count) {
      fail(name, "declares " + std::to_string(tuples_) + " values per array, but the file has " +
                     std::to_string(point_count) + " points");
    }
  }

  // One attribute (SCALARS, VECTORS, ...); false if `key` is none.
  bool attribute(const std::string& key) {
    const std::string section = section_name() + " " + upper(key);
    if (key == "lookup_table") {
      (void)need(section);
      const uint64_t size = count(section, "the table size");
      check_product(section, size, 4);
      values(section, binary_ ? Scalar::kU8 : Scalar::kF32, 4 * size, nullptr);
      return true;
    }
    if (key == "color_scalars") {
      const std::string name = decode_name(need(section));
      const uint64_t comps = count(section, "the number of components");
      array(section, name, binary_ ? Scalar::kU8 : Scalar::kF32, comps, tuples_);
      return true;
    }
    if (key == "scalars") {
      const std::string name = decode_name(need(section));
      const Scalar type = scalar(section);
      // An optional component count ends the line.
      const std::string_view rest = in_.line();
      uint64_t comps = 1;
      const size_t b = rest.find_first_not_of(" \t");
      if (b != std::string_view::npos) {
        const auto [end, ec] = std::from_chars(rest.data() + b, rest.data() + rest.size(), comps);
        if (ec != std::errc() || comps == 0 || comps > 4) {
          fail(section, "'" + name + "': expected a component count of 1 to 4, found '" + shown(rest.substr(b)) + "'");
        }
      }
      if (lower(need(section)) != "lookup_table") fail(section, "'" + name + "': expected LOOKUP_TABLE after SCALARS");
      (void)need(section);
      array(section, name, type, comps, tuples_);
      return true;
    }
    static const std::pair<const char*, uint64_t> kFixed[] = {{"vectors", 3},      {"normals", 3},
                                                               {"tensors", 9},      {"tensors6", 6},
                                                               {"global_ids", 1},   {"pedigree_ids", 1},
                                                               {"edge_flags", 1}};
    for (const auto& [word, comps] : kFixed) {
      if (key != word) continue;
      const std::string name = decode_name(need(section));
      array(section, name, scalar(section + " '" + name + "'"), comps, tuples_);
      return true;
    }
    if (key == "texture_coordinates") {
      const std::string name = decode_name(need(section));
      const uint64_t comps = count(section, "the number of dimensions");
      if (comps == 0 || comps > 3) fail(section, "'" + name + "': " + std::to_string(comps) + " dimensions (1 to 3 allowed)");
      array(section, name, scalar(section + " '" + name + "'"), comps, tuples_);
      return true;
    }
    return false;
  }

  void check_product(const std::string& section, uint64_t a, uint64_t b) {
    if (b != 0 && a > std::numeric_limits<uint64_t>::max() / b) {
      fail(section, std::to_string(a) + " x " + std::to_string(b) + " values cannot be stored");
    }
  }

  // The data of one array; kept when it is a wanted point array.
  void array(const std::string& section, const std::string& name, Scalar type, uint64_t comps, uint64_t tuples) {
    check_product(section, comps, tuples);
    const std::string what = section + " '" + name + "'";
    const bool point_array = section_ == Section::kPoints;
    if (point_array) point_arrays.push_back(name);
    const bool keep = read_values_ && point_array && is_wanted(name) && !is_kept(name);
    if (!keep) return values(what, type, comps * tuples, nullptr);
    Array a{name, comps, tuples, {}};
    values(what, type, comps * tuples, &a.values);
    kept.push_back(std::move(a));
  }

  bool is_wanted(const std::string& name) const {
    return std::find(wanted_.begin(), wanted_.end(), name) != wanted_.end();
  }
  bool is_kept(const std::string& name) const {
    return std::any_of(kept.begin(), kept.end(), [&](const Array& a) { return a.name == name; });
  }

  // FIELD name count, then per array: name components tuples type, data.
  void field(const std::string& section) {
    (void)need(section);  // the field's name
    const uint64_t arrays = count(section, "the number of arrays");
    for (uint64_t k = 0; k < arrays; ++k) {
      std::string_view word = in_.word();
      while (lower(word) == "metadata") {  // of the array before
        metadata();
        word = in_.word();
      }
      if (word.empty()) {
        fail(section, "the file ends after " + std::to_string(k) + " of " + std::to_string(arrays) + " arrays (cut short)");
      }
      const std::string name = decode_name(word);
      if (lower(name) == "null_array") continue;
      const uint64_t comps = count(section + " '" + name + "'", "the number of components");
      const uint64_t tuples = count(section + " '" + name + "'", "the number of tuples");
      const Scalar type = scalar(section + " '" + name + "'");
      if (section_ != Section::kDataset) {
        array(section, name, type, comps, tuples);
        continue;
      }
      const std::string lname = lower(name);
      if ((lname == "timevalue" || lname == "time") && comps * tuples >= 1) {
        Values v;
        check_product(section, comps, tuples);
        values(section + " '" + name + "'", type, comps * tuples, &v);
        const double t = visit(type, [&](auto x) { return static_cast<double>(v.as<decltype(x)>()[0]); });
        if (std::isfinite(t)) time = t;
        continue;
      }
      check_product(section, comps, tuples);
      values(section + " '" + name + "'", type, comps * tuples, nullptr);
    }
  }

  // METADATA (COMPONENT_NAMES, INFORMATION): text lines up to an empty one.
  void metadata() {
    (void)in_.line();
    for (;;) {
      if (in_.remaining() == 0) return;
      const std::string_view line = in_.line();
      if (line.find_first_not_of(" \t") == std::string_view::npos) return;
    }
  }

  // --------------------------------------------------------- finish
  void finish() {
    const bool point_set = dataset_ == "polydata" || dataset_ == "unstructured_grid" || dataset_ == "structured_grid";
    if (point_set && !has_points_) {
      fail("POINTS", "the file has no POINTS section (it ends at byte " + std::to_string(in_.size()) + ")");
    }
    if (!point_set && !has_dims_) fail("DIMENSIONS", "the file has no DIMENSIONS section");
    if (dataset_ == "rectilinear_grid" && read_values_) {
      for (int axis = 0; axis < 3; ++axis) {
        if (coords_[axis].count != dims_[axis]) {
          fail(std::string(1, static_cast<char>('X' + axis)) + "_COORDINATES",
               "missing, or not the " + std::to_string(dims_[axis]) + " values DIMENSIONS ask for");
        }
      }
    }
    if (!point_set) {
      // The cells VTK makes of a grid: the dimensionality decides.
      const int d = (dims_[0] > 1) + (dims_[1] > 1) + (dims_[2] > 1);
      const bool image = dataset_ != "structured_grid";
      if (d == 3) ignored_cell_types.insert(image ? 11 : 12);  // VOXEL : HEXAHEDRON
      if (d == 2) ignored_cell_types.insert(image ? 8 : 9);    // PIXEL : QUAD
      if (d == 1) ignored_cell_types.insert(3);                // LINE
    }
  }

  void generate_image(std::vector<float>& out) const {
    uint64_t i = 0;
    for (uint64_t z = 0; z < dims_[2]; ++z) {
      for (uint64_t y = 0; y < dims_[1]; ++y) {
        for (uint64_t x = 0; x < dims_[0]; ++x, ++i) {
          const uint64_t idx[3] = {x, y, z};
          for (int c = 0; c < 3; ++c) {
            out[i * 3 + c] = static_cast<float>(origin_[c] + static_cast<double>(idx[c]) * spacing_[c]);
          }
        }
      }
    }
  }

  void generate_rectilinear(std::vector<float>& out) const {
    std::array<std::vector<float>, 3> axes;
    for (int c = 0; c < 3; ++c) {
      axes[c].resize(dims_[c]);
      visit(coords_[c].type, [&](auto t) { convert_values(coords_[c].as<decltype(t)>(), dims_[c], axes[c].data()); });
    }
    uint64_t i = 0;
    for (uint64_t z = 0; z < dims_[2]; ++z) {
      for (uint64_t y = 0; y < dims_[1]; ++y) {
        for (uint64_t x = 0; x < dims_[0]; ++x, ++i) {
          out[i * 3 + 0] = axes[0][x];
          out[i * 3 + 1] = axes[1][y];
          out[i * 3 + 2] = axes[2][z];
        }
      }
    }
  }

  ByteStream in_;
  std::vector<std::string> wanted_;
  bool read_values_;
  bool binary_ = false;
  int major_ = 0;
  std::string dataset_;
  Section section_ = Section::kDataset;
  uint64_t tuples_ = 0;      // values per array in the current attribute section
  bool has_points_ = false;
  Values points_;
  bool has_dims_ = false;
  std::array<uint64_t, 3> dims_{};
  std::array<double, 3> origin_{};
  std::array<double, 3> spacing_{1, 1, 1};
  std::array<Values, 3> coords_;
};

// ------------------------------------------------------- arrays -> frame

Array& point_array(Parser& p, const std::string& name, const char* what) {
  for (Array& a : p.kept) {
    if (a.name != name) continue;
    if (a.tuples != p.point_count) {
      throw Error({p.path()}, "array '" + name + "' has " + std::to_string(a.tuples) + " values but the file has " +
                                  std::to_string(p.point_count) + " points");
    }
    return a;
  }
  throw Error({p.path()}, "no point array '" + name + "' (" + what + "); arrays in the file: " + join(p.point_arrays));
}

void copy_ids(const Parser& p, const Array& a, std::vector<uint64_t>& out) {
  if (a.components != 1) {
    throw Error({p.path()}, "id array '" + a.name + "' has " + std::to_string(a.components) + " components; ids need 1");
  }
  const size_t bad = visit(a.values.type, [&](auto t) { return assign_ids(a.values.as<decltype(t)>(), a.tuples, out); });
  if (bad >= a.tuples) return;
  const double v = visit(a.values.type, [&](auto t) { return static_cast<double>(a.values.as<decltype(t)>()[bad]); });
  char value[64];
  std::snprintf(value, sizeof value, "%.17g", v);
  throw Error({p.path()}, "id array '" + a.name + "' holds " + value + " at index " + std::to_string(bad) +
                              ": ids must be non-negative integers");
}

void copy_scalar(Array& a, std::vector<float>& out) {
  if (a.components == 1 && a.values.type == Scalar::kF32) {
    out = std::move(a.values.floats);
    return;
  }
  out.resize(a.tuples);
  visit(a.values.type, [&](auto t) {
    const auto* in = a.values.as<decltype(t)>();
    if (a.components == 1) convert_values(in, a.tuples, out.data());
    else magnitudes(in, a.tuples, a.components, out.data());
  });
}

}  // namespace

std::vector<std::string> legacy_vtk_arrays(const std::string& path) {
  Parser p(path, {}, false);
  p.run();
  return p.point_arrays;
}

LegacyRead read_legacy_vtk(const std::string& path, const std::vector<std::string>& attributes,
                           const std::string& id_array) {
  std::vector<std::string> wanted = attributes;
  if (!id_array.empty()) wanted.push_back(id_array);
  Parser p(path, wanted, true);
  p.run();

  LegacyRead out;
  out.time = p.time;
  ParticleFrame& f = out.frame;
  f.attributes.resize(attributes.size());
  if (p.point_count == 0) return out;
  f.positions = p.take_positions();
  if (!id_array.empty()) copy_ids(p, point_array(p, id_array, "id array"), f.ids);
  for (size_t k = 0; k < attributes.size(); ++k) copy_scalar(point_array(p, attributes[k], "attribute"), f.attributes[k]);
  std::vector<std::string> ignored = p.ignored_sections;
  for (const std::string& name : non_vertex_names(p.ignored_cell_types)) ignored.push_back(name);
  if (!ignored.empty()) f.repairs.push_back(ignored_cells_note(ignored, p.point_count));
  return out;
}

}  // namespace sluice::import::detail
