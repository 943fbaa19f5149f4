// The players' input as the sluice command opens it: import::open_playable
// with its cache's and conversion's messages on stderr.
#include "playable.h"

#include <cstdio>

#include "conversion.h"

namespace sluice::app {
namespace {

import::CacheEvents cache_messages(const std::string& input, bool temporary) {
  import::CacheEvents events;
  events.reused = [input](const std::string& entry) {
    std::fprintf(stderr, "%s: using its conversion %s (the input is unchanged)\n", input.c_str(), entry.c_str());
  };
  events.converting = [input, temporary](const std::string& entry) {
    if (temporary) {
      std::fprintf(stderr, "converting %s into a temporary file (--no-cache)\n", input.c_str());
      return;
    }
    std::fprintf(stderr,
                 "%s is not a .sluice file: converting it once into %s\n"
                 "  (reused while the input files are unchanged; --no-cache converts into a temporary file instead)\n",
                 input.c_str(), entry.c_str());
  };
  return events;
}

}  // namespace

import::PlayableFile open_playable(const std::string& input, const PlayableOptions& o) {
  ConversionReport report;
  report.quiet = o.quiet;
  ConversionPrinter printer(report);
  import::PlayableOptions options;
  options.use = o.no_cache ? import::CacheUse::Temporary : import::CacheUse::Cache;
  options.isolation = import_isolation(false, 120);
  if (!o.quiet) options.events = cache_messages(input, o.no_cache);
  // Waiting is said even when quiet: a player that seems stuck says why.
  options.events.waiting = [](const std::string& folder, long pid) {
    std::fprintf(stderr, "waiting for another sluice%s converting into %s\n",
                 pid > 0 ? (" (process " + std::to_string(pid) + ")").c_str() : "", folder.c_str());
  };
  return printer.run([&](const import::ConvertObserver& observer) {
    options.observer = observer;
    return import::open_playable(input, options);
  });
}

void add_input_options(CLI::App& cmd, const char* name, std::string& input, bool& no_cache) {
  cmd.add_option(name, input, ".sluice file, or anything `convert` reads (converted once into a cache beside it)")
      ->required();
  cmd.add_flag("--no-cache", no_cache, "Input that is not .sluice: convert into a temporary file, not the cache");
}

}  // namespace sluice::app
