// skyloc teach / repeat / replay / route: the firmware's modes. Argument parsing only;
// the work is in session.cpp.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "cli/commands.h"
#include "firmware/route_db.h"
#include "firmware/session.h"

namespace skyloc::cli {
using namespace skyloc::firmware;
namespace {

constexpr const char* kTeachUsage =
    "usage: skyloc teach --route FILE.db [--config FILE] [--dataset DIR] [--frames N]\n"
    "                    [--force] [--record DIR] [SIM]\n"
    "  Records the sky descriptors of a route into FILE.db until SIGINT/SIGTERM, the end\n"
    "  of the camera's run or N frames; prints one JSON line per frame. --dataset: teach\n"
    "  from a recorded dataset folder instead of the configured camera. --record DIR: also\n"
    "  write every frame into the dataset folder DIR (for replay and eval).\n"
    "  SIM (camera.kind = \"sim\" only): --tilt DEG --zigzag DEG --bumps DEG --yaw DEG\n"
    "  --lighting noon|dawn|overcast --run N (jitter, clouds, noise seed)\n";
constexpr const char* kRepeatUsage =
    "usage: skyloc repeat --route FILE.db [--config FILE] [--frames N] [--record DIR] [SIM]\n"
    "  Localises live against a taught route; one JSON line per frame (frame, timestamp,\n"
    "  best_index, uniqueness, confidence, state, latency_us) until SIGINT/SIGTERM.\n"
    "  SIM: as for teach. A finite run with poses ends with precision/recall. --record DIR:\n"
    "  also write every frame into the dataset folder DIR.\n";
constexpr const char* kRecordUsage =
    "usage: skyloc record DIR [--config FILE] [--frames N] [SIM]\n"
    "  Records the configured camera into the dataset folder DIR (docs/DATASETS.md):\n"
    "  frames/NNNNNN.png, frames.csv with timestamps (and roll/pitch when [attitude] gives\n"
    "  them), camera.toml. A writer thread keeps up with the camera or drops frames (counted);\n"
    "  a full disk stops the recording and keeps what was written. Until SIGINT/SIGTERM/\n"
    "  SIGHUP or N frames; one JSON line per frame. replay and eval read DIR.\n";
constexpr const char* kReplayUsage =
    "usage: skyloc replay DATASET --route FILE.db [--config FILE] [--pace recorded|fast]\n"
    "                     [--frames N] [--tolerance-m X]\n"
    "  Runs a recorded dataset folder through the same pipeline as repeat; with poses,\n"
    "  prints precision/recall (a match within X metres, default 2, is correct).\n";
constexpr const char* kRouteUsage =
    "usage: skyloc route info FILE.db | skyloc route recover [--salvage] FILE.db\n"
    "  info: what the file holds. recover: make an interrupted teach loadable (keeps every\n"
    "  intact chunk, cuts a torn tail or trailing bytes, appends the commit record); it\n"
    "  refuses a file a running teach is writing. --salvage: also for damage in the middle:\n"
    "  keeps the intact chunks before it (the original is kept as FILE.db.damaged).\n";

bool ParseCount(const char* text, std::uint64_t* out) {
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text, &end, 10);
  if (end == text || *end != '\0' || text[0] == '-')
    return false;
  *out = v;
  return true;
}

// Parses the options the three modes share. Returns -1 to go on, else the exit code.
int ParseModeArgs(const char* name, const char* usage, std::span<char* const> args, SessionArgs* s,
                  bool replay) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    const char* a = args[i];
    const char* next = i + 1 < args.size() ? args[i + 1] : nullptr;
    auto need = [&](const char* flag) {
      if (next == nullptr)
        std::fprintf(stderr, "skyloc %s: %s needs a value\n%s", name, flag, usage);
      return next != nullptr;
    };
    if (IsHelpFlag(a)) {
      std::fputs(usage, stdout);
      return kExitOk;
    } else if (std::strcmp(a, "--route") == 0) {
      if (!need(a))
        return kExitUsage;
      s->route_path = args[++i];
    } else if (std::strcmp(a, "--config") == 0) {
      if (!need(a))
        return kExitUsage;
      s->config_path = args[++i];
    } else if (std::strcmp(a, "--frames") == 0) {
      if (!need(a) || !ParseCount(next, &s->max_frames)) {
        std::fprintf(stderr, "skyloc %s: --frames needs a whole number\n", name);
        return kExitUsage;
      }
      ++i;
    } else if (std::strcmp(a, "--tilt") == 0 || std::strcmp(a, "--zigzag") == 0 ||
               std::strcmp(a, "--bumps") == 0 || std::strcmp(a, "--yaw") == 0) {
      char* end = nullptr;
      const double v = next != nullptr ? std::strtod(next, &end) : 0.0;
      if (next == nullptr || end == next || *end != '\0' || !(v >= -90 && v <= 90)) {
        std::fprintf(stderr, "skyloc %s: %s needs degrees in -90..90\n", name, a);
        return kExitUsage;
      }
      ++i;
      (a[2] == 't'   ? s->sim.tilt_deg
       : a[2] == 'z' ? s->sim.zigzag_deg
       : a[2] == 'b' ? s->sim.bumps_deg
                     : s->sim.yaw_deg) = v;
    } else if (std::strcmp(a, "--lighting") == 0) {
      if (!need(a))
        return kExitUsage;
      s->sim.lighting = args[++i];
    } else if (std::strcmp(a, "--run") == 0) {
      if (!need(a) || !ParseCount(next, &s->sim.run_seed)) {
        std::fprintf(stderr, "skyloc %s: --run needs a whole number\n", name);
        return kExitUsage;
      }
      ++i;
    } else if (std::strcmp(a, "--dataset") == 0 && s->mode == LoopMode::kTeach) {
      if (!need(a))
        return kExitUsage;
      s->dataset = args[++i];
    } else if (std::strcmp(a, "--record") == 0 && !replay && s->mode != LoopMode::kRecord) {
      if (!need(a))
        return kExitUsage;
      s->record_dir = args[++i];
    } else if (s->mode == LoopMode::kRecord && a[0] != '-' && s->record_dir.empty()) {
      s->record_dir = a;
    } else if (std::strcmp(a, "--force") == 0 && s->mode == LoopMode::kTeach) {
      s->force = true;
    } else if (replay && std::strcmp(a, "--pace") == 0) {
      if (!need(a))
        return kExitUsage;
      ++i;
      if (std::strcmp(next, "recorded") == 0) {
        s->paced = true;
      } else if (std::strcmp(next, "fast") == 0) {
        s->paced = false;
      } else {
        std::fprintf(stderr, "skyloc %s: --pace is 'recorded' or 'fast', not '%s'\n", name, next);
        return kExitUsage;
      }
    } else if (replay && std::strcmp(a, "--tolerance-m") == 0) {
      if (!need(a))
        return kExitUsage;
      char* end = nullptr;
      s->tolerance_m = std::strtod(next, &end);
      if (end == next || *end != '\0' || !(s->tolerance_m > 0)) {
        std::fprintf(stderr, "skyloc %s: --tolerance-m needs a positive number\n", name);
        return kExitUsage;
      }
      ++i;
    } else if (replay && a[0] != '-' && s->dataset.empty()) {
      s->dataset = a;
    } else {
      std::fprintf(stderr, "skyloc %s: unknown argument '%s'\n%s", name, a, usage);
      return kExitUsage;
    }
  }
  if (s->mode == LoopMode::kRecord) {
    if (s->record_dir.empty()) {
      std::fprintf(stderr, "skyloc %s: name the dataset folder DIR to record into\n%s", name,
                   usage);
      return kExitUsage;
    }
  } else if (s->route_path.empty()) {
    std::fprintf(stderr, "skyloc %s: --route FILE.db is required\n%s", name, usage);
    return kExitUsage;
  }
  if (replay && s->dataset.empty()) {
    std::fprintf(stderr, "skyloc %s: name the DATASET folder\n%s", name, usage);
    return kExitUsage;
  }
  return -1;
}

