// `sluice bench`: measurements that print tables (never pass/fail).
#include "commands.h"
#include "sluice/bench/band_bench.h"
#include "sluice/bench/io_bench.h"
#include "sluice/bench/stream_bench.h"
#include "sluice/bench/view_bench.h"
#include "sluice/runtime/budget.h"

namespace sluice::app {

namespace {

// `sluice bench io`: VTK's readers against .sluice on the same frames.
void add_bench_io(CLI::App* bench) {
  auto io = std::make_shared<bench::IoBenchOptions>();
  CLI::App* cmd = bench->add_subcommand("io", "VTK's XML reader against .sluice read+decode on the same frames");
  cmd->footer("Example: sluice bench io 'data/dam_break_3d/*.vtu' --threads 16");
  cmd->add_option("input", io->input, "Simulation output, as `sluice convert` takes it")->required();
  cmd->add_option("-t,--threads", io->max_threads, "Most threads (default: all cores)");
  cmd->add_option("--min-time", io->min_seconds, "Seconds each timing repeats for")->capture_default_str();
  cmd->add_option("--work-dir", io->work_dir, "Keep the converted files here (default: a temp dir)");
  cmd->add_option("--tile", io->tile,
                  "VTK copies of the frames (legacy, .vtu raw, .vtu zlib) hold each frame N times side by side")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->callback([io] { bench::run_io_bench(*io); });
}

// `sluice bench band`: the narrow-band classifier.
void add_bench_band(CLI::App* bench) {
  auto band = std::make_shared<bench::BandBenchOptions>();
  CLI::App* bc = bench->add_subcommand("band", "The narrow-band classifier (LNM) on the input's frames, against the exact narrow band");
  bc->footer(
      "Examples: sluice bench band data/dam_break_3d/dam_break_3d.pvd --frames 3\n"
      "          sluice bench band --synth 10000000 --no-exact --frames 1 --gpu   (CPU against GPU)");
  bc->add_option("input", band->input, "Simulation output, as `sluice convert` takes it");
  bc->add_option("--synth", band->synth, "Classify one frame of a synthetic sloshing block of N particles instead");
  bc->add_flag("--no-exact", [band](int64_t) { band->exact = false; }, "Skip the exact narrow band (slow on millions)");
  bc->add_option("-t,--threads", band->max_threads, "Most threads (default: all cores)");
  bc->add_option("--min-time", band->min_seconds, "Seconds each timing repeats for")->capture_default_str();
  bc->add_option("--frames", band->frames, "Frames measured, first to last")->capture_default_str();
  bc->add_option("--diameter", band->diameter, "Particle diameter h (default: the estimated spacing)");
  bc->add_flag("--gpu", band->gpu, "Also classify on the GPU: its speed, and how many particles differ from the CPU's layers");
  bc->add_option("--device", band->device, "Vulkan device for --gpu: index or part of its name (default: the first discrete GPU)");
  bc->callback([band] {
    if (band->input.empty() && band->synth == 0) throw CLI::ValidationError("bench band", "give an input or --synth N");
    bench::run_band_bench(*band);
  });
}

// `sluice bench stream`: the streaming pipeline against the machine's bounds.
void add_bench_stream(CLI::App* bench) {
  auto stream = std::make_shared<bench::StreamBenchOptions>();
  auto stream_memory = std::make_shared<std::string>();
  CLI::App* st = bench->add_subcommand("stream", "The streaming pipeline from storage and the page cache, against the machine's bounds");
  st->footer("Example: sluice synth -n 10M --frames 200 -o synth.sluice && sluice bench stream synth.sluice");
  st->add_option("file", stream->file, ".sluice file to stream")->required()->check(CLI::ExistingFile);
  st->add_option("-t,--threads", stream->max_threads, "Most decode workers (default: the pipeline's, all cores but one per 4 kept for reading)");
  st->add_option("-r,--read-threads", stream->read_threads, "Threads reading a record (default: one per 4 cores, 1 to 4; thirteen sixteenths of the cores, 1 to 13, for the --gpu rows)");
  st->add_option("--min-time", stream->min_seconds, "Seconds each page-cache timing runs for")->capture_default_str();
  st->add_option("--memory", *stream_memory, "Memory cap of the pipeline, e.g. 4G (default: 2G)");
  st->add_option("--frames", stream->frames, "Stream the first N frames (default: as many as fit in the page cache)");
  st->add_flag("--surface", stream->surface,
               "Read the surface and voxel blobs of a file with layers (what players read), not every particle");
  st->add_flag("!--no-storage", stream->storage, "Skip the storage passes (they drop the file from the page cache)");
  auto stream_gpu = std::make_shared<bool>(false);
  st->add_flag("--gpu", *stream_gpu,
               "Frames into the renderer's device memory, decoded by the GPU and, beside it, by the CPU, against\n"
               "the bounds: the page-cache read, the host-to-device copy (1, 2 and 4 copies in flight; the best),\n"
               "the two at once, and GPU decode alone; the read and the copy are measured again after the\n"
               "pipeline rows, and each row is put against the mean of both measures (needs a Vulkan device)");
  st->add_option("--device", stream->device, "With --gpu: the Vulkan device (index or name; default: the first GPU)");
  auto ring_piece = std::make_shared<std::string>();
  st->add_option("--ring-slots", stream->ring_slots,
                 "With --gpu: slots of the ring the relayed row reads through (default: the read threads + 4)");
  st->add_option("--ring-piece", *ring_piece, "With --gpu: bytes of a ring slot, e.g. 8M (default: 8M)");
  st->add_flag("--ring-imported", stream->ring_imported,
               "With --gpu: the ring in anonymous memory the device imports (VK_EXT_external_memory_host), not the "
               "driver's own (the row says which it got)");
  st->callback([stream, stream_memory, stream_gpu, ring_piece] {
    if (!stream_memory->empty()) {
      const auto bytes = runtime::parse_byte_size(*stream_memory);
      if (!bytes) throw std::runtime_error("--memory: cannot read '" + *stream_memory + "' as a size (try 4G or 512M)");
      stream->memory = *bytes;
    }
    if (!ring_piece->empty()) {
      const auto bytes = runtime::parse_byte_size(*ring_piece);
      if (!bytes || *bytes < 4096) throw std::runtime_error("--ring-piece: cannot read '" + *ring_piece + "' as a size of 4K or more (try 8M)");
      stream->ring_piece_bytes = *bytes;
    }
    if (*stream_gpu) {
#if SLUICE_WITH_RENDER
      bench::run_stream_gpu_bench(*stream);
#else
      throw std::runtime_error("--gpu: this build has no renderer (SLUICE_WITH_RENDER=OFF)");
#endif
    } else {
      bench::run_stream_bench(*stream);
    }
  });
}

// `sluice bench view`: reading by the view on a scripted camera path.
void add_bench_view(CLI::App* bench) {
  auto view = std::make_shared<bench::ViewBenchOptions>();
  auto view_size = std::make_shared<std::string>("1920x1080");
  auto view_memory = std::make_shared<std::string>();
  CLI::App* vw = bench->add_subcommand(
      "view", "Reading only what the view draws (LOD tiers) against the full read, on a scripted camera path");
  vw->footer(
      "The path: a quarter orbit of the overview, a fly-in to a close-up inside the pool, and a pause on the\n"
      "overview while the LOD level rises to 1. Each is played through the players' own path as fast as frames\n"
      "arrive, from storage (the file dropped from the page cache) and from the page cache, reading by the view\n"
      "and reading every tier of the surface and blobs, side by side; then each streamed picture is compared\n"
      "with the full read's (PSNR).\n"
      "Examples: sluice synth -n 10M --frames 48 --gpu-decodable -o pool.sluice && sluice bench view pool.sluice\n"
      "          sluice bench view pool.sluice --stereo --size 2064x2208 --memory 16G");
  vw->add_option("file", view->file, ".sluice file to stream")->required()->check(CLI::ExistingFile);
  vw->add_option("--size", *view_size, "Image size WxH (per eye with --stereo)")->capture_default_str();
  vw->add_flag("--stereo", view->stereo, "Both eyes in one pass (a headset's view)");
  vw->add_option("--lod", view->lod, "clod or density")->capture_default_str()->check(CLI::IsMember({"clod", "density"}));
  vw->add_option("--lod-level", view->level, "LOD level, 0..1")->capture_default_str()->check(CLI::Range(0.0f, 1.0f));
  vw->add_option("--position-error", view->position_error,
                 "Format 3.0 files: records far enough away are read without the low bits of their positions when\n"
                 "that moves no particle more than this many pixels (0: always at full precision)")
      ->capture_default_str()->check(CLI::Range(0.0f, 16.0f));
  vw->add_option("--cache-steps", view->cache_steps,
                 "The same from the page cache, where the file may loop: more than the file's frames give steadier\n"
                 "rates (default: --steps)")
      ->check(CLI::Range(2u, 100000u));
  vw->add_option("--steps", view->steps, "Frames of the orbit and of the fly-in each")->capture_default_str()
      ->check(CLI::Range(2u, 100000u));
  vw->add_option("--memory", *view_memory, "Memory cap of the pipeline, e.g. 16G (default: 4G)");
  vw->add_flag("!--no-storage", view->storage, "Skip the storage passes (they drop the file from the page cache)");
  vw->add_flag("!--no-psnr", view->psnr, "Skip the quality pass");
  vw->add_flag("--close-up-only", view->close_up_only,
               "Only the close-up's read share against the share of the frame in view (no timed segments):\n"
               "quick to compare layouts");
  vw->add_option("--decode", view->decode, "auto, cpu or gpu")->capture_default_str()->check(CLI::IsMember({"auto", "cpu", "gpu"}));
  vw->add_option("--device", view->device, "Vulkan device (index or name; default: the first GPU)");
  vw->add_option("--read-threads", view->read_threads, "Threads reading a frame's pieces at once (default: the pipeline's)")
      ->check(CLI::Range(1, 64));
  vw->add_option("--read-rounds", view->read_rounds, "Frames read at once, each a round of the read threads' pieces (default: 2)")
      ->check(CLI::Range(1, 4));
  vw->add_flag("!--pread", view->mapped_reads, "Read with pread instead of copying out of the file's mapping");
  vw->add_flag("--direct", view->direct_io, "Read with O_DIRECT (the page cache bypassed; reads by the view are always\n"
                                            "pread or O_DIRECT, never the mapping)");
  vw->callback([view, view_size, view_memory] {
#if SLUICE_WITH_RENDER
    const auto x = view_size->find('x');
    if (x == std::string::npos) throw std::runtime_error("--size: give WxH, e.g. 1920x1080");
    view->width = static_cast<uint32_t>(std::stoul(view_size->substr(0, x)));
    view->height = static_cast<uint32_t>(std::stoul(view_size->substr(x + 1)));
    if (!view_memory->empty()) {
      const auto bytes = runtime::parse_byte_size(*view_memory);
      if (!bytes) throw std::runtime_error("--memory: cannot read '" + *view_memory + "' as a size (try 16G)");
      view->memory = *bytes;
    }
    bench::run_view_bench(*view);
#else
    throw std::runtime_error("bench view: this build has no renderer (SLUICE_WITH_RENDER=OFF)");
#endif
  });
}

}  // namespace

void add_bench(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Measure throughput; print tables side by side with the peers");
  bench->require_subcommand(1);
  add_bench_io(bench);
  add_bench_band(bench);
  add_bench_stream(bench);
  add_bench_view(bench);
}

}  // namespace sluice::app
