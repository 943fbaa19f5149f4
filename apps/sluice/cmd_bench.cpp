// `sluice bench`: measurements that print tables (never pass/fail).
#include "commands.h"
#include "sluice/bench/io_bench.h"

namespace sluice::app {

void add_bench(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Measure throughput; print tables side by side with the peers");
  bench->require_subcommand(1);
  auto io = std::make_shared<bench::IoBenchOptions>();
  CLI::App* cmd = bench->add_subcommand("io", "VTK's XML reader against .sluice read+decode on the same frames");
  cmd->footer("Example: sluice bench io 'data/dam_break_3d/*.vtu' --threads 16");
  cmd->add_option("input", io->input, "Simulation output, as `sluice convert` takes it")->required();
  cmd->add_option("-t,--threads", io->max_threads, "Most threads (default: all cores)");
  cmd->add_option("--min-time", io->min_seconds, "Seconds each timing repeats for")->capture_default_str();
  cmd->add_option("--work-dir", io->work_dir, "Keep the converted files here (default: a temp dir)");
  cmd->callback([io] { bench::run_io_bench(*io); });
}

}  // namespace sluice::app