// The configuration --config names (the built-in defaults without it), then the run.
int RunWithConfigFile(const SessionArgs& s) {
  Config config = DefaultConfig();
  if (!s.config_path.empty()) {
    Result<Config> loaded = LoadConfigFile(s.config_path.c_str());
    if (!loaded.ok()) {
      std::fprintf(stderr, "%s: %s\n", s.label, loaded.status().message());
      return kExitFailure;
    }
    config = *loaded;
  }
  return RunSession(config, s) == 0 ? kExitOk : kExitFailure;
}

}  // namespace

int RunTeach(std::span<char* const> args) {
  SessionArgs s;
  s.mode = LoopMode::kTeach;
  s.label = "skyloc teach";
  if (const int rc = ParseModeArgs("teach", kTeachUsage, args, &s, false); rc >= 0)
    return rc;
  return RunWithConfigFile(s);
}

int RunRepeat(std::span<char* const> args) {
  SessionArgs s;
  s.mode = LoopMode::kRepeat;
  s.label = "skyloc repeat";
  if (const int rc = ParseModeArgs("repeat", kRepeatUsage, args, &s, false); rc >= 0)
    return rc;
  return RunWithConfigFile(s);
}

int RunRecord(std::span<char* const> args) {
  SessionArgs s;
  s.mode = LoopMode::kRecord;
  s.label = "skyloc record";
  if (const int rc = ParseModeArgs("record", kRecordUsage, args, &s, false); rc >= 0)
    return rc;
  return RunWithConfigFile(s);
}

