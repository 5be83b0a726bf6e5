// skyloc teach / repeat / record / replay / route: the firmware's modes. Argument parsing
// only (each command's OptionTable); the work is in session.cpp and route_db.cpp.
#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "firmware/route_db.h"
#include "firmware/session.h"

namespace skyloc::cli {
using namespace skyloc::firmware;
namespace {

constexpr const char* kTeachDescription =
    "Records the sky descriptors of a route into FILE.db until SIGINT/SIGTERM, the end of\n"
    "the camera's run or N frames; prints one JSON line per frame. --dataset: teach from a\n"
    "recorded dataset folder instead of the configured camera. --record DIR: also write\n"
    "every frame into the dataset folder DIR (for replay and eval). The simulated run's\n"
    "options (--run ... --lighting) apply to camera.kind = \"sim\" only.\n";
constexpr const char* kRepeatDescription =
    "Localises live against a taught route; one JSON line per frame (frame, timestamp,\n"
    "best_index, uniqueness, confidence, state, latency_us) until SIGINT/SIGTERM. The\n"
    "simulated run's options: as for teach. A finite run with poses ends with\n"
    "precision/recall. --record DIR: also write every frame into the dataset folder DIR.\n";
constexpr const char* kRecordDescription =
    "Records the configured camera into the dataset folder DIR (docs/DATASETS.md):\n"
    "frames/NNNNNN.png, frames.csv with timestamps (and roll/pitch when [attitude] gives\n"
    "them), camera.toml. A writer thread keeps up with the camera or drops frames (counted);\n"
    "a full disk stops the recording and keeps what was written. Until SIGINT/SIGTERM/\n"
    "SIGHUP or N frames; one JSON line per frame. replay and eval read DIR.\n";
constexpr const char* kReplayDescription =
    "Runs a recorded dataset folder through the same pipeline as repeat; with poses,\n"
    "prints precision/recall (a match within X metres, default 2, is correct).\n";
constexpr const char* kRouteDescription =
    "info: what the file holds. recover: make an interrupted teach loadable (keeps every\n"
    "intact chunk, cuts a torn tail or trailing bytes, appends the commit record); it\n"
    "refuses a file a running teach is writing. --salvage: also for damage in the middle:\n"
    "keeps the intact chunks before it (the original is kept as FILE.db.damaged).\n";

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

void AddCommonOptions(OptionTable& t, SessionArgs* s) {
  t.Text("--config", "FILE", "the configuration file (default: the built-in defaults)",
         &s->config_path);
  t.Count("--frames", "N", "stop after N frames (default: until a signal or the run's end)",
          &s->max_frames);
}

// route info: a teach writing the route now, or the FILE.db.tmp a killed one left.
void PrintTeachState(const char* path, std::FILE* out) {
  long pid = 0;
  if (RouteBeingTaught(path, &pid)) {
    std::fprintf(out, "%s: being taught now by process %ld\n", path, pid);
    return;
  }
  const RouteTmpReport tmp = InspectRouteTmp(path);
  if (!tmp.exists)
    return;
  if (tmp.loads)
    std::fprintf(out,
                 "%s.tmp: left by an interrupted teach: %zu intact frames, never committed; "
                 "'skyloc route recover %s.tmp' makes it a route of its own; the next teach of "
                 "%s replaces it\n",
                 path, tmp.frames, path, path);
  else
    std::fprintf(out,
                 "%s.tmp: left by an interrupted teach: %llu bytes, no intact frame; the next "
                 "teach of %s replaces it\n",
                 path, static_cast<unsigned long long>(tmp.bytes), path);
}

// teach and repeat: one table over a route; teach also takes a dataset to teach from and
// may replace the route.
ParseOutcome ParseOnRoute(std::span<char* const> args, LoopMode mode, SessionArgs* s) {
  const bool teach = mode == LoopMode::kTeach;
  *s = {.mode = mode, .label = teach ? "skyloc teach" : "skyloc repeat"};
  OptionTable t(teach ? "teach" : "repeat", "--route FILE.db [options]",
                teach ? kTeachDescription : kRepeatDescription);
  t.Text("--route", "FILE.db", teach ? "the route database to write" : "the taught route database",
         &s->route_path);
  AddCommonOptions(t, s);
  if (teach) {
    t.Text("--dataset", "DIR", "teach from this recorded dataset folder", &s->dataset);
    t.Flag("--force", "replace an existing route database", &s->force);
  }
  t.Text("--record", "DIR", "also write every frame into this dataset folder", &s->record_dir);
  AddSimRunOptions(&t, SimRunOptions::kRun, &s->sim);
  if (const ParseOutcome o = t.Parse(args); o != ParseOutcome::kRun)
    return o;
  if (s->route_path.empty())
    return t.Refuse("--route FILE.db is required");
  return ParseOutcome::kRun;
}

ParseOutcome ParseTeachArgs(std::span<char* const> args, SessionArgs* s) {
  return ParseOnRoute(args, LoopMode::kTeach, s);
}

ParseOutcome ParseRepeatArgs(std::span<char* const> args, SessionArgs* s) {
  return ParseOnRoute(args, LoopMode::kRepeat, s);
}

ParseOutcome ParseRecordArgs(std::span<char* const> args, SessionArgs* s) {
  *s = {.mode = LoopMode::kRecord, .label = "skyloc record"};
  OptionTable t("record", "DIR [options]", kRecordDescription);
  std::vector<std::string> dir;
  t.Positional("DIR", "the dataset folder to record into", 1, 1, &dir);
  AddCommonOptions(t, s);
  AddSimRunOptions(&t, SimRunOptions::kRun, &s->sim);
  if (const ParseOutcome o = t.Parse(args); o != ParseOutcome::kRun)
    return o;
  s->record_dir = dir.front();
  return ParseOutcome::kRun;
}

ParseOutcome ParseReplayArgs(std::span<char* const> args, SessionArgs* s) {
  *s = {.mode = LoopMode::kRepeat, .label = "skyloc replay"};
  OptionTable t("replay", "DATASET --route FILE.db [options]", kReplayDescription);
  std::vector<std::string> dataset;
  t.Positional("DATASET", "the recorded dataset folder", 1, 1, &dataset);
  t.Text("--route", "FILE.db", "the taught route database", &s->route_path);
  AddCommonOptions(t, s);
  t.Choice<bool>("--pace", "at the recorded frame times, or as fast as it runs (default fast)",
                 {{"recorded", true}, {"fast", false}}, &s->paced);
  t.Number("--tolerance-m", "X", "a match within X metres is correct (default 2)", kPositive,
           &s->tolerance_m);
  if (const ParseOutcome o = t.Parse(args); o != ParseOutcome::kRun)
    return o;
  if (s->route_path.empty())
    return t.Refuse("--route FILE.db is required");
  s->dataset = dataset.front();
  return ParseOutcome::kRun;
}

// route's command line: what to do with which route database.
struct RouteOptions {
  bool recover = false;
  bool salvage = false;
  std::string path;
};

ParseOutcome ParseRouteArgs(std::span<char* const> args, RouteOptions* o) {
  OptionTable t("route", "info FILE.db | recover [--salvage] FILE.db", kRouteDescription);
  std::vector<std::string> words;
  t.Positional("info|recover FILE.db", "what to do, and the route database", 2, 2, &words);
  t.Flag("--salvage", "recover: also past damage in the middle of the file", &o->salvage);
  if (const ParseOutcome outcome = t.Parse(args); outcome != ParseOutcome::kRun)
    return outcome;
  o->recover = words[0] == "recover";
  if (!o->recover && words[0] != "info")
    return t.Refuse("unknown route subcommand '" + words[0] + "': expected info or recover");
  if (o->salvage && !o->recover)
    return t.Refuse("--salvage is for 'route recover' only");
  o->path = words[1];
  return ParseOutcome::kRun;
}

// route info prints what the file holds; route recover makes it loadable.
int InfoOrRecover(const RouteOptions& o) {
  const bool recover = o.recover;
  const bool salvage = o.salvage;
  const char* path = o.path.c_str();
  RouteDbLoadReport report;
  Status s;
  if (recover) {
    s = RecoverRouteDb(path, &report, salvage);
  } else {
    s = LoadRouteDb(path, nullptr, RouteDbLoadPolicy::kRecoverInterrupted, nullptr, &report);
  }
  if (!s.ok()) {
    std::fprintf(stderr, "skyloc route: %s\n", s.message());
    if (!recover)
      PrintTeachState(path, stderr);
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
        "%s: horizon strips for heading: %u columns at %u bits a column (%zu bytes per frame), "
        "%u rows over %.2f..%.2f deg above the horizon\n",
        path, st.strip.columns, report.strip_bits,
        RouteDbStripBytes(report.version, st.strip.columns), st.strip.band_rows,
        st.strip.elevation_min_cdeg / 100.0, st.strip.elevation_max_cdeg / 100.0);
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
  if (!recover)
    PrintTeachState(path, stdout);
  return kExitOk;
}

}  // namespace

int RunTeach(std::span<char* const> args) {
  return RunParsed(args, ParseTeachArgs, RunWithConfigFile);
}

int RunRepeat(std::span<char* const> args) {
  return RunParsed(args, ParseRepeatArgs, RunWithConfigFile);
}

int RunRecord(std::span<char* const> args) {
  return RunParsed(args, ParseRecordArgs, RunWithConfigFile);
}

int RunReplay(std::span<char* const> args) {
  return RunParsed(args, ParseReplayArgs, RunWithConfigFile);
}

int RunRoute(std::span<char* const> args) {
  return RunParsed(args, ParseRouteArgs, InfoOrRecover);
}

}  // namespace skyloc::cli
