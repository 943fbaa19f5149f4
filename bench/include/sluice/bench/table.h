// A plain text table: columns sized to their contents, numbers right-aligned.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sluice::bench {

class Table {
 public:
  explicit Table(std::vector<std::string> header) : header_(std::move(header)) {}
  void row(std::vector<std::string> cells) { rows_.push_back(std::move(cells)); }
  void print(const std::string& title) const;

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

// `v` with `decimals` digits after the point: fixed(2.345, 1) -> "2.3" (also the CLI's numbers).
std::string fixed(double v, int decimals);
// "1M", "2.5M", "100k", "950": particle counts in table rows.
std::string count_name(uint64_t n);
// The median of `v` (0 when empty).
double median(std::vector<double> v);

}  // namespace sluice::bench
