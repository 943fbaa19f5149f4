// Values packed into bytes and back, for what MPI ranks send each other
// (convert_mpi.cpp): fixed-width little-endian numbers and sized strings.
// A reader that runs out of bytes throws io::Error: a message cut short is
// an error, never a read past its end.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "sluice/error.h"

namespace sluice::import {

class WireWriter {
 public:
  template <class T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof v);
  }
  void put_bytes(std::span<const std::byte> b) {
    put<uint64_t>(b.size());
    bytes_.insert(bytes_.end(), b.begin(), b.end());
  }
  void put_string(const std::string& s) { put_bytes(std::as_bytes(std::span(s.data(), s.size()))); }
  std::vector<std::byte>& bytes() { return bytes_; }

 private:
  std::vector<std::byte> bytes_;
};

class WireReader {
 public:
  explicit WireReader(std::span<const std::byte> bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    std::memcpy(&v, take(sizeof v).data(), sizeof v);
    return v;
  }
  std::span<const std::byte> get_bytes() { return take(get<uint64_t>()); }
  std::string get_string() {
    const std::span<const std::byte> b = get_bytes();
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  bool done() const { return at_ == bytes_.size(); }
  size_t remaining() const { return bytes_.size() - at_; }

 private:
  std::span<const std::byte> take(uint64_t n) {
    if (n > bytes_.size() - at_) throw io::Error({}, "a message between MPI ranks is cut short");
    const std::span<const std::byte> b = bytes_.subspan(at_, n);
    at_ += n;
    return b;
  }
  std::span<const std::byte> bytes_;
  size_t at_ = 0;
};

}  // namespace sluice::import
