#include "sluice/io/writer.h"

#include <algorithm>

#include "records.h"

namespace sluice::io {

std::vector<std::byte> container_head(const FileHeader& header) {
  std::vector<std::byte> head = serialize_file_header(header);
  const std::vector<std::byte> copy = serialize_header_copy(head);
  head.insert(head.end(), copy.begin(), copy.end());
  return head;
}

FileHeader parse_container_head(std::span<const std::byte> head, const ErrorLocation& where) {
  return parse_file_header(head, where);  // checks the size it states against what is there
}

std::vector<std::byte> container_tail(const FrameIndex& index, size_t attribute_count, uint64_t at) {
  std::vector<std::byte> tail = serialize_index(index, attribute_count);
  const std::vector<std::byte> footer = serialize_footer({at, tail.size()});
  tail.insert(tail.end(), footer.begin(), footer.end());
  return tail;
}

}  // namespace sluice::io
