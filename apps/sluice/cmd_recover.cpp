// `sluice recover`: rebuild the index of a file cut short (a crash during
// convert, a partial copy) from its per-frame headers.
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "human.h"
#include "sluice/io/maintenance.h"

namespace sluice::app {
namespace {

// run.sluice.partial -> run.sluice; anything else -> X.recovered.sluice.
std::string default_output(const std::string& input) {
  const std::string suffix = ".partial";
  if (input.size() > suffix.size() && input.ends_with(suffix)) return input.substr(0, input.size() - suffix.size());
  const std::filesystem::path p(input);
  return (p.parent_path() / p.stem()).string() + ".recovered.sluice";
}

}  // namespace

void add_recover(CLI::App& app) {
  struct Options {
    std::string input, output;
    bool in_place = false, force = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("recover", "Rebuild the frame index of a .sluice file that was cut short");
  cmd->footer(
      "Keeps every complete frame whose checksums hold and writes them with a new index: a damaged frame is\n"
      "left out (and listed) and the frames after it kept; a damaged header is rebuilt from the copy files\n"
      "of format 1.5 hold. The input is left untouched unless --in-place is given.\n"
      "Exit status 1 when no frame could be saved.\n\n"
      "Example: sluice recover run.sluice.partial        (writes run.sluice)");
  cmd->add_option("input", o->input, "Damaged .sluice file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->output,
                  "Where to write the recovered file (default: X.sluice for X.sluice.partial, else X.recovered.sluice)");
  cmd->add_flag("--in-place", o->in_place, "Truncate the damaged tail of INPUT and append the index there");
  cmd->add_flag("-f,--force", o->force, "Overwrite OUTPUT if it exists");
  cmd->callback([o] {
    if (o->in_place && !o->output.empty()) throw std::runtime_error("give either --in-place or -o, not both");
    const std::string output = o->in_place ? o->input : !o->output.empty() ? o->output : default_output(o->input);
    if (!o->in_place && std::filesystem::exists(output) && !o->force) {
      throw std::runtime_error(output + " exists; pass --force to overwrite it");
    }
    const io::RecoveryReport r = io::recover_container(o->input, output);
    if (r.header_rebuilt) std::printf("the header was damaged: rebuilt from its copy\n");
    for (const std::string& d : r.dropped) std::printf("  left out: %s\n", d.c_str());
    std::printf("recovered %llu frame%s (%s) into %s\n", (unsigned long long)r.frames, r.frames == 1 ? "" : "s",
                human_bytes(double(r.bytes_kept)).c_str(), output.c_str());
    std::printf("  %s of the input not kept; the scan ended: %s\n", human_bytes(double(r.bytes_dropped)).c_str(),
                r.stopped_because.c_str());
    if (r.frames == 0) {
      std::fprintf(stderr, "sluice: nothing could be recovered from %s\n", o->input.c_str());
      throw ExitCode{1};
    }
  });
}

}  // namespace sluice::app
