// `sluice recover`: rebuild the index of a file cut short (a crash during
// convert, a partial copy) from its per-frame headers.
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "human.h"
#include "sluice/io/maintenance.h"

namespace sluice::app {

void add_recover(CLI::App& app) {
  struct Options {
    std::string input, output;
    bool in_place = false, force = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("recover", "Rebuild the frame index of a .sluice file that was cut short");
  cmd->footer(
      "Keeps every complete frame whose checksums hold, up to the first damaged one, and writes them with a\n"
      "new index. The input is left untouched unless --in-place is given.\n\n"
      "Example: sluice recover run.sluice.partial -o run.sluice");
  cmd->add_option("input", o->input, "Damaged .sluice file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->output, "Where to write the recovered file (default: INPUT.recovered.sluice)");
  cmd->add_flag("--in-place", o->in_place, "Truncate the damaged tail of INPUT and append the index there");
  cmd->add_flag("-f,--force", o->force, "Overwrite OUTPUT if it exists");
  cmd->callback([o] {
    if (o->in_place && !o->output.empty()) throw std::runtime_error("give either --in-place or -o, not both");
    const std::string output = o->in_place ? o->input : (o->output.empty() ? o->input + ".recovered.sluice" : o->output);
    if (!o->in_place && std::filesystem::exists(output) && !o->force) {
      throw std::runtime_error(output + " exists; pass --force to overwrite it");
    }
    const io::RecoveryReport r = io::recover_container(o->input, output);
    std::printf("recovered %llu frames (%s) into %s\n", (unsigned long long)r.frames,
                human_bytes(double(r.bytes_kept)).c_str(), output.c_str());
    std::printf("  dropped %s after the last good frame: %s\n", human_bytes(double(r.bytes_dropped)).c_str(),
                r.stopped_because.c_str());
  });
}

}  // namespace sluice::app
