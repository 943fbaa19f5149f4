#include "sluice/bench/table.h"

#include <algorithm>
#include <cstdio>

namespace sluice::bench {

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string count_name(uint64_t n) {
  if (n >= 1'000'000 && n % 100'000 == 0) return fixed(double(n) / 1e6, n % 1'000'000 ? 1 : 0) + "M";
  if (n >= 1'000) return fixed(double(n) / 1e3, n % 1000 ? 1 : 0) + "k";
  return std::to_string(n);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

void Table::print(const std::string& title) const {
  std::vector<size_t> width(header_.size());
  for (size_t c = 0; c < header_.size(); ++c) width[c] = header_[c].size();
  for (const auto& r : rows_)
    for (size_t c = 0; c < r.size() && c < width.size(); ++c) width[c] = std::max(width[c], r[c].size());
  std::printf("\n%s\n", title.c_str());
  auto line = [&](const std::vector<std::string>& cells) {
    std::string out = " ";
    for (size_t c = 0; c < width.size(); ++c) {
      const std::string cell = c < cells.size() ? cells[c] : "";
      const std::string pad(width[c] - cell.size(), ' ');
      out += " " + (c == 0 ? cell + pad : pad + cell) + " ";
    }
    std::printf("%s\n", out.c_str());
  };
  line(header_);
  std::string rule;
  for (size_t c = 0; c < width.size(); ++c) rule += " " + std::string(width[c] + 1, '-');
  std::printf(" %s\n", rule.c_str());
  for (const auto& r : rows_) line(r);
}

}  // namespace sluice::bench
