// Natural ordering of file names and glob expansion in that order, so that a
// numbered series without zero padding (frame_2, frame_10) plays in order.
#include <glob.h>
#include <sys/stat.h>

#include <algorithm>
#include <string_view>

#include "sluice/error.h"
#include "sluice/import/source.h"

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Length of the digit run starting at s[i].
size_t digit_run(std::string_view s, size_t i) {
  size_t j = i;
  while (j < s.size() && is_digit(s[j])) ++j;
  return j - i;
}

// Compares two digit runs by value without converting them (runs may be
// longer than any integer type). Returns <0, 0, >0.
int compare_numbers(std::string_view a, std::string_view b) {
  const auto strip = [](std::string_view s) {
    const size_t nz = s.find_first_not_of('0');
    return nz == std::string_view::npos ? std::string_view{} : s.substr(nz);
  };
  const std::string_view sa = strip(a);
  const std::string_view sb = strip(b);
  if (sa.size() != sb.size()) return sa.size() < sb.size() ? -1 : 1;
  return sa.compare(sb);
}

// Ordering that treats digit runs as numbers; 0 when the strings differ
// only in zero padding.
int natural_compare(std::string_view a, std::string_view b) {
  size_t i = 0;
  size_t j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      const size_t na = digit_run(a, i);
      const size_t nb = digit_run(b, j);
      if (const int c = compare_numbers(a.substr(i, na), b.substr(j, nb)); c != 0) return c;
      i += na;
      j += nb;
      continue;
    }
    const auto ca = static_cast<unsigned char>(a[i]);
    const auto cb = static_cast<unsigned char>(b[j]);
    if (ca != cb) return ca < cb ? -1 : 1;
    ++i;
    ++j;
  }
  const bool a_left = i < a.size();
  const bool b_left = j < b.size();
  if (a_left == b_left) return 0;
  return a_left ? 1 : -1;
}

bool is_regular_file(const char* path) {
  struct stat st {};
  return ::stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  const int c = natural_compare(a, b);
  // Ties (frame_01 vs frame_1) fall back to plain order: a strict total order.
  return c != 0 ? c < 0 : a < b;
}

std::vector<std::string> expand_glob_natural(const std::string& pattern) {
  glob_t g{};
  const int rc = ::glob(pattern.c_str(), GLOB_NOSORT, nullptr, &g);
  std::vector<std::string> files;
  if (rc == 0) {
    files.reserve(g.gl_pathc);
    for (size_t k = 0; k < g.gl_pathc; ++k) {
      // Directories matching the pattern are not frames.
      if (is_regular_file(g.gl_pathv[k])) files.emplace_back(g.gl_pathv[k]);
    }
  }
  globfree(&g);
  if (rc != 0 && rc != GLOB_NOMATCH) {
    throw Error({pattern}, rc == GLOB_NOSPACE ? "out of memory while expanding the pattern"
                                              : "cannot read a directory while expanding the pattern");
  }
  std::sort(files.begin(), files.end(), natural_less);
  return files;
}

}  // namespace sluice::import
