// Worker processes for reads by third-party readers: spawn, ask, answer,
// and what a worker's death or silence becomes.
#include "sluice/import/isolation.h"

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <cstring>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

#include "sluice/error.h"
#include "sluice/import/freed_memory.h"

extern char** environ;

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

constexpr const char* kWorkerFlag = "--import-worker";
constexpr uint32_t kOk = 0x4B4F4C53;     // "SLOK"
constexpr uint32_t kFailed = 0x52454C53;  // "SLER"
constexpr uint64_t kMostValues = uint64_t(1) << 36;

// ------------------------------------------------------------ byte moves

bool send_all(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t sent = ::send(fd, p, n, MSG_NOSIGNAL);
    if (sent < 0 && errno == EINTR) continue;
    if (sent <= 0) return false;
    p += sent;
    n -= static_cast<size_t>(sent);
  }
  return true;
}

template <class T>
bool send_value(int fd, const T& v) {
  return send_all(fd, &v, sizeof v);
}

bool send_string(int fd, const std::string& s) {
  const uint64_t n = s.size();
  return send_value(fd, n) && send_all(fd, s.data(), s.size());
}

bool recv_all(int fd, void* data, size_t n) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    const ssize_t got = ::recv(fd, p, n, 0);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    p += got;
    n -= static_cast<size_t>(got);
  }
  return true;
}

// ---------------------------------------------------------------- worker

// Test hook (fault injection): SLUICE_READER_FAULT=crash:TEXT or hang:TEXT
// makes a worker crash or hang on frames whose name contains TEXT.
void injected_fault(const std::string& frame_name) {
  const char* fault = std::getenv("SLUICE_READER_FAULT");
  if (!fault) return;
  const std::string_view f = fault;
  const size_t colon = f.find(':');
  if (colon == std::string_view::npos || frame_name.find(f.substr(colon + 1)) == std::string::npos) return;
  if (f.substr(0, colon) == "crash") {
    ::signal(SIGSEGV, SIG_DFL);  // a real crash's death, also under a sanitizer's handler
    ::raise(SIGSEGV);
  }
  if (f.substr(0, colon) == "hang") {
    for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
  }
}

bool send_frame(int fd, const ParticleFrame& f) {
  const uint64_t positions = f.positions.size(), ids = f.ids.size(), attributes = f.attributes.size(),
                 repairs = f.repairs.size();
  const uint8_t time_given = f.time_given ? 1 : 0;
  bool ok = send_value(fd, kOk) && send_value(fd, positions) && send_value(fd, ids) && send_value(fd, attributes) &&
            send_value(fd, repairs) && send_value(fd, f.time) && send_value(fd, time_given);
  for (const auto& r : f.repairs) ok = ok && send_string(fd, r);
  ok = ok && send_all(fd, f.positions.data(), positions * sizeof(float));
  ok = ok && send_all(fd, f.ids.data(), ids * sizeof(uint64_t));
  for (const auto& a : f.attributes) {
    const uint64_t n = a.size();
    ok = ok && send_value(fd, n) && send_all(fd, a.data(), n * sizeof(float));
  }
  return ok;
}

bool send_error(int fd, const io::Error& e) {
  const io::ErrorLocation& w = e.where();
  const uint64_t frame = w.frame.value_or(0), chunk = w.chunk.value_or(0);
  const uint8_t has_frame = w.frame.has_value(), has_chunk = w.chunk.has_value();
  return send_value(fd, kFailed) && send_string(fd, w.file) && send_value(fd, has_frame) && send_value(fd, frame) &&
         send_value(fd, has_chunk) && send_value(fd, chunk) && send_string(fd, e.message());
}

int serve(int fd, const std::string& spec, const SourceOptions& options) {
  const KeepFreedMemory keep;  // VTK allocates per frame (freed_memory.h)
  std::unique_ptr<FrameSource> source;
  std::optional<io::Error> open_error;
  try {
    source = open_source(spec, options);
  } catch (const io::Error& e) {
    open_error = e;
  }
  uint64_t index = 0;
  while (recv_all(fd, &index, sizeof index)) {
    if (open_error) {
      if (!send_error(fd, *open_error)) return 1;
      continue;
    }
    const std::string name = source->frame_name(index);
    injected_fault(name);
    bool sent = false;
    try {
      const ParticleFrame f = source->read(index);
      sent = send_frame(fd, f);
    } catch (const io::Error& e) {
      sent = send_error(fd, e);
    } catch (const std::exception& e) {
      sent = send_error(fd, io::Error({name, index}, e.what()));
    }
    if (!sent) return 1;
  }
  return 0;  // the parent closed its end
}