int RunReplay(std::span<char* const> args) {
  SessionArgs s;
  s.mode = LoopMode::kRepeat;
  s.label = "skyloc replay";
  if (const int rc = ParseModeArgs("replay", kReplayUsage, args, &s, true); rc >= 0)
    return rc;
  return RunWithConfigFile(s);
}

int RunRoute(std::span<char* const> args) {
  if (args.size() == 1 && IsHelpFlag(args[0])) {
    std::fputs(kRouteUsage, stdout);
    return kExitOk;
  }
  const bool recover = !args.empty() && std::strcmp(args[0], "recover") == 0;
  const bool salvage = recover && args.size() == 3 && std::strcmp(args[1], "--salvage") == 0;
  if ((args.size() != 2 && !salvage) ||
      (std::strcmp(args[0], "info") != 0 && std::strcmp(args[0], "recover") != 0)) {
    std::fputs(kRouteUsage, stderr);
    return kExitUsage;
  }
  const char* path = args[args.size() - 1];
  RouteDbLoadReport report;
  Status s;
  if (recover) {
    s = RecoverRouteDb(path, &report, salvage);
  } else {
    s = LoadRouteDb(path, nullptr, RouteDbLoadPolicy::kRecoverInterrupted, nullptr, &report);
  }
  if (!s.ok()) {
    std::fprintf(stderr, "skyloc route: %s\n", s.message());
    return kExitFailure;
  }
  const RouteDbSettings& st = report.settings;
  std::printf(
      "%s: %zu frames in %zu chunks, %s; format version %u, descriptor kind %u, %u bands, grid "
      "%u x %u, normalisation %u, lens hash %016llx\n",
      path, report.frames, report.chunks,
      report.committed ? "committed" : "NOT committed (teach was interrupted)", report.version,
      st.descriptor_kind, st.bands, st.rings, st.longitudes, st.normalisation,
      static_cast<unsigned long long>(st.lens_hash));
  char lens[320];
  FormatRouteDbLens(st.lens, lens, sizeof lens);
  std::printf("%s: lens %s%s\n", path, lens,
              st.lens.known ? "" : "; repeat checks the lens hash only (teach again to store it)");
  if (st.strip.columns != 0)
    std::printf(
        "%s: horizon strips for heading: %u columns (bytes per frame), %u rows over "
        "%.2f..%.2f deg above the horizon\n",
        path, st.strip.columns, st.strip.band_rows, st.strip.elevation_min_cdeg / 100.0,
        st.strip.elevation_max_cdeg / 100.0);
  else
    std::printf("%s: no horizon strips: repeat reports no heading (teach again to store them)\n",
                path);
  if (report.trailing_bytes > 0) {
    std::printf(
        "%s: %zu trailing bytes after the commit record at offset %zu (not part of the "
        "route) %s\n",
        path, report.trailing_bytes, report.valid_bytes,
        recover ? "were cut off" : "would be cut off by 'skyloc route recover'");
  }
  if (report.dropped_bytes > 0) {
    std::printf("%s: %zu bytes %s after offset %zu %s\n", path, report.dropped_bytes,
                report.damaged_mid_file ? "from the damage on" : "of a torn final chunk",
                report.valid_bytes, recover ? "were cut off" : "would be cut off");
  }
  if (report.damaged_mid_file)
    std::printf("%s: the damaged original was kept as %s.damaged\n", path, path);
  if (recover && !report.committed)
    std::printf("%s: recovered: %zu frames, now committed\n", path, report.frames);
  return kExitOk;
}

}  // namespace skyloc::cli
