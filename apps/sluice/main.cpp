// sluice: stream huge particle-fluid simulations to the GPU and look at them
// as liquid. This file wires the subcommands together and turns errors into
// messages and exit codes.
#include <cstdio>
#include <exception>
#include <string>

#include "commands.h"
#include "sluice/import/isolation.h"
#include "sluice/error.h"
#include "sluice/io/format.h"

int main(int argc, char** argv) {
  // A worker process of `convert` (sluice/import/isolation.h), before anything else.
  if (int status = 0; sluice::import::run_worker(argc, argv, status)) return status;
  CLI::App app{
      "sluice: stream huge particle-fluid simulation sequences (SPH, MPM, FLIP) from disk and look at them.\n\n"
      "Typical use:\n"
      "  sluice convert 'out/fluid_*.vtu' -o run.sluice --attribute rho   # VTK/CSV -> .sluice\n"
      "  sluice info run.sluice                                         # what is inside\n"
      "  sluice verify run.sluice                                       # check every checksum, decode all\n"
      "  sluice bench io 'out/fluid_*.vtu'                              # sluice against VTK's reader\n",
      "sluice"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "sluice 0.3.0 (container format " + std::to_string(sluice::io::kFormatMajor) + "." +
                                         std::to_string(sluice::io::kFormatMinor) + ")");
  app.footer("Run `sluice COMMAND --help` for the options of a command.");
  sluice::app::add_convert(app);
  sluice::app::add_info(app);
  sluice::app::add_verify(app);
  sluice::app::add_recover(app);
  sluice::app::add_bench(app);
  sluice::app::add_play(app);
  sluice::app::add_synth(app);
  sluice::app::add_export(app);
#if SLUICE_WITH_RENDER
  sluice::app::add_render(app);
  sluice::app::add_devices(app);
  sluice::app::add_bench_render(*app.get_subcommand("bench"));
  sluice::app::add_bench_layers(*app.get_subcommand("bench"));
#endif
#if SLUICE_WITH_XR
  sluice::app::add_xr(app);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const sluice::app::ExitCode& e) {
    return e.code;
  } catch (const sluice::io::Error& e) {
    std::fprintf(stderr, "sluice: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sluice: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
