#include "conversion_mpi.h"

#include <mpi.h>

#include <cstdio>
#include <cstdlib>

#include "commands.h"
#include "sluice/import/convert_mpi.h"

namespace sluice::app {
namespace {

// MPI from here to the end of the scope, on this (the main) thread.
class MpiSession {
 public:
  MpiSession() {
    // Each rank's records of a round are one contiguous range of the file,
    // so collective buffering (two-phase I/O: the bytes shuffled to
    // aggregator ranks first) only adds a copy. Open MPI's OMPIO chooses its
    // collective component at MPI_Init from the environment: its
    // `individual` one writes each rank's range itself. On the GPU machine
    // (16 ranks, 2.9 GB in one round) the write took 0.80 s against 2.09 s
    // (docs/convert_mpi.md). A choice the user made (OMPI_MCA_fcoll, or
    // mpirun --mca fcoll ...: on a parallel filesystem whose locks favour
    // aggregators) is kept.
    setenv("OMPI_MCA_fcoll", "individual", 0);
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  }
  ~MpiSession() { MPI_Finalize(); }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }

 private:
  int rank_ = 0;
};

}  // namespace

std::optional<import::ConvertSummary> convert_mpi_and_report(const import::ConvertOptions& options,
                                                             const std::string& output, const ConversionReport& report,
                                                             const std::function<void()>& check) {
  MpiSession mpi;
  int refused = 0;
  if (mpi.rank() == 0 && check) {
    try {
      check();
    } catch (...) {
      refused = 1;
      MPI_Bcast(&refused, 1, MPI_INT, 0, MPI_COMM_WORLD);
      throw;
    }
  }
  MPI_Bcast(&refused, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (refused) throw ExitCode{0};  // (a rank but 0: rank 0 says why)
  std::optional<ConversionPrinter> printer;
  if (mpi.rank() == 0) printer.emplace(report);
  try {
    const import::ConvertObserver observer = printer ? printer->observer() : import::ConvertObserver{};
    import::ConvertSummary summary = import::convert_mpi(options, output, MPI_COMM_WORLD, observer);
    if (!printer) return std::nullopt;
    printer->finish();
    return summary;
  } catch (const import::ConvertStopped& e) {  // every rank stopped alike: rank 0 says why
    if (!printer) throw ExitCode{0};
    printer->finish();
    rethrow_with_advice(e);
  } catch (const io::Error&) {  // every rank has the same error: rank 0 says it
    if (!printer) throw ExitCode{0};
    printer->finish();
    throw;
  } catch (const std::exception& e) {  // this rank's alone: the others may wait on it in vain
    std::fprintf(stderr, "sluice: error on rank %d: %s\n", mpi.rank(), e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
    throw;
  }
}

}  // namespace sluice::app
