// sluice-import-worker: the executable that reads frames for
// Isolation::WorkerProcesses (sluice/import/isolation.h).
#include <cstdio>

#include "sluice/import/isolation.h"

int main(int argc, char** argv) {
  if (int status = 0; sluice::import::run_worker(argc, argv, status)) return status;
  std::fprintf(stderr,
               "sluice-import-worker reads frames for sluice's importer and is started by it "
               "(sluice/import/isolation.h); it is not run by hand\n");
  return 2;
}
