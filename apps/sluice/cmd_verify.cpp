// `sluice verify`: every checksum checked, every chunk decoded; the decode
// rate is printed as a by-product.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "commands.h"
#include "human.h"
#include "progress.h"
#include "sluice/io/format.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"

namespace sluice::app {

void add_verify(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("verify", "Check every checksum of a .sluice file and decode every chunk");
  cmd->footer("Exit status 0: the file is intact; 1: problems were found (each names its frame and chunk).");
  cmd->add_option("file", *file, ".sluice file")->required();
  cmd->add_flag("-q,--quiet", *quiet, "No progress bar and no summary: only problems, and the exit status");
  cmd->callback([file, quiet] {
    const io::ContainerReader reader(*file);  // opening errors are reported by main
    const size_t per_particle =
        io::decoded_particle_bytes(reader.header().position_coding) + 2 * reader.header().attributes.size();
    ProgressBar bar("frames", reader.frame_count(), *quiet);
    const io::VerifyReport report = io::verify_container(*file, [&](uint64_t done, uint64_t) { bar.update(done); });
    bar.finish();
    const double t = bar.elapsed();
    for (const std::string& p : report.problems) std::fprintf(stderr, "problem: %s\n", p.c_str());
    if (*quiet) {
      if (!report.ok()) throw ExitCode{1};
      return;
    }
    const std::string blobs = report.blobs ? " (and " + human_count(double(report.blobs)) + " voxel blobs)" : "";
    std::printf("%s: %llu frames, %llu chunks, %s particles%s: %s\n", file->c_str(), (unsigned long long)report.frames,
                (unsigned long long)report.chunks, human_count(double(report.particles)).c_str(), blobs.c_str(),
                report.ok() ? "all checksums match" : (std::to_string(report.problems.size()) + " problems").c_str());
    std::printf("  %s\n", precision_text(reader.header()).c_str());
    std::printf("  read and decoded %s in %s: %s particles/s, %s/s decoded\n", human_bytes(double(report.bytes)).c_str(),
                human_duration(t).c_str(), human_count(double(report.particles) / t).c_str(),
                human_bytes(double(report.particles * per_particle) / t).c_str());
    if (!report.ok()) throw ExitCode{1};
  });
}

}  // namespace sluice::app
