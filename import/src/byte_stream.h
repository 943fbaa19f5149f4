// Private: a forward cursor over a file for formats that mix text words and
// raw bytes (legacy VTK). Reads through a bounded buffer, so memory does not
// follow the file's size, and knows how many bytes remain before anything
// is read: callers check a declared size against remaining() first.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <memory>
#include <vector>

namespace sluice::import::detail {

class ByteStream {
 public:
  // Throws io::Error naming `path` when it cannot be opened.
  explicit ByteStream(const std::string& path);
  ~ByteStream();
  ByteStream(const ByteStream&) = delete;
  ByteStream& operator=(const ByteStream&) = delete;

  const std::string& path() const { return path_; }
  uint64_t size() const { return size_; }
  uint64_t offset() const { return base_ + pos_; }  // of the next byte
  uint64_t remaining() const { return size_ - offset(); }
  // 1-based line of the next byte, counting the newlines passed by word()
  // and line(); raw bytes are not counted (meaningless in binary data).
  uint64_t line_number() const { return line_; }

  // The next whitespace-separated word, empty at the end of the file. Valid
  // until the next call. Throws when a word is longer than kLongestWord.
  std::string_view word();
  // The rest of the current line without its newline (and '\r'); consumes
  // the newline. Empty at the end of the file.
  std::string_view line();
  // Copies `n` bytes; throws when fewer remain.
  void read(void* into, uint64_t n);
  // Moves past `n` bytes; throws when fewer remain.
  void skip(uint64_t n);

  static constexpr size_t kLongestWord = 4096;

 private:
  // Makes at least `want` bytes available at pos_ (fewer only at the end).
  size_t available(size_t want);

  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
  std::unique_ptr<char[]> buffer_;  // kBufferBytes, not zeroed
  size_t capacity_ = 0;
  uint64_t base_ = 0;  // file offset of buffer_[0]
  size_t pos_ = 0;
  size_t end_ = 0;
  uint64_t line_ = 1;
};

}  // namespace sluice::import::detail
