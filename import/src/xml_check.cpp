// VTK XML size checks: markup up to <AppendedData>, then a few header bytes
// per appended block, read with pread wherever the block lies.
#include "xml_check.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <string_view>

#include <zlib.h>

#include "cell_types.h"
#include "xml_tags.h"
#include "sluice/error.h"

namespace sluice::import::detail {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

namespace fs = std::filesystem;

constexpr const char* kKind = "not a valid VTK XML file";

// ------------------------------------------------------------ the file

class File {
 public:
  explicit File(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw Error({path}, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      ::close(fd_);
      throw Error({path}, "cannot read its size");
    }
    size_ = static_cast<uint64_t>(st.st_size);
  }
  ~File() { ::close(fd_); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  uint64_t size() const { return size_; }

  // Up to `n` bytes at `offset` (fewer at the end of the file).
  std::string read(uint64_t offset, uint64_t n) const {
    std::string out;
    append(out, offset, n);
    return out;
  }

  // Appends up to `n` bytes at `offset` to `out`.
  void append(std::string& out, uint64_t offset, uint64_t n) const {
    const size_t start = out.size();
    out.resize(start + static_cast<size_t>(std::min(n, offset < size_ ? size_ - offset : 0)));
    size_t done = start;
    while (done < out.size()) {
      const ssize_t got = ::pread(fd_, out.data() + done, out.size() - done, static_cast<off_t>(offset + done - start));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) break;
      done += static_cast<size_t>(got);
    }
    out.resize(done);
  }

  // The markup: everything before the appended data (the whole file when
  // there is none), read in steps so a large appended block is not read.
  std::string markup(uint64_t& appended_at) const {
    std::string text;
    constexpr uint64_t kStep = 1 << 16;  // markup is a few kB; the data after it is not read
    appended_at = std::numeric_limits<uint64_t>::max();
    while (text.size() < size_) {
      const size_t from = text.size() > 16 ? text.size() - 16 : 0;
      const size_t before = text.size();
      append(text, text.size(), kStep);
      if (text.size() == before) break;  // the file shrank
      const size_t tag = text.find("<AppendedData", from);
      if (tag == std::string::npos) continue;
      // The data starts after the '_' that follows the tag and spaces. VTK
      // skips the first character after the spaces, whatever it is: any
      // other than '_' throws (offsets would not mean what they say).
      const size_t close = text.find('>', tag);
      const size_t first = close == std::string::npos ? close : text.find_first_not_of(" \t\r\n", close + 1);
      if (first == std::string::npos && text.size() < size_) continue;
      if (first != std::string::npos) {
        if (text[first] != '_') {
          throw Error({path_}, "the appended data must start with '_' after <AppendedData>, found '" +
                                   std::string(std::isprint(static_cast<unsigned char>(text[first])) ? 1 : 0, text[first]) +
                                   "' at byte " + std::to_string(first));
        }
        appended_at = first + 1;
      }
      text.resize(close == std::string::npos ? text.size() : close + 1);
      return text;
    }
    return text;
  }

