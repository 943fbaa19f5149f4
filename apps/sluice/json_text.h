// JSON text for the commands' --json output: values written by hand (the
// output is small and flat), escaped as RFC 8259 asks.
#pragma once

#include <string>

namespace sluice::app {

// A quoted, escaped JSON string.
std::string json_string(const std::string& s);
// A JSON number with 9 significant digits; null for NaN and infinities.
std::string json_number(double v);

}  // namespace sluice::app
