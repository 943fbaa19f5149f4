// What a benchmark says about the machine it ran on.
#pragma once

#include <string>

namespace sluice::bench {

std::string cpu_model();  // from /proc/cpuinfo
int core_count();         // TBB's default concurrency (cgroup-aware)
// Copies a 256 MiB buffer on one thread: the memcpy bound in GB/s.
double memcpy_gbps(double min_seconds);

}  // namespace sluice::bench
