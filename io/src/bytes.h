// Little-endian byte serialization with bounds checks on every read.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "sluice/error.h"

namespace sluice::io {

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::byte>& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(std::byte{v}); }
  void u16(uint16_t v) { put(v); }
  void u32(uint32_t v) { put(v); }
  void u64(uint64_t v) { put(v); }
  void f32(float v) { put(v); }
  void f64(double v) { put(v); }
  void bytes(const void* data, size_t n);
  // Length-prefixed (u8) string; longer names are a programming error upstream.
  void name(const std::string& s);
  // Length-prefixed (u16) string, truncated to 65535 bytes.
  void text(const std::string& s);
  size_t size() const { return out_.size(); }

 private:
  template <class T>
  void put(T v) {
    static_assert(std::endian::native == std::endian::little, "sluice assumes a little-endian host");
    // resize + memcpy, not insert: GCC 12 reports a false -Wstringop-overflow
    // for vector::insert of a few bytes inlined here.
    const size_t at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &v, sizeof(T));
  }
  std::vector<std::byte>& out_;
};

// Reads fields in order; any read past the end throws io::Error at `where`
// with "truncated <what>". Borrows `where` and `what` (they must outlive it):
// a frame's record is parsed without building its location.
class ByteReader {
 public:
  ByteReader(std::span<const std::byte> data, const ErrorLocation& where, const char* what)
      : data_(data), where_(where), what_(what) {}
  uint8_t u8() { return get<uint8_t>(); }
  uint16_t u16() { return get<uint16_t>(); }
  uint32_t u32() { return get<uint32_t>(); }
  uint64_t u64() { return get<uint64_t>(); }
  float f32() { return get<float>(); }
  double f64() { return get<double>(); }
  std::string name();
  std::string text();
  void skip(size_t n);
  size_t position() const { return pos_; }
  size_t remaining() const { return data_.size() - pos_; }
  [[noreturn]] void fail(const std::string& message) const;

 private:
  void need(size_t n) const;
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::span<const std::byte> data_;
  size_t pos_ = 0;
  const ErrorLocation& where_;
  const char* what_;
};

uint64_t checksum(std::span<const std::byte> data);

}  // namespace sluice::io
