// The MPI conversion's collectives (convert_mpi.cpp): every one is called
// by every rank of the communicator in the same order. Errors are agreed
// (the lowest rank's broadcast) before any rank throws, so no rank is left
// waiting in a collective another has left.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sluice/error.h"

namespace sluice::import {

struct Ranks {
  MPI_Comm comm;
  int rank = 0, size = 1;
  bool root() const { return rank == 0; }
};

// `bytes` of rank `from` on every rank.
std::vector<std::byte> broadcast(const Ranks& r, std::vector<std::byte> bytes, int from = 0);
// Every rank's bytes, concatenated in rank order, on rank 0 (empty elsewhere).
std::vector<std::byte> gather(const Ranks& r, const std::vector<std::byte>& mine);

// Returns once every rank has called it, sleeping meanwhile. MPI's own
// waits spin on a core, which a rank's reader processes (isolation.h) and
// the ranks still encoding need: a rank that finished its frames early
// would slow those that did not.
void wait_for_all(const Ranks& r);

// Throws on every rank the error of the lowest rank that has one (none: returns).
void agree(const Ranks& r, const std::optional<io::Error>& mine);
// Runs `step` on this rank; what it throws is thrown on every rank alike.
void on_each(const Ranks& r, const std::function<void()>& step);
// Runs `step` on rank 0; what it throws is thrown on every rank alike.
void on_root(const Ranks& r, const std::function<void()>& step);

std::string mpi_error_text(int code);

// The output file, opened by every rank (created, emptied), closed
// collectively (or by the destructor, which every rank reaches alike).
class SharedFile {
 public:
  SharedFile(const Ranks& r, const std::string& path);  // throws io::Error on every rank
  ~SharedFile();
  SharedFile(const SharedFile&) = delete;
  SharedFile& operator=(const SharedFile&) = delete;

  // One rank's own write (rank 0's header and index). Throws io::Error.
  void write_at(uint64_t at, std::span<const std::byte> bytes);
  // Every rank's records, contiguous from `at`, in one collective write
  // (no copy: the records are described where they lie). Returns MPI's code.
  int write_records_at_all(uint64_t at, const std::vector<const std::vector<std::byte>*>& records);
  // Collective. Returns MPI's code.
  int sync_and_close();

 private:
  std::string path_;
  MPI_File file_ = MPI_FILE_NULL;
};

}  // namespace sluice::import
