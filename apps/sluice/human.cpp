#include "human.h"

#include <cmath>
#include <cstdio>

#include "sluice/io/format.h"

namespace sluice::app {

std::string human_bytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB"};
  int u = 0;
  while (std::fabs(bytes) >= 1000 && u < 4) bytes /= 1000, ++u;
  return fixed(bytes, u == 0 ? 0 : (bytes < 10 ? 2 : 1)) + " " + units[u];
}

std::string human_count(double n) {
  if (n >= 1e9) return fixed(n / 1e9, 2) + " G";
  if (n >= 1e6) return fixed(n / 1e6, 2) + " M";
  std::string digits = fixed(n, 0), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

std::string human_duration(double s) {
  if (!std::isfinite(s)) return "?";
  if (s < 60) return fixed(s, s < 10 ? 2 : 1) + " s";
  const auto t = static_cast<long>(std::lround(s));
  char buf[32];
  if (t < 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  else std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return buf;
}

}  // namespace sluice::app

namespace sluice::app {

std::string percent(double fraction) { return fixed(100.0 * fraction, 1) + "%"; }

std::string precision_text(const io::FileHeader& h) {
  const float bound = io::position_bound(h);
  if (bound == 0) return "exact (float32 positions)";
  if (!std::isfinite(bound)) return "16 bits per chunk box; no error bound stated (a file older than format 1.5, or no spacing)";
  char text[200];
  std::snprintf(text, sizeof text, "every position within %.3g of its source on each axis (1/%.0f of the spacing)",
                double(bound), std::ldexp(1.0, h.precision_bits));
  return text;
}

}  // namespace sluice::app