 private:
  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

// ------------------------------------------------------------- numbers

std::optional<uint64_t> parse_count(const std::string* s) {
  if (!s) return std::nullopt;
  const std::string_view v = *s;
  const size_t b = v.find_first_not_of(" \t\r\n");
  const size_t e = v.find_last_not_of(" \t\r\n");
  if (b == std::string_view::npos) return std::nullopt;
  uint64_t out = 0;
  const auto [end, ec] = std::from_chars(v.data() + b, v.data() + e + 1, out);
  if (ec != std::errc() || end != v.data() + e + 1) return std::nullopt;
  return out;
}

uint64_t type_size(const std::string& type) {
  if (type == "Int8" || type == "UInt8" || type == "Char") return 1;
  if (type == "IdType") return 0;  // Int32 or Int64 by the writer's build: not checked
  if (type == "Int16" || type == "UInt16") return 2;
  if (type == "Int32" || type == "UInt32" || type == "Float32") return 4;
  if (type == "Int64" || type == "UInt64" || type == "Float64") return 8;
  return 0;  // String, Bit, unknown: not checked
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

// Decodes whole quads of `text` (whitespace skipped) until `bytes` bytes or
// the end of a padded run or any other character; returns what was decoded.
std::string base64_decode(std::string_view text, size_t bytes) {
  std::string out;
  uint32_t acc = 0;
  int have = 0;
  size_t k = 0;
  for (; k < text.size() && out.size() < bytes; ++k) {
    const char c = text[k];
    if (c == ' ' || c == '\n' || c == '\r' || c == '\t') continue;
    const int v = base64_value(c);
    if (v < 0) {
      // '=' pads the last quad of a run: its first bytes are complete.
      if (c == '=' && have >= 2) {
        acc <<= 6 * (4 - have);
        out += static_cast<char>((acc >> 16) & 0xFF);
        if (have == 3) out += static_cast<char>((acc >> 8) & 0xFF);
      }
      break;
    }
    acc = (acc << 6) | static_cast<uint32_t>(v);
    if (++have == 4) {
      out += static_cast<char>((acc >> 16) & 0xFF);
      out += static_cast<char>((acc >> 8) & 0xFF);
      out += static_cast<char>(acc & 0xFF);
      acc = 0;
      have = 0;
    }
  }
  if (out.size() > bytes) out.resize(bytes);
  return out;
}

// Base64 characters in `text` (whitespace excluded, padding included).
uint64_t base64_chars(std::string_view text) {
  uint64_t n = 0;
  for (char c : text) n += base64_value(c) >= 0 || c == '=';
  return n;
}

uint64_t encoded_size(uint64_t bytes) { return (bytes + 2) / 3 * 4; }

// ------------------------------------------------------------- the checks

struct Layout {
  bool big_endian = false;
  uint64_t header_bytes = 4;  // UInt32 or UInt64 block headers
  bool compressed = false;
  bool base64_appended = false;
  bool zlib = false;
  uint64_t appended_at = std::numeric_limits<uint64_t>::max();
};

class Checker {
 public:
  explicit Checker(const std::string& path) : path_(path), file_(path) {}

  XmlFacts run() {
    uint64_t appended_at = 0;
    const std::string text = file_.markup(appended_at);
    layout_.appended_at = appended_at;
    XmlTag tag;
    // The arrays come before <AppendedData>, but their checks need its encoding.
    if (const size_t at = text.rfind("<AppendedData"); at != std::string::npos) {
      TagScanner appended_scanner(std::string_view(text).substr(at), path_, kKind);
      if (appended_scanner.next(tag)) appended(tag);
    }
    TagScanner scanner(text, path_, kKind);
    if (!scanner.next(tag) || tag.name != "VTKFile") fail("the file does not start with a <VTKFile> element");
    file_header(tag);
    while (scanner.next(tag)) {
      if (tag.name == "Piece") piece(tag);
      else if (tag.name == "PointData" || tag.name == "Points") section(tag.name, points_, false);
      else if (tag.name == "CellData") section(tag.name, cells_, false);
      else if (tag.name == "FieldData" || tag.name == "Coordinates") section(tag.name, std::nullopt, false);
      else if (tag.name == "Cells" || tag.name == "Verts" || tag.name == "Lines" || tag.name == "Strips" ||
               tag.name == "Polys") section(tag.name, std::nullopt, true);
      else if (tag.name == "DataArray") data_array(tag, scanner.text_after(tag));
    }
    return std::move(facts_);
  }

 private:
  struct Section {
    std::string name;
    std::optional<uint64_t> tuples;  // declared by the piece, when known
    bool cells = false;              // a cell list (connectivity + offsets)
  };

  [[noreturn]] void fail(const std::string& msg) const { throw Error({path_}, msg); }

  void section(const std::string& name, std::optional<uint64_t> tuples, bool cells) {
    section_ = {name, tuples, cells};
    connectivity_.reset();
  }

  uint64_t header_int(const std::string& bytes, size_t k) const {
    uint64_t v = 0;
    for (uint64_t b = 0; b < layout_.header_bytes; ++b) {
      const auto byte = static_cast<unsigned char>(bytes[k * layout_.header_bytes + b]);
      const uint64_t shift = layout_.big_endian ? 8 * (layout_.header_bytes - 1 - b) : 8 * b;
      v |= static_cast<uint64_t>(byte) << shift;
    }
    return v;
  }

  void file_header(const XmlTag& tag) {
    const std::string* order = tag.attribute("byte_order");
    layout_.big_endian = order && *order == "BigEndian";
    const std::string* header = tag.attribute("header_type");
    if (header && *header == "UInt64") layout_.header_bytes = 8;
    else if (header && *header != "UInt32") fail("header_type '" + *header + "' (expected UInt32 or UInt64)");
    const std::string* compressor = tag.attribute("compressor");
    layout_.compressed = compressor && !compressor->empty();
    layout_.zlib = compressor && *compressor == "vtkZLibDataCompressor";
  }

  std::optional<uint64_t> count_attribute(const XmlTag& tag, const char* key) const {
    const std::string* s = tag.attribute(key);
    if (!s) return std::nullopt;
    const std::optional<uint64_t> v = parse_count(s);
    if (!v) fail("line " + std::to_string(tag.line) + ": Piece " + key + "=\"" + s->substr(0, 40) + "\" is not a count");
    return v;
  }

  void piece(const XmlTag& tag) {
    points_ = count_attribute(tag, "NumberOfPoints");
    cells_ = count_attribute(tag, "NumberOfCells");
    if (!cells_) {  // polydata: all kinds of cells together
      uint64_t sum = 0;
      bool any = false;
      for (const char* key : {"NumberOfVerts", "NumberOfLines", "NumberOfStrips", "NumberOfPolys"}) {
        if (const auto v = count_attribute(tag, key)) {
          sum += *v;
          any = true;
          const std::string k = key;
          const char* list = k == "NumberOfLines" ? "LINES" : k == "NumberOfStrips" ? "TRIANGLE_STRIPS"
                             : k == "NumberOfPolys" ? "POLYGONS" : nullptr;
          if (list && *v > 0 && std::find(facts_.cell_lists.begin(), facts_.cell_lists.end(), list) == facts_.cell_lists.end()) {
            facts_.cell_lists.push_back(list);
          }
        }
      }
      if (any) cells_ = sum;
    }
    section("Piece", std::nullopt, false);
  }

  void appended(const XmlTag& tag) {
    const std::string* encoding = tag.attribute("encoding");
    layout_.base64_appended = encoding && *encoding == "base64";
    if (encoding && *encoding != "base64" && *encoding != "raw") {
      fail("line " + std::to_string(tag.line) + ": AppendedData encoding '" + *encoding + "' (expected raw or base64)");
    }
  }

  // ------------------------------------------------------ one array
  // Where an array's bytes are, once its header has been read.
  struct Where {
    bool base64 = false;
    bool appended = false;
    uint64_t at = 0;   // appended: file offset of the block
    std::string text;  // inline: the base64 text without whitespace
  };

  // A block's decoded header: the bytes it says it holds (uncompressed),
  // the bytes after the header (compressed sizes), and for compressed
  // blocks where the last sub-block lies.
  struct Block {
    uint64_t header = 0;   // header bytes
    uint64_t content = 0;  // uncompressed bytes
    uint64_t stored = 0;   // bytes after the header
    uint64_t before_last = 0, last_stored = 0, last_content = 0;  // compressed only
    uint64_t block_size = 0;                                       // compressed: bytes per sub-block
    std::vector<uint64_t> sizes;                                   // compressed: stored bytes per sub-block
  };

  void data_array(const XmlTag& tag, std::string_view text) {
    const std::string name = tag.attribute("Name") ? *tag.attribute("Name") : "(unnamed)";
    const std::string what = section_.name + " array '" + name + "'";
    const std::string type = tag.attribute("type") ? *tag.attribute("type") : "";
    uint64_t comps = 1;
    if (const std::string* c = tag.attribute("NumberOfComponents")) {
      const auto v = parse_count(c);
      if (!v || *v == 0 || *v > 4096) fail(what + ": NumberOfComponents=\"" + c->substr(0, 40) + "\" is not 1 to 4096");
      comps = *v;
    }
    std::optional<uint64_t> tuples = section_.tuples;
    if (tag.attribute("NumberOfTuples")) {
      tuples = parse_count(tag.attribute("NumberOfTuples"));
      if (!tuples) fail(what + ": NumberOfTuples is not a count");
    }
    const uint64_t size = type_size(type);
    // VTK's reader dereferences the array it could not create for a type it
    // does not know (found by fuzz_vtk_import).
    if (size == 0 && type != "String" && type != "Bit" && type != "IdType") {
      fail(what + ": unknown type '" + type.substr(0, 40) +
           "' (expected Int8 to Int64, UInt8 to UInt64, Float32, Float64 or String)");
    }
    std::optional<uint64_t> expected;
    std::string declared;
    if (tuples && size > 0) {
      if (*tuples > std::numeric_limits<uint64_t>::max() / comps / size) {
        fail(what + ": " + std::to_string(*tuples) + " tuples of " + std::to_string(comps) + " cannot be stored");
      }
      expected = *tuples * comps * size;
      declared = std::to_string(*tuples) + " tuples x " + std::to_string(comps) + " components of " + type + " = " +
                 std::to_string(*expected) + " bytes";
    }
    const std::string format = tag.attribute("format") ? *tag.attribute("format") : "ascii";
    // Cell lists: VTK sizes the connectivity by the last offset, so that
    // value is read too (a few bytes; the last sub-block when compressed).
    const bool cell_list = section_.cells && (name == "connectivity" || name == "offsets") && size > 0;
    std::optional<int64_t> last;
    uint64_t values = 0;
    if (format == "appended") {
      const auto offset = parse_count(tag.attribute("offset"));
      if (!offset) fail(what + ": appended data without a valid offset");
      where_ = Where{};
      block_ = appended_block(what, *offset, expected, declared, where_);
      values = size ? block_.content / size : 0;
      if (cell_list && name == "offsets") last = last_value(where_, block_, type);
    } else if (format == "binary") {
      where_ = Where{};
      block_ = inline_block(what, text, expected, declared, where_);
      values = size ? block_.content / size : 0;
      if (cell_list && name == "offsets") last = last_value(where_, block_, type);
    } else if (format == "ascii") {
      std::string_view last_word;
      values = ascii_values(what, text, expected ? *tuples * comps : 0, declared, last_word);
      int64_t v = 0;
      if (cell_list && name == "offsets" &&
          std::from_chars(last_word.data(), last_word.data() + last_word.size(), v).ec == std::errc()) {
        last = v;
      }
    } else {
      fail(what + ": format '" + format + "' (expected ascii, binary or appended)");
    }
    if (cell_list && name == "connectivity") connectivity_ = values;
    if (section_.name == "Cells" && name == "types") cell_types(where_, block_, format, text, type);
    if (last && connectivity_ && (*last < 0 || static_cast<uint64_t>(*last) != *connectivity_)) {
      fail(section_.name + ": the cell offsets end at " + std::to_string(*last) + ", but the connectivity holds " +
           std::to_string(*connectivity_) + " values");
    }
  }

  Block parse_header(const std::string& what, const std::string& head, const std::string& more_for_blocks) const {
    Block b;
    if (!layout_.compressed) {
      if (head.size() < layout_.header_bytes) fail(what + ": its data block ends inside its size header");
      b.header = layout_.header_bytes;
      b.content = b.stored = header_int(head, 0);
      return b;
    }
    if (head.size() < 3 * layout_.header_bytes) fail(what + ": its data block ends inside its compression header");
    const uint64_t blocks = header_int(head, 0);
    const uint64_t block_size = header_int(head, 1);
    const uint64_t last = header_int(head, 2);
    b.header = (3 + blocks) * layout_.header_bytes;
    // VTK divides by the block size (found by fuzz_vtk_import).
    if (blocks > 0 && (block_size == 0 || last > block_size)) {
      fail(what + ": its compression header declares blocks of " + std::to_string(block_size) +
           " bytes with a last block of " + std::to_string(last));
    }
    if (blocks > file_.size() / layout_.header_bytes) {
      fail(what + ": its compression header lists " + std::to_string(blocks) + " blocks, more than the file can hold");
    }
    const std::string& all = more_for_blocks;
    if (all.size() < b.header) fail(what + ": its data block ends inside its compression header");
    if (blocks > 0 && block_size > std::numeric_limits<uint64_t>::max() / blocks) {
      fail(what + ": its compression header declares " + std::to_string(blocks) + " blocks of " +
           std::to_string(block_size) + " bytes");
    }
    b.content = blocks == 0 ? 0 : (blocks - 1) * block_size + (last == 0 ? block_size : last);
    for (uint64_t k = 0; k < blocks; ++k) {
      const uint64_t stored = header_int(all, 3 + k);
      if (stored > file_.size()) fail(what + ": a compressed block of " + std::to_string(stored) + " bytes, more than the file holds");
      if (k + 1 == blocks) b.before_last = b.stored, b.last_stored = stored;
      b.stored += stored;
      b.sizes.push_back(stored);
    }
    b.last_content = blocks == 0 ? 0 : (last == 0 ? block_size : last);
    b.block_size = block_size;
    return b;
  }

  void check_content(const std::string& what, const Block& b, const std::optional<uint64_t>& expected,
                     const std::string& declared) const {
    if (expected && b.content != *expected) {
      fail(what + ": declares " + declared + ", but its data block holds " + std::to_string(b.content) + " bytes");
    }
  }

  Block appended_block(const std::string& what, uint64_t offset, const std::optional<uint64_t>& expected,
                       const std::string& declared, Where& where) const {
    if (layout_.appended_at == std::numeric_limits<uint64_t>::max()) {
      fail(what + ": appended data, but the file has no <AppendedData> section");
    }
    const uint64_t at = layout_.appended_at + offset;
    if (offset > file_.size() || at > file_.size()) {
      fail(what + ": its block starts at byte " + std::to_string(at) + ", past the end of the file (" +
           std::to_string(file_.size()) + " bytes): cut short, or the offset is wrong");
    }
    where.appended = true;
    where.base64 = layout_.base64_appended;
    where.at = at;
    const uint64_t left = file_.size() - at;
    const uint64_t word = layout_.header_bytes;
    if (!layout_.base64_appended) {
      const std::string head = file_.read(at, 3 * word);
      std::string all = head;
      if (layout_.compressed && head.size() == 3 * word) {
        const uint64_t blocks = header_int(head, 0);
        if (blocks <= file_.size() / word) all = file_.read(at, (3 + blocks) * word);
      }
      const Block b = parse_header(what, head, all);
      check_content(what, b, expected, declared);
      if (b.header + b.stored > left) {
        fail(what + ": its block needs " + std::to_string(b.header + b.stored) + " bytes from byte " +
             std::to_string(at) + ", but the file has " + std::to_string(left) + " (cut short)");
      }
      return b;
    }
    // base64: the header is decoded from the first characters.
    const std::string chars = file_.read(at, encoded_size(3 * word) + 64);
    const std::string head = base64_decode(chars, 3 * word);
    std::string all = head;
    if (layout_.compressed && head.size() == 3 * word) {
      const uint64_t blocks = header_int(head, 0);
      if (blocks <= file_.size() / word) all = base64_decode(file_.read(at, encoded_size((3 + blocks) * word) + 64), (3 + blocks) * word);
    }
    const Block b = parse_header(what, head, all);
    check_content(what, b, expected, declared);
    const uint64_t needed = stream_chars(b);
    if (needed > left) {
      fail(what + ": its block needs " + std::to_string(needed) + " base64 characters from byte " + std::to_string(at) +
           ", but the file has " + std::to_string(left) + " (cut short)");
    }
    return b;
  }

  // Base64 characters of a block: uncompressed, header and data are one
  // run; compressed, the header is a run of its own.
  uint64_t stream_chars(const Block& b) const {
    return layout_.compressed ? encoded_size(b.header) + encoded_size(b.stored) : encoded_size(b.header + b.stored);
  }

  Block inline_block(const std::string& what, std::string_view text, const std::optional<uint64_t>& expected,
                     const std::string& declared, Where& where) const {
    where.base64 = true;
    where.text.reserve(text.size());
    for (char c : text) {
      if (c != ' ' && c != '\n' && c != '\r' && c != '\t') where.text += c;
    }
    const uint64_t word = layout_.header_bytes;
    const std::string head = base64_decode(where.text, 3 * word);
    std::string all = head;
    if (layout_.compressed && head.size() == 3 * word) {
      const uint64_t blocks = header_int(head, 0);
      if (blocks <= file_.size() / word) all = base64_decode(where.text, (3 + blocks) * word);
    }
    const Block b = parse_header(what, head, all);
    check_content(what, b, expected, declared);
    const uint64_t have = base64_chars(where.text);
    const uint64_t needed = stream_chars(b);
    if (needed > have) {
      fail(what + ": its inline data needs " + std::to_string(needed) + " base64 characters, but has " +
           std::to_string(have) + " (cut short)");
    }
    return b;
  }

  // `n` bytes of a block from byte `from` of its data run (the header is
  // the start of that run when uncompressed, a run of its own otherwise).
  std::string block_bytes(const Where& w, const Block& b, uint64_t from, uint64_t n) const {
    if (!w.base64) return file_.read(w.at + (layout_.compressed ? b.header : 0) + from, n);
    const uint64_t run = layout_.compressed ? encoded_size(b.header) : 0;
    const uint64_t first_char = run + from / 3 * 4;
    const uint64_t chars = encoded_size(n + from % 3) + 4;
    const std::string enc = w.appended ? file_.read(w.at + first_char, chars)
                                       : std::string(std::string_view(w.text).substr(std::min<size_t>(first_char, w.text.size()), chars));
    const std::string dec = base64_decode(enc, n + from % 3);
    return dec.size() > from % 3 ? dec.substr(from % 3) : std::string();
  }

  // Every byte a block holds (inflated when zlib-compressed); none when that
  // cannot be had cheaply (another compressor, more than 64 MiB, a damaged
  // block: VTK would report it, and the cells are only named in a note).
  std::optional<std::string> content(const Where& w, const Block& b) const {
    if (b.content > (uint64_t(1) << 26)) return std::nullopt;
    if (!layout_.compressed) return block_bytes(w, b, b.header, b.content);
    if (!layout_.zlib) return std::nullopt;
    std::string out;
    uint64_t at = 0;
    for (size_t k = 0; k < b.sizes.size(); ++k) {
      const std::string packed = block_bytes(w, b, at, b.sizes[k]);
      const uint64_t plain_size = k + 1 == b.sizes.size() ? b.last_content : b.block_size;
      const size_t start = out.size();
      out.resize(start + plain_size);
      uLongf got = static_cast<uLongf>(plain_size);
      if (::uncompress(reinterpret_cast<Bytef*>(out.data() + start), &got, reinterpret_cast<const Bytef*>(packed.data()),
                       static_cast<uLong>(packed.size())) != Z_OK || got != plain_size) {
        return std::nullopt;
      }
      at += b.sizes[k];
    }
    return out;
  }

  // The kinds of cells of an unstructured grid, from its types array.
  void cell_types(const Where& w, const Block& b, const std::string& format, std::string_view text,
                  const std::string& type) {
    if (format == "ascii") {
      size_t k = 0;
      while (k < text.size()) {
        const size_t s = text.find_first_not_of(" \n\r\t", k);
        if (s == std::string_view::npos) break;
        size_t e = text.find_first_of(" \n\r\t", s);
        if (e == std::string_view::npos) e = text.size();
        int64_t v = 0;
        if (std::from_chars(text.data() + s, text.data() + e, v).ec == std::errc()) facts_.cell_types.insert(v);
        k = e;
      }
      return;
    }
    if (type != "UInt8" && type != "Int8") return;
    const std::optional<std::string> bytes = content(w, b);
    if (!bytes) return;
    std::array<bool, 256> seen{};
    for (const char c : *bytes) seen[static_cast<unsigned char>(c)] = true;
    for (int t = 0; t < 256; ++t) {
      if (seen[t]) facts_.cell_types.insert(type == "Int8" ? static_cast<int8_t>(t) : t);
    }
  }

  // The last value of an integer array (the end of a cell list), or none
  // when it cannot be had cheaply (another compressor, a damaged block:
  // VTK then reports the block itself).
  std::optional<int64_t> last_value(const Where& w, const Block& b, const std::string& type) const {
    const uint64_t size = type_size(type);
    if (size == 0 || b.content < size || type.rfind("Float", 0) == 0) return std::nullopt;
    std::string bytes;
    if (!layout_.compressed) {
      bytes = block_bytes(w, b, b.header + b.content - size, size);
    } else {
      if (!layout_.zlib || b.last_content < size || b.last_content > (uint64_t(1) << 26)) return std::nullopt;
      const std::string packed = block_bytes(w, b, b.before_last, b.last_stored);
      std::string plain(b.last_content, '\0');
      uLongf got = static_cast<uLongf>(plain.size());
      if (::uncompress(reinterpret_cast<Bytef*>(plain.data()), &got, reinterpret_cast<const Bytef*>(packed.data()),
                       static_cast<uLong>(packed.size())) != Z_OK || got != plain.size()) {
        return std::nullopt;
      }
      bytes = plain.substr(plain.size() - size);
    }
    if (bytes.size() != size) return std::nullopt;
    uint64_t v = 0;
    for (uint64_t k = 0; k < size; ++k) {
      const auto byte = static_cast<unsigned char>(bytes[k]);
      v |= static_cast<uint64_t>(byte) << (layout_.big_endian ? 8 * (size - 1 - k) : 8 * k);
    }
    if (type.rfind("Int", 0) == 0 && size < 8 && (v >> (8 * size - 1)) != 0) return -1;  // negative
    return static_cast<int64_t>(v);
  }

  // Checks every value is a number and that there are at least `values`
  // (0: unknown); returns how many there are and the last one.
  uint64_t ascii_values(const std::string& what, std::string_view text, uint64_t values, const std::string& declared,
                        std::string_view& last) const {
    uint64_t words = 0;
    size_t k = 0;
    while (k < text.size()) {
      const size_t b = text.find_first_not_of(" \n\r\t", k);
      if (b == std::string_view::npos) break;
      size_t e = text.find_first_of(" \n\r\t", b);
      if (e == std::string_view::npos) e = text.size();
      double v = 0;
      const char* first = text.data() + b + (text[b] == '+' ? 1 : 0);
      const auto [end, ec] = std::from_chars(first, text.data() + e, v);
      if (end != text.data() + e || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
        fail(what + ": value " + std::to_string(words + 1) + " is '" + std::string(text.substr(b, std::min<size_t>(e - b, 40))) +
             "', not a number");
      }
      last = text.substr(b, e - b);
      ++words;
      k = e;
    }
    if (words < values) {
      fail(what + ": declares " + declared + " (" + std::to_string(values) + " values), but holds " +
           std::to_string(words) + " (cut short, or the count is wrong)");
    }
    return words;
  }

  std::string path_;
  File file_;
  Layout layout_;
  Section section_;
  std::optional<uint64_t> points_;
  std::optional<uint64_t> cells_;
  std::optional<uint64_t> connectivity_;  // values in the current cell list's connectivity
  Where where_;                           // of the last DataArray
  Block block_;
  XmlFacts facts_;
};

}  // namespace

std::vector<std::string> XmlFacts::non_vertex_cells() const {
  std::vector<std::string> names = cell_lists;
  for (const std::string& n : non_vertex_names(cell_types)) names.push_back(n);
  return names;
}

XmlFacts check_vtk_xml(const std::string& path) { return Checker(path).run(); }

std::vector<std::string> check_parallel_xml(const std::string& path, XmlFacts& facts) {
  const File file(path);
  uint64_t appended_at = 0;
  const std::string text = file.markup(appended_at);
  TagScanner scanner(text, path, kKind);
  XmlTag tag;
  const fs::path folder = fs::path(path).parent_path();
  std::vector<std::string> pieces;
  while (scanner.next(tag)) {
    if (tag.name != "Piece") continue;
    const std::string* source = tag.attribute("Source");
    const std::string where = "line " + std::to_string(tag.line) + ": piece ";
    if (!source || source->empty()) throw Error({path}, where + "without a Source attribute");
    const fs::path rel(*source);
    const fs::path normal = rel.lexically_normal();
    if (rel.is_absolute() || (!normal.empty() && *normal.begin() == "..")) {
      throw Error({path}, where + "'" + *source + "' lies outside the folder of this file; pieces must be beside it or below it");
    }
    std::string ext = normal.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext != ".vtu" && ext != ".vtp") {
      throw Error({path}, where + "'" + *source + "' is not a .vtu or .vtp file (a parallel file cannot hold another)");
    }
    const std::string piece = (folder / normal).string();
    std::error_code ec;
    if (!fs::is_regular_file(piece, ec)) throw Error({path}, where + "'" + *source + "' does not exist");
    const XmlFacts piece_facts = check_vtk_xml(piece);
    facts.cell_types.insert(piece_facts.cell_types.begin(), piece_facts.cell_types.end());
    for (const auto& list : piece_facts.cell_lists) {
      if (std::find(facts.cell_lists.begin(), facts.cell_lists.end(), list) == facts.cell_lists.end()) facts.cell_lists.push_back(list);
    }
    pieces.push_back(piece);
  }
  if (pieces.empty()) throw Error({path}, "the file lists no pieces");
  return pieces;
}

}  // namespace sluice::import::detail
