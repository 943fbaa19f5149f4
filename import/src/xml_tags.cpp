// A small XML tag scanner: no DOM, no validation beyond well-formed tags.
#include "xml_tags.h"

#include <algorithm>
#include <cctype>
#include <charconv>

#include "sluice/error.h"

namespace sluice::import::detail {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)

std::string decode_entities(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    const size_t semi = s[i] == '&' ? s.find(';', i) : std::string_view::npos;
    if (semi == std::string_view::npos || semi - i > 10) {
      out += s[i];
      continue;
    }
    const std::string_view ent = s.substr(i + 1, semi - i - 1);
    uint32_t code = 0;
    if (ent == "amp") code = '&';
    else if (ent == "lt") code = '<';
    else if (ent == "gt") code = '>';
    else if (ent == "quot") code = '"';
    else if (ent == "apos") code = '\'';
    else if (ent.size() > 1 && ent[0] == '#') {
      const bool hex = ent[1] == 'x' || ent[1] == 'X';
      const std::string_view digits = ent.substr(hex ? 2 : 1);
      std::from_chars(digits.data(), digits.data() + digits.size(), code, hex ? 16 : 10);
    }
    if (code == 0 || code > 0x10FFFF) {
      out += s[i];
      continue;
    }
    if (code < 0x80) {
      out += static_cast<char>(code);
    } else if (code < 0x800) {
      out += static_cast<char>(0xC0 | (code >> 6));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else if (code < 0x10000) {
      out += static_cast<char>(0xE0 | (code >> 12));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (code >> 18));
      out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    }
    i = semi;
  }
  return out;
}

bool TagScanner::next(XmlTag& tag) {
  while (true) {
    const size_t lt = text_.find('<', pos_);
    if (lt == std::string_view::npos) return false;
    advance_to(lt);
    if (skip_special()) continue;
    if (text_.substr(pos_, 2) == "</") {
      skip_past(">", "end tag");
      continue;
    }
    parse_tag(tag);
    return true;
  }
}

std::string_view TagScanner::text_after(const XmlTag& tag) const {
  if (tag.empty || tag.end >= text_.size()) return {};
  const size_t lt = text_.find('<', tag.end);
  return text_.substr(tag.end, (lt == std::string_view::npos ? text_.size() : lt) - tag.end);
}

void TagScanner::fail(const std::string& msg) const {
  throw Error({path_}, "line " + std::to_string(line_) + ": " + msg + " (" + kind_ + ")");
}

void TagScanner::advance_to(size_t p) {
  line_ += static_cast<uint64_t>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                            text_.begin() + static_cast<std::ptrdiff_t>(p), '\n'));
  pos_ = p;
}

void TagScanner::skip_past(std::string_view end, const char* what) {
  const size_t e = text_.find(end, pos_);
  if (e == std::string_view::npos) fail(std::string("unterminated ") + what);
  advance_to(e + end.size());
}

// Comments, <?xml ...?>, <!DOCTYPE ...>.
bool TagScanner::skip_special() {
  if (text_.substr(pos_, 4) == "<!--") {
    skip_past("-->", "comment");
  } else if (text_.substr(pos_, 2) == "<?") {
    skip_past("?>", "declaration");
  } else if (text_.substr(pos_, 2) == "<!") {
    skip_past(">", "declaration");
  } else {
    return false;
  }
  return true;
}

namespace {
bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':' || c == '-' || c == '.';
}
}  // namespace

void TagScanner::skip_space() {
  while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) advance_to(pos_ + 1);
}

std::string TagScanner::read_name(const char* what) {
  const size_t start = pos_;
  while (pos_ < text_.size() && name_char(text_[pos_])) ++pos_;
  if (pos_ == start) fail(std::string("expected ") + what);
  return std::string(text_.substr(start, pos_ - start));
}

void TagScanner::parse_tag(XmlTag& tag) {
  tag = XmlTag{};
  tag.line = line_;
  ++pos_;  // '<'
  tag.name = read_name("an element name after '<'");
  while (true) {
    skip_space();
    if (pos_ >= text_.size()) fail("unterminated <" + tag.name + "> tag");
    if (text_[pos_] == '>') {
      tag.end = ++pos_;
      return;
    }
    if (text_.substr(pos_, 2) == "/>") {
      tag.end = pos_ += 2;
      tag.empty = true;
      return;
    }
    const std::string key = read_name("an attribute name");
    skip_space();
    if (pos_ >= text_.size() || text_[pos_] != '=') fail("expected '=' after attribute " + key);
    ++pos_;
    skip_space();
    const char quote = pos_ < text_.size() ? text_[pos_] : '\0';
    if (quote != '"' && quote != '\'') fail("attribute " + key + " has no quoted value");
    const size_t close = text_.find(quote, pos_ + 1);
    if (close == std::string_view::npos) fail("unterminated value of attribute " + key);
    tag.attributes[key] = decode_entities(text_.substr(pos_ + 1, close - pos_ - 1));
    advance_to(close + 1);
  }
}

}  // namespace sluice::import::detail
