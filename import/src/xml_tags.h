// Private: just enough XML for the files sluice checks or plans from (.pvd,
// .pvtu/.pvtp, the headers of .vtu/.vtp): start tags with their attributes
// and the text that follows them. Comments, declarations and end tags are
// skipped; broken markup throws io::Error naming the file and line.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>

namespace sluice::import::detail {

// A start (or empty-element) tag.
struct XmlTag {
  std::string name;
  std::map<std::string, std::string> attributes;  // entities decoded
  uint64_t line = 0;
  bool empty = false;  // <tag/>: no text and no children
  size_t end = 0;      // offset just past the tag's '>'

  const std::string* attribute(const char* key) const {
    const auto it = attributes.find(key);
    return it == attributes.end() ? nullptr : &it->second;
  }
};

class TagScanner {
 public:
  // `kind` ends error messages: "... (not a valid .pvd file)".
  TagScanner(std::string_view text, std::string path, std::string kind)
      : text_(text), path_(std::move(path)), kind_(std::move(kind)) {}

  // The next start tag; false at the end of the text.
  bool next(XmlTag& tag);
  // The character data from the end of the last tag to the next '<'.
  std::string_view text_after(const XmlTag& tag) const;

 private:
  [[noreturn]] void fail(const std::string& msg) const;
  void advance_to(size_t p);
  void skip_past(std::string_view end, const char* what);
  bool skip_special();
  void skip_space();
  std::string read_name(const char* what);
  void parse_tag(XmlTag& tag);

  std::string_view text_;
  std::string path_;
  std::string kind_;
  size_t pos_ = 0;
  uint64_t line_ = 1;
};

// The five predefined entities and numeric character references.
std::string decode_entities(std::string_view s);

}  // namespace sluice::import::detail
