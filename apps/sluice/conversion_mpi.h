// `sluice convert --mpi`: import::convert_mpi() over the ranks mpirun (or
// srun) started, shown as convert_and_report shows a conversion, by rank 0.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "conversion.h"

namespace sluice::app {

// Initializes MPI, converts, finalizes. Rank 0 prints the plan, progress
// and notes and gets the summary; other ranks print nothing and get none.
// A stopped conversion is rethrown on rank 0 as convert_and_report does.
// Other ranks end in ExitCode{0} once they share the error: one that ended
// non-zero would make mpirun kill the job, rank 0 perhaps before it has
// said why; mpirun's status is then rank 0's. An error that is not one the
// ranks share (an exception on one rank) aborts the job.
// `check` runs on rank 0 first (the output exists and is not to be
// overwritten, ...); what it throws is rank 0's error, and every rank stops.
std::optional<import::ConvertSummary> convert_mpi_and_report(const import::ConvertOptions& options,
                                                             const std::string& output, const ConversionReport& report,
                                                             const std::function<void()>& check = {});

}  // namespace sluice::app
