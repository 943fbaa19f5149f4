#include "sluice/io/writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>

#include "file.h"

namespace sluice::io {

ContainerWriter::ContainerWriter(const std::filesystem::path& path, FileHeader header)
    : path_(path.string()), header_(std::move(header)), index_(header_.attributes.size()) {
  if (header_.attributes.size() > kMaxAttributes) throw Error({path_}, "too many attributes (limit 32)");
  for (const AttributeInfo& a : header_.attributes) {
    if (a.name.empty() || a.name.size() > kMaxNameBytes) throw Error({path_}, "attribute name is empty or too long");
  }
  fd_ = open_or_throw(path_, O_WRONLY | O_CREAT | O_TRUNC);
  write_all(container_head(header_));
}

ContainerWriter::~ContainerWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void ContainerWriter::write_all(std::span<const std::byte> bytes) {
  if (failed_) throw Error({path_}, "an earlier write to this file failed; nothing more is written");
  try {
    write_all_or_throw(fd_, bytes, path_);
  } catch (...) {
    failed_ = true;  // the file now ends inside a record: no index may follow it
    throw;
  }
  offset_ += bytes.size();
}

void ContainerWriter::append(EncodedFrame frame) {
  if (fd_ < 0) throw Error({path_}, "append after finish");
  const auto number = static_cast<uint32_t>(frames_written());
  if (frame.header.frame_number != number) set_frame_number(frame, number, header_.attributes.size());
  const uint64_t at = offset_;
  write_all(frame.record);
  index_.add(frame.header, at);  // only frames wholly written are indexed
}

void ContainerWriter::update_header(const FileHeader& header) {
  if (fd_ < 0) throw Error({path_}, "header update after finish");
  if (failed_) throw Error({path_}, "an earlier write to this file failed; the header is not rewritten");
  const std::vector<std::byte> head = container_head(header);
  if (head.size() != container_head(header_).size() || header.attributes.size() != header_.attributes.size() ||
      header.position_coding != header_.position_coding) {
    throw Error({path_}, "header update would change its size or the frames' layout");
  }
  if (::pwrite(fd_, head.data(), head.size(), 0) != ssize_t(head.size())) {
    throw Error({path_}, "could not rewrite the file header");
  }
  header_ = header;
}

void ContainerWriter::finish() {
  if (fd_ < 0) return;
  write_all(container_tail(index_.index(), header_.attributes.size(), offset_));
  if (::fsync(fd_) != 0 || ::close(fd_) != 0) {
    fd_ = -1;
    throw Error({path_}, "could not flush the file to disk");
  }
  fd_ = -1;
}

}  // namespace sluice::io
