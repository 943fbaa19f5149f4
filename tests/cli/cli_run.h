// The `sluice` command run from a test, as a user's shell runs it.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace sluice::cli_test {

struct Result {
  int status = -1;  // exit status; -1 when killed by a signal
  int signal = 0;   // the signal that killed it
  std::string out;  // stdout, then stderr when asked
};

// Runs a shell command line; its stdout (with whatever redirection it asks) is the output.
inline Result run_command(const std::string& command) {
  Result r;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe)) r.out += buf;
  const int status = pclose(pipe);
  if (WIFEXITED(status)) {
    r.status = WEXITSTATUS(status);
    // The shell reports a child killed by a signal as 128 + signal.
    if (r.status > 128) r.signal = r.status - 128;
  } else if (WIFSIGNALED(status)) {
    r.signal = WTERMSIG(status);
  }
  return r;
}

// Runs `ENV sluice ARGS` through the shell; `both`: stderr joins stdout.
inline Result run_sluice(const std::string& args, const std::string& env = "", bool both = true) {
  return run_command(env + " \"" + SLUICE_BINARY + "\" " + args + (both ? " 2>&1" : " 2>/dev/null"));
}

// An empty folder under the test temp folder: `suite`/`name`.
inline std::filesystem::path fresh_dir(const std::string& suite, const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / suite / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace sluice::cli_test
