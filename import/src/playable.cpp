// The players' cache: convert once, reuse while the inputs are unchanged.
#include "sluice/import/playable.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <string_view>

#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/import/source.h"
#include "sluice/io/writer.h"
#include "sluice/io/reader.h"

namespace sluice::import {
namespace fs = std::filesystem;
namespace {


// A name for the cache file: the .pvd/file stem, or the folder a glob or
// directory lies in.
std::string cache_name(const fs::path& input) {
  const std::string text = input.string();
  if (fs::is_directory(input)) return fs::absolute(input).lexically_normal().filename().string();
  if (text.find_first_of("*?[") == std::string::npos) return input.stem().string();
  // The pattern without its wildcards: 'out/fluid_*.vtu' -> out_fluid.
  std::string stem;
  for (char c : input.stem().string()) {
    if (std::string_view("*?[]").find(c) == std::string_view::npos) stem += c;
  }
  while (!stem.empty() && std::string_view("_-. ").find(stem.back()) != std::string_view::npos) stem.pop_back();
  const fs::path dir = fs::absolute(input).parent_path().lexically_normal();
  return dir.filename().string() + (stem.empty() ? "" : "_" + stem);
}

// The folder the input lies in (for a glob: the folder of the pattern).
fs::path input_folder(const fs::path& input) {
  if (fs::is_directory(input)) return fs::absolute(input);
  return fs::absolute(input).parent_path();
}

bool writable_folder(const fs::path& dir) { return ::access(dir.c_str(), W_OK | X_OK) == 0; }

fs::path user_cache_folder() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "sluice";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "sluice";
  return fs::temp_directory_path() / "sluice-cache";
}

// Input files, sizes and modification times, and the settings: equal keys
// mean the cached conversion is still what a new one would write.
std::string cache_key(const std::string& input) {
  const auto source = open_source(input, {});
  std::ostringstream key;
  key << "sluice cache 1, format " << io::kFormatMajor << "." << io::kFormatMinor << "\nspec " << fs::absolute(input).lexically_normal().string() << "\nsettings attributes=all\n";
  const auto stat_line = [&](const std::string& path) {
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec) return;
    const auto time = fs::last_write_time(path, ec);
    key << "file " << path << ' ' << size << ' ' << time.time_since_epoch().count() << '\n';
  };
  if (fs::is_regular_file(input)) stat_line(input);
  for (uint64_t i = 0; i < source->frame_count(); ++i) {
    const std::string names = source->frame_name(i);
    size_t from = 0;
    while (true) {
      const size_t plus = names.find(" + ", from);
      stat_line(names.substr(from, plus == std::string::npos ? std::string::npos : plus - from));
      if (plus == std::string::npos) break;
      from = plus + 3;
    }
  }
  return key.str();
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every point array carried (the player may colour by any), defaults
// otherwise.
void convert_for_playing(const std::string& input, const std::string& output, const PlayableOptions& o) {
  ConvertOptions c;
  c.input = input;
  c.all_attributes = true;
  c.isolation = o.isolation;
  convert(c, output, o.observer);
}

// Reuses dir/name.sluice when its key matches, else converts into it.
PlayableFile open_playable_in(const fs::path& dir, const std::string& name, const std::string& key,
                              const std::string& input, const PlayableOptions& o) {
  const fs::path file = dir / (name + ".sluice");
  const fs::path key_file = dir / (name + ".sluice.key");
  std::error_code ec;
  fs::create_directories(dir, ec);
  // One player fills an entry; another of the same input waits for it and
  // then reuses what it wrote.
  const io::OutputLock entry(key_file, io::OutputLock::Wait::Yes, [&o](const fs::path& locked, long pid) {
    if (o.events.waiting) o.events.waiting(locked.parent_path().string(), pid);
  });
  if (io::is_container(file) && fs::exists(key_file, ec) && read_text(key_file) == key) {
    if (o.events.reused) o.events.reused(file.string());
    return PlayableFile(file.string(), false);
  }
  fs::create_directories(dir);
  if (o.events.converting) o.events.converting(file.string());
  // The key goes last: a conversion cut short leaves no key, so it is redone.
  fs::remove(key_file, ec);
  convert_for_playing(input, file.string(), o);
  const fs::path partial = key_file.string() + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    out << key;
    if (!out.flush()) throw io::Error({partial.string()}, "could not write the cache key");
  }
  fs::rename(partial, key_file);
  return PlayableFile(file.string(), false);
}

}  // namespace

PlayableFile::~PlayableFile() {
  if (!temporary_) return;
  std::error_code ec;
  fs::remove(path_, ec);
}

PlayableFile open_playable(const std::string& input, const PlayableOptions& o) {
  if (io::is_container(input)) return PlayableFile(input, false);
  if (o.use == CacheUse::Temporary) {
    const fs::path tmp = fs::temp_directory_path() / ("sluice-" + std::to_string(::getpid()) + "-" + cache_name(input) + ".sluice");
    if (o.events.converting) o.events.converting(tmp.string());
    convert_for_playing(input, tmp.string(), o);
    return PlayableFile(tmp.string(), true);
  }
  const std::string key = cache_key(input);
  const fs::path folder = input_folder(input);
  const std::string name = cache_name(input);
  fs::path dir = folder / ".sluice-cache";
  std::error_code ec;
  const bool chosen = !o.cache_folder.empty();
  if (chosen || !(fs::is_directory(dir, ec) ? writable_folder(dir) : writable_folder(folder))) {
    // A folder shared by inputs (the caller's, or the user cache): the
    // name carries a hash of the input's path, so two inputs with the same
    // name do not share a file.
    dir = chosen ? o.cache_folder : user_cache_folder();
    char hash[20];
    std::snprintf(hash, sizeof hash, "%016zx", std::hash<std::string>{}(fs::absolute(input).lexically_normal().string()));
    return open_playable_in(dir, name + "-" + hash, key, input, o);
  }
  return open_playable_in(dir, name, key, input, o);
}

}  // namespace sluice::import
