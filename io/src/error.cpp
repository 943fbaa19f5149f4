#include "sluice/error.h"

namespace sluice::io {

std::string format_location(const ErrorLocation& where) {
  std::string out = where.file.empty() ? std::string("<memory>") : where.file;
  if (where.frame) out += ": frame " + std::to_string(*where.frame);
  if (where.chunk) out += (where.frame ? ", chunk " : ": chunk ") + std::to_string(*where.chunk);
  return out;
}

Error::Error(ErrorLocation where, const std::string& message)
    : sluice::Error(format_location(where) + ": " + message),
      where_(std::move(where)),
      message_(message) {}

}  // namespace sluice::io
