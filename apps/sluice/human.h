// Numbers for people: sizes, counts, rates and durations.
#pragma once

#include <cstdint>
#include <string>

#include "sluice/bench/table.h"

namespace sluice::io {
struct FileHeader;
}

namespace sluice::app {

std::string human_bytes(double bytes);      // "12.3 MB" (decimal units, as drives and networks count)
std::string human_count(double n);          // "9,360" below a million, else "1.09 M"
std::string human_duration(double seconds); // "0.84 s", "3:05", "1:02:09"
using bench::fixed;                         // the tables' own: one way to print a number
// A fraction as a percentage with one decimal: 0.234 -> "23.4%".
std::string percent(double fraction);

// What a file promises about its positions: exact, a stated bound (format
// 1.5), or 16 bits per chunk box without one.
std::string precision_text(const io::FileHeader& h);

}  // namespace sluice::app
