#include "bytes.h"

namespace sluice::io {

void ByteWriter::bytes(const void* data, size_t n) {
  const auto* p = static_cast<const std::byte*>(data);
  out_.insert(out_.end(), p, p + n);
}

void ByteWriter::name(const std::string& s) {
  const size_t n = s.size() > 255 ? 255 : s.size();
  u8(static_cast<uint8_t>(n));
  bytes(s.data(), n);
}

void ByteWriter::text(const std::string& s) {
  const size_t n = s.size() > 65535 ? 65535 : s.size();
  u16(static_cast<uint16_t>(n));
  bytes(s.data(), n);
}

void ByteReader::need(size_t n) const {
  if (n > remaining()) {
    throw Error(where_, std::string("truncated ") + what_ + " (needs " + std::to_string(pos_ + n) + " bytes, has " +
                            std::to_string(data_.size()) + ")");
  }
}

void ByteReader::fail(const std::string& message) const { throw Error(where_, std::string(what_) + ": " + message); }

std::string ByteReader::name() {
  const size_t n = u8();
  need(n);
  std::string s(reinterpret_cast<const char*>(data_.data() + pos_), n);
  pos_ += n;
  return s;
}

std::string ByteReader::text() {
  const size_t n = u16();
  need(n);
  std::string s(reinterpret_cast<const char*>(data_.data() + pos_), n);
  pos_ += n;
  return s;
}

void ByteReader::skip(size_t n) {
  need(n);
  pos_ += n;
}

}  // namespace sluice::io