// ---------------------------------------------------------------- parent

// A worker that died or went silent; not reused.
struct Lost {
  std::string why;
};

std::string describe_exit(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = sigabbrev_np(sig);
    return "the reader crashed on it (signal " + std::to_string(sig) + (name ? std::string(", SIG") + name : "") + ")";
  }
  if (WIFEXITED(status)) return "the reader process ended (exit status " + std::to_string(WEXITSTATUS(status)) + ")";
  return "the reader process ended";
}

class Worker {
 public:
  Worker(const std::string& executable, const std::vector<std::string>& args) {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
      throw io::Error({}, std::string("cannot start a reader process: ") + std::strerror(errno));
    }
    fd_ = fds[0];
    constexpr int kChildFd = 3;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], kChildFd);  // dup2 clears close-on-exec
    std::vector<std::string> all = {executable, kWorkerFlag, std::to_string(kChildFd)};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int rc = ::posix_spawn(&pid_, executable.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    if (rc != 0) {
      ::close(fd_);
      throw io::Error({executable}, std::string("cannot start a reader process: ") + std::strerror(rc));
    }
  }
  ~Worker() {
    ::close(fd_);  // the worker reads end-of-file and exits
    if (pid_ > 0 && !reaped_) {
      int status = 0;
      while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
      }
    }
  }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  // Frame `index`, or its io::Error; throws Lost when the worker died or
  // did not answer in time (it is then gone).
  ParticleFrame ask(uint64_t index, std::chrono::seconds limit) {
    deadline_ = std::chrono::steady_clock::now() + limit;
    limit_ = limit;
    if (!send_value(fd_, index)) lost();
    uint32_t kind = 0;
    take(&kind, sizeof kind);
    if (kind == kFailed) throw_error();
    if (kind != kOk) throw Lost{"the reader process answered garbage"};
    uint64_t positions = 0, ids = 0, attributes = 0, repairs = 0;
    ParticleFrame f;
    uint8_t time_given = 0;
    take(&positions, 8);
    take(&ids, 8);
    take(&attributes, 8);
    take(&repairs, 8);
    take(&f.time, sizeof f.time);
    take(&time_given, 1);
    if (positions > 3 * kMostValues || ids > kMostValues || attributes > 4096 || repairs > 1 << 20) {
      throw Lost{"the reader process answered garbage"};
    }
    f.time_given = time_given != 0;
    for (uint64_t k = 0; k < repairs; ++k) f.repairs.push_back(take_string());
    f.positions.resize(positions);
    take(f.positions.data(), positions * sizeof(float));
    f.ids.resize(ids);
    take(f.ids.data(), ids * sizeof(uint64_t));
    f.attributes.resize(attributes);
    for (auto& a : f.attributes) {
      uint64_t n = 0;
      take(&n, 8);
      if (n > kMostValues) throw Lost{"the reader process answered garbage"};
      a.resize(n);
      take(a.data(), n * sizeof(float));
    }
    return f;
  }

 private:
  [[noreturn]] void lost() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
    throw Lost{describe_exit(status) + ": the file is damaged, or holds something the reader cannot handle"};
  }

  // Waits for `n` bytes until the deadline.
  void take(void* data, size_t n) {
    char* p = static_cast<char*>(data);
    while (n > 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - std::chrono::steady_clock::now());
      pollfd pfd{fd_, POLLIN, 0};
      const int ready = left.count() > 0 ? ::poll(&pfd, 1, static_cast<int>(left.count())) : 0;
      if (ready < 0 && errno == EINTR) continue;
      if (ready == 0) {
        ::kill(pid_, SIGKILL);
        int status = 0;
        while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
        }
        reaped_ = true;
        throw Lost{"reading it took more than " + std::to_string(limit_.count()) +
                   " s (the reader hangs on it, or it needs more time: raise the read limit, IsolationPolicy::read_limit)"};
      }
      const ssize_t got = ::recv(fd_, p, n, 0);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) lost();
      p += got;
      n -= static_cast<size_t>(got);
    }
  }

  std::string take_string() {
    uint64_t n = 0;
    take(&n, 8);
    if (n > (1 << 24)) throw Lost{"the reader process answered garbage"};
    std::string s(n, '\0');
    take(s.data(), n);
    return s;
  }

  [[noreturn]] void throw_error() {
    io::ErrorLocation where;
    where.file = take_string();
    uint8_t has_frame = 0, has_chunk = 0;
    uint64_t frame = 0, chunk = 0;
    take(&has_frame, 1);
    take(&frame, 8);
    take(&has_chunk, 1);
    take(&chunk, 8);
    if (has_frame) where.frame = frame;
    if (has_chunk) where.chunk = chunk;
    throw io::Error(where, take_string());
  }

  int fd_ = -1;
  pid_t pid_ = -1;
  bool reaped_ = false;
  std::chrono::steady_clock::time_point deadline_;
  std::chrono::seconds limit_{0};
};

