#include "mpi_collectives.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <thread>

#include "mpi_messages.h"

namespace sluice::import {

using io::Error;
namespace {

int checked_int(uint64_t n, const char* what) {
  if (n > uint64_t(INT_MAX)) throw Error({}, std::string(what) + " is over 2 GiB: too large for one MPI message");
  return int(n);
}

}  // namespace

std::vector<std::byte> broadcast(const Ranks& r, std::vector<std::byte> bytes, int from) {
  uint64_t n = bytes.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, from, r.comm);
  bytes.resize(n);
  MPI_Bcast(bytes.data(), checked_int(n, "a broadcast"), MPI_BYTE, from, r.comm);
  return bytes;
}

void wait_for_all(const Ranks& r) {
  MPI_Request arrived;
  MPI_Ibarrier(r.comm, &arrived);
  for (int done = 0;;) {
    MPI_Test(&arrived, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void agree(const Ranks& r, const std::optional<Error>& mine) {
  wait_for_all(r);  // (rank 0 may have worked long: reading the first frames)
  const int have = mine ? r.rank : INT_MAX;
  int lowest = INT_MAX;
  MPI_Allreduce(&have, &lowest, 1, MPI_INT, MPI_MIN, r.comm);
  if (lowest == INT_MAX) return;
  WireWriter w;
  if (r.rank == lowest) put_error(w, *mine);
  const std::vector<std::byte> bytes = broadcast(r, std::move(w.bytes()), lowest);
  WireReader read(bytes);
  throw get_error(read);
}

void on_each(const Ranks& r, const std::function<void()>& step) {
  std::optional<Error> failed;
  try {
    step();
  } catch (const Error& e) {
    failed = e;
  } catch (const std::exception& e) {
    failed = Error({}, e.what());
  }
  agree(r, failed);
}

void on_root(const Ranks& r, const std::function<void()>& step) {
  on_each(r, [&] {
    if (r.root()) step();
  });
}

std::vector<std::byte> gather(const Ranks& r, const std::vector<std::byte>& mine) {
  const int n = checked_int(mine.size(), "a rank's frame tables");
  std::vector<int> counts(size_t(r.root() ? r.size : 0)), at(counts.size());
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, r.comm);
  std::vector<std::byte> all;
  if (r.root()) {
    uint64_t total = 0;
    for (size_t i = 0; i < counts.size(); ++i) {
      at[i] = checked_int(total, "a round's frame tables");
      total += uint64_t(counts[i]);
    }
    all.resize(total);
  }
  MPI_Gatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), at.data(), MPI_BYTE, 0, r.comm);
  return all;
}

std::string mpi_error_text(int code) {
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  return std::string(text, size_t(length));
}

SharedFile::SharedFile(const Ranks& r, const std::string& path) : path_(path) {
  // Each rank writes one contiguous range a round: no collective buffering
  // (the standard's hint, and ROMIO's own name for it; OMPIO takes its
  // choice from the environment, which `sluice convert --mpi` sets).
  MPI_Info hints;
  MPI_Info_create(&hints);
  MPI_Info_set(hints, "collective_buffering", "false");
  MPI_Info_set(hints, "romio_cb_write", "disable");
  const int opened = MPI_File_open(r.comm, path.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY, hints, &file_);
  MPI_Info_free(&hints);
  std::optional<Error> failed;
  if (opened != MPI_SUCCESS) failed = Error({path}, "rank " + std::to_string(r.rank) + " could not create it: " + mpi_error_text(opened));
  try {
    agree(r, failed);
  } catch (...) {
    if (opened == MPI_SUCCESS) MPI_File_close(&file_);
    throw;
  }
  MPI_File_set_size(file_, 0);  // as O_TRUNC: a longer file of an earlier run is cut
}

SharedFile::~SharedFile() {
  if (file_ != MPI_FILE_NULL) MPI_File_close(&file_);
}

void SharedFile::write_at(uint64_t at, std::span<const std::byte> bytes) {
  for (uint64_t done = 0; done < bytes.size();) {
    const int n = int(std::min<uint64_t>(bytes.size() - done, 1u << 30));
    MPI_Status status;
    const int code = MPI_File_write_at(file_, MPI_Offset(at + done), bytes.data() + done, n, MPI_BYTE, &status);
    if (code != MPI_SUCCESS) throw Error({path_}, "could not write: " + mpi_error_text(code));
    done += uint64_t(n);
  }
}

int SharedFile::write_records_at_all(uint64_t at, const std::vector<const std::vector<std::byte>*>& records) {
  std::vector<int> lengths;
  std::vector<MPI_Aint> places;
  for (const std::vector<std::byte>* record : records) {
    for (uint64_t done = 0; done < record->size();) {
      const int n = int(std::min<uint64_t>(record->size() - done, 1u << 30));
      MPI_Aint place;
      MPI_Get_address(record->data() + done, &place);
      lengths.push_back(n);
      places.push_back(place);
      done += uint64_t(n);
    }
  }
  MPI_Datatype layout;
  MPI_Type_create_hindexed(int(lengths.size()), lengths.data(), places.data(), MPI_BYTE, &layout);
  MPI_Type_commit(&layout);
  MPI_Status status;
  const int code = MPI_File_write_at_all(file_, MPI_Offset(at), MPI_BOTTOM, lengths.empty() ? 0 : 1, layout, &status);
  MPI_Type_free(&layout);
  return code;
}

int SharedFile::sync_and_close() {
  const int synced = MPI_File_sync(file_);
  const int closed = MPI_File_close(&file_);
  return synced != MPI_SUCCESS ? synced : closed;
}

}  // namespace sluice::import