class IsolatedSource final : public FrameSource {
 public:
  IsolatedSource(std::unique_ptr<FrameSource> source, std::string executable, std::vector<std::string> args,
                 std::chrono::seconds limit)
      : source_(std::move(source)), executable_(std::move(executable)), args_(std::move(args)), limit_(limit) {}

  uint64_t frame_count() const override { return source_->frame_count(); }
  const SourceInfo& info() const override { return source_->info(); }
  std::string frame_name(uint64_t i) const override { return source_->frame_name(i); }

  ParticleFrame read(uint64_t i) const override {
    std::unique_ptr<Worker> worker = take_worker();
    try {
      ParticleFrame f = worker->ask(i, limit_);
      give_back(std::move(worker));
      return f;
    } catch (const io::Error&) {
      give_back(std::move(worker));  // a clean error: the worker is fine
      throw;
    } catch (const Lost& lost) {
      throw io::Error({source_->frame_name(i), i}, lost.why);
    }
  }

 private:
  std::unique_ptr<Worker> take_worker() const {
    {
      std::lock_guard lock(mutex_);
      if (!idle_.empty()) {
        std::unique_ptr<Worker> w = std::move(idle_.back());
        idle_.pop_back();
        return w;
      }
    }
    return std::make_unique<Worker>(executable_, args_);
  }
  void give_back(std::unique_ptr<Worker> w) const {
    std::lock_guard lock(mutex_);
    idle_.push_back(std::move(w));
  }

  std::unique_ptr<FrameSource> source_;
  std::string executable_;
  std::vector<std::string> args_;
  std::chrono::seconds limit_;
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<Worker>> idle_;
};

bool executable(const std::string& path) { return !path.empty() && ::access(path.c_str(), X_OK) == 0; }

}  // namespace

std::string worker_executable(const IsolationPolicy& policy) {
  if (!policy.worker.empty()) {
    if (!executable(policy.worker)) throw io::Error({policy.worker}, "the import worker is not an executable file");
    return policy.worker;
  }
  if (const char* env = std::getenv("SLUICE_IMPORT_WORKER"); env && *env) {
    if (!executable(env)) throw io::Error({env}, "SLUICE_IMPORT_WORKER names no executable file");
    return env;
  }
  for (const char* candidate : {SLUICE_IMPORT_WORKER_BUILT, SLUICE_IMPORT_WORKER_INSTALLED}) {
    if (executable(candidate)) return candidate;
  }
  throw io::Error({SLUICE_IMPORT_WORKER_INSTALLED},
                  "no import worker found (built at " SLUICE_IMPORT_WORKER_BUILT
                  "): install sluice, set SLUICE_IMPORT_WORKER, or read in process (Isolation::InProcess)");
}

std::unique_ptr<FrameSource> open_isolated(const std::string& spec, const SourceOptions& options,
                                           const IsolationPolicy& policy) {
  std::unique_ptr<FrameSource> source = open_source(spec, options);
  if (policy.mode == Isolation::InProcess || !source->info().third_party_reader) return source;
  // The worker reads with the id array this process resolved ("=" + name;
  // "=" alone: no ids), then the attributes.
  std::vector<std::string> args = {spec, "=" + source->info().id_array};
  args.insert(args.end(), options.attributes.begin(), options.attributes.end());
  return std::make_unique<IsolatedSource>(std::move(source), worker_executable(policy), std::move(args),
                                          policy.read_limit);
}

bool run_worker(int argc, char** argv, int& status) {
  if (argc < 5 || std::string_view(argv[1]) != kWorkerFlag) return false;
  const int fd = std::atoi(argv[2]);
  SourceOptions options;
  const std::string_view ids = argv[4];
  options.id_array = std::string(ids.substr(ids.empty() ? 0 : 1));
  options.no_ids = options.id_array.empty();
  for (int k = 5; k < argc; ++k) options.attributes.emplace_back(argv[k]);
  status = serve(fd, argv[3], options);
  return true;
}

}  // namespace sluice::import
