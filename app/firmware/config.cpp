#include "firmware/config.h"

#include <sys/stat.h>
#include <toml++/toml.h>

#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <span>
#include <sstream>
#include <tuple>
#include <vector>

#include "skyloc/drivers/status_pattern.h"
#include "skyloc/drivers/toml_keys.h"
#include "skyloc/drivers/toml_text.h"
#include "skyloc/dsp/sh_grid.h"

namespace skyloc::firmware {
namespace {

template <typename E>
struct EnumName {
  const char* name;
  E value;
};

// Spelled here: the configuration's own enums and the simulator's sampling.
constexpr EnumName<CameraKind> kCameraKinds[] = {{"sim", CameraKind::kSim},
                                                 {"v4l2", CameraKind::kV4l2},
                                                 {"libcamera", CameraKind::kLibcamera},
                                                 {"dataset", CameraKind::kDataset}};
constexpr EnumName<sim::Sampling> kSimSamplings[] = {{"distance", sim::Sampling::kDistance},
                                                     {"time", sim::Sampling::kTime}};
constexpr EnumName<SegmentationMethod> kSegmentationMethods[] = {
    {"otsu", SegmentationMethod::kOtsu}, {"fixed", SegmentationMethod::kFixed}};
constexpr EnumName<GridPreset> kGridPresets[] = {{"oversampled", GridPreset::kOversampled},
                                                 {"auto", GridPreset::kAuto},
                                                 {"paper", GridPreset::kPaper},
                                                 {"custom", GridPreset::kCustom}};
constexpr EnumName<StatusOutputKind> kStatusOutputKinds[] = {{"none", StatusOutputKind::kNone},
                                                             {"sim", StatusOutputKind::kSim},
                                                             {"gpio", StatusOutputKind::kGpio}};
constexpr EnumName<Matcher> kMatchers[] = {{"filter", Matcher::kRouteFilter},
                                           {"openseqslam", Matcher::kOpenSeqSlam}};
constexpr EnumName<AttitudeKind> kAttitudeKinds[] = {{"none", AttitudeKind::kNone},
                                                     {"iio", AttitudeKind::kIio},
                                                     {"dataset", AttitudeKind::kDataset},
                                                     {"sim", AttitudeKind::kSim}};

// The table of an enum whose own layer spells its values (`name`, e.g.
// dsp::AmplitudeNormalisationName): each value listed once, its name the layer's.
template <auto name, typename E, typename... More>
constexpr std::array<EnumName<E>, 1 + sizeof...(More)> SpelledBy(E first, More... more) {
  return {{{name(first), first}, {name(more), more}...}};
}

constexpr auto kNormalisations = SpelledBy<dsp::AmplitudeNormalisationName>(
    dsp::AmplitudeNormalisation::kNone, dsp::AmplitudeNormalisation::kDivideByA0,
    dsp::AmplitudeNormalisation::kUnitL2);
constexpr auto kStatusLineModes = SpelledBy<drivers::StatusLineModeName>(
    drivers::StatusLineMode::kLinePerState, drivers::StatusLineMode::kBlink);
constexpr auto kRouteStorages = SpelledBy<dsp::ReferenceStorageName>(
    dsp::ReferenceStorage::kFloat32, dsp::ReferenceStorage::kBFloat16,
    dsp::ReferenceStorage::kCodes8, dsp::ReferenceStorage::kCodes16);

// Every table above, found by its enum's type (NameOf, SectionReader::Enum).
template <typename E, std::size_t N>
constexpr std::span<const EnumName<E>> Names(const EnumName<E> (&names)[N]) {
  return names;
}
template <typename E, std::size_t N>
constexpr std::span<const EnumName<E>> Names(const std::array<EnumName<E>, N>& names) {
  return names;
}
constexpr std::tuple kNameTables{Names(kCameraKinds),         Names(kSimSamplings),
                                 Names(kSegmentationMethods), Names(kGridPresets),
                                 Names(kNormalisations),      Names(kStatusOutputKinds),
                                 Names(kStatusLineModes),     Names(kMatchers),
                                 Names(kAttitudeKinds),       Names(kRouteStorages)};

// What the sections read: each one's keys, and the first key refused as unknown, so that
// a key written in the wrong section can be told where it belongs.
struct KeysRead {
  struct Section {
    const char* name;
    std::vector<std::string> keys;
  };
  std::vector<Section> sections;
  std::string unknown_key;  // the first refused key, when it was the first error
  const char* unknown_in = nullptr;
  unsigned unknown_line = 0;
};

// Reads the keys of one [section] through drivers::TomlKeyReader; adds the enums of this
// file's name tables. The first error of every section lands in `*error`.
class SectionReader : public drivers::TomlKeyReader {
 public:
  SectionReader(const toml::table* table, const char* section, const std::string& source,
                Status* error, KeysRead* keys)
      : TomlKeyReader(table, section, source.c_str(), drivers::TomlKeyNaming::kSection),
        section_(section),
        error_(error),
        keys_(keys) {}
  SectionReader(const SectionReader&) = delete;
  SectionReader& operator=(const SectionReader&) = delete;
  ~SectionReader() = default;

  // An enum's key: one of the names of its table.
  template <typename E>
  void Enum(const char* key, E* out) {
    const std::span<const EnumName<E>> names = std::get<std::span<const EnumName<E>>>(kNameTables);
    std::vector<const char*> list;
    std::size_t index = names.size();
    for (std::size_t i = 0; i < names.size(); ++i) {
      list.push_back(names[i].name);
      if (names[i].value == *out)
        index = i;
    }
    Choice(key, list, &index);
    if (index < names.size())
      *out = names[index].value;
  }
  // Reports the first key nobody asked for; keeps the first error of all.
  void Finish() {
    const Status s = TomlKeyReader::Finish();
    if (error_->ok() && !s.ok() && !unknown_key().empty()) {
      keys_->unknown_key = unknown_key();
      keys_->unknown_in = section_;
      keys_->unknown_line = unknown_line();
    }
    if (error_->ok())
      *error_ = s;
    keys_->sections.push_back({section_, known_keys()});
  }

 private:
  const char* section_;
  Status* error_;
  KeysRead* keys_;
};

// A key refused in one section that another section reads: the error says where it belongs.
Status WithWhereTheKeyBelongs(const Status& error, const KeysRead& keys,
                              const std::string& source) {
  if (keys.unknown_key.empty())
    return error;
  std::string belongs;  // "[camera]", "[camera] or [status]", ...
  for (const KeysRead::Section& s : keys.sections) {
    bool reads = false;
    for (const std::string& k : s.keys)
      reads = reads || k == keys.unknown_key;
    if (reads && std::string_view(s.name) != keys.unknown_in)
      belongs += std::string(belongs.empty() ? "" : " or ") + "[" + s.name + "]";
  }
  if (belongs.empty())
    return error;
  return Status::Error(StatusCode::kInvalidArgument,
                       "%s:%u: key %s is not known in [%s]; it belongs in %s", source.c_str(),
                       keys.unknown_line, keys.unknown_key.c_str(), keys.unknown_in,
                       belongs.c_str());
}
}  // namespace

void ResolveDescriptorGrid(DescriptorConfig* d) {
  switch (d->grid) {
    case GridPreset::kOversampled: {
      const dsp::ShGridConfig g = dsp::OversampledShGridConfig(d->bands);
      d->rings = g.rings;
      d->longitudes = g.longitudes;
      break;
    }
    case GridPreset::kAuto: {
      const dsp::ShGridConfig g = dsp::DefaultShGridConfig(d->bands);
      d->rings = g.rings;
      d->longitudes = g.longitudes;
      break;
    }
    case GridPreset::kPaper: {
      const dsp::ShGridConfig g = dsp::PaperShGridConfig();
      d->bands = 120;
      d->rings = g.rings;
      d->longitudes = g.longitudes;
      break;
    }
    case GridPreset::kCustom:
      break;
  }
}

template <typename E>
const char* NameOf(E value) {
  for (const EnumName<E>& n : std::get<std::span<const EnumName<E>>>(kNameTables))
    if (n.value == value)
      return n.name;
  return "?";
}
template const char* NameOf(CameraKind);
template const char* NameOf(GridPreset);
template const char* NameOf(StatusOutputKind);
template const char* NameOf(AttitudeKind);
template const char* NameOf(Matcher);
template const char* NameOf(dsp::ReferenceStorage);

template <typename E>
bool ValueOf(std::string_view name, E* value) {
  for (const EnumName<E>& n : std::get<std::span<const EnumName<E>>>(kNameTables))
    if (name == n.name) {
      *value = n.value;
      return true;
    }
  return false;
}
template bool ValueOf(std::string_view, dsp::ReferenceStorage*);

template <typename E>
std::string NamesOf() {
  std::string names;
  for (const EnumName<E>& n : std::get<std::span<const EnumName<E>>>(kNameTables))
    names += std::string(names.empty() ? "" : ", ") + n.name;
  return names;
}
template std::string NamesOf<dsp::ReferenceStorage>();

Config DefaultConfig() {
  Config c;
  ResolveDescriptorGrid(&c.descriptor);
  return c;
}

namespace {

// [camera]
void ReadCameraSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Enum("kind", &c.camera.kind);
  r.String("device", &c.camera.device, false);
  r.Path("dataset", &c.camera.dataset);
  r.Path("lens_file", &c.camera.lens_file);
  SimWorldConfig& sim = c.camera.sim;
  r.OneOf("sim_world", &sim.name, {"city", "forest", "repetitive", "street"});
  std::int64_t seed = static_cast<std::int64_t>(sim.seed);
  r.Int64("sim_seed", &seed, 0, INT64_MAX);
  sim.seed = static_cast<std::uint64_t>(seed);
  r.Enum("sim_sampling", &sim.frames.sampling);
  r.Double("sim_speed_mps", &sim.frames.speed.cruise_mps, 0.01, 100.0);
  r.Double("sim_speed_band", &sim.frames.speed.band, 0.0, 0.99);
  r.Double("sim_accel_mps2", &sim.frames.speed.accel_mps2, 0.01, 100.0);
  r.Double("sim_start_stop_s", &sim.frames.speed.start_stop_s, 0.0, 3600.0);
  r.Int("sim_stops", &sim.frames.speed.stops, 0, 1000);
  r.Double("sim_stop_min_s", &sim.frames.speed.stop_min_s, 0.0, 3600.0);
  r.Double("sim_stop_max_s", &sim.frames.speed.stop_max_s, 0.0, 3600.0);
  if (r.ok() && sim.frames.speed.stop_min_s > sim.frames.speed.stop_max_s)
    r.Invalid("sim_stop_min_s", "must not exceed sim_stop_max_s");
  r.Int("width", &c.camera.capture.width, 16, 8192);
  r.Int("height", &c.camera.capture.height, 16, 8192);
  r.Double("fps", &c.camera.capture.fps, 0.1, 1000.0);
  r.Int("frame_timeout_ms", &c.camera.frame_timeout_ms, 1, 60000);
  r.Int("reconnect_timeout_ms", &c.camera.reconnect_timeout_ms, 0, 600000);
  if (r.ok() && c.camera.kind == CameraKind::kDataset && c.camera.dataset.empty())
    r.Invalid("dataset", "must name the dataset folder when kind = \"dataset\"");
}

// [segmentation]
void ReadSegmentationSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Enum("method", &c.segmentation.method);
  r.Int("threshold", &c.segmentation.threshold, 0, 254);
}

// [descriptor]
void ReadDescriptorSection(SectionReader& r, const toml::table* table, Config& c) {
  r.Int("bands", &c.descriptor.bands, 1, 256);
  r.Enum("grid", &c.descriptor.grid);
  r.Int("rings", &c.descriptor.rings, 0, 1024);
  r.Int("longitudes", &c.descriptor.longitudes, 0, 4096);
  r.Enum("normalisation", &c.descriptor.normalisation);
  if (r.ok() && c.descriptor.grid == GridPreset::kCustom) {
    if (c.descriptor.rings < 1)
      r.Invalid("rings", "must be 1..1024 when grid = \"custom\"");
    else if (c.descriptor.longitudes < 4)
      r.Invalid("longitudes", "must be 4..4096 when grid = \"custom\"");
  } else if (r.ok() && (c.descriptor.rings != 0 || c.descriptor.longitudes != 0)) {
    r.Invalid(c.descriptor.rings != 0 ? "rings" : "longitudes",
              "is only used with grid = \"custom\"; remove it or set grid = \"custom\"");
  }
  const toml::table* t = table;
  if (r.ok() && c.descriptor.grid == GridPreset::kPaper && t != nullptr && t->contains("bands") &&
      c.descriptor.bands != 120)
    r.Invalid("bands", "must be 120 (or left out) with grid = \"paper\"");
  ResolveDescriptorGrid(&c.descriptor);
}

// [seqslam]
void ReadSeqslamSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Enum("matcher", &c.seqslam.matcher);
  dsp::RouteFilterParams& filter = c.seqslam.filter;
  dsp::SeqSlamParams& open = c.seqslam.openseqslam;
  int ds = c.seqslam.ds(), rwindow = c.seqslam.rwindow();
  r.Int("ds", &ds, 1, 100);
  c.seqslam.set_ds(ds);
  r.Int("max_advance", &filter.max_advance, 1, 64);
  r.Float("keyframe_noise_factor", &filter.keyframe_noise_factor, 0.0, 100.0);
  r.Int("search_window", &filter.search_window, 0, dsp::kMaxSearchWindow);
  r.Int("refresh_frames", &filter.refresh_frames, 0, dsp::kMaxRefreshFrames);
  r.Float("vmin", &open.v_min, 0.1, 10.0);
  r.Float("vmax", &open.v_max, 0.1, 10.0);
  r.Float("vstep", &open.v_step, 0.01, 10.0);
  r.Int("rwindow", &rwindow, 0, 1000);
  filter.uniqueness_window = rwindow;
  open.uniqueness_window = rwindow;
  r.Int("contrast_r", &open.contrast_window, 0, 1000);
  if (r.ok() && open.v_max < open.v_min)
    r.Invalid("vmax", "must not be smaller than vmin");
  if (r.ok() && filter.search_window > 0 && filter.refresh_frames < 1)
    r.Invalid("refresh_frames",
              "must be 1..1000 with search_window > 0 (how many frames a row outside the "
              "window may go without being compared)");
  else if (r.ok() && filter.search_window == 0 && filter.refresh_frames != 0)
    r.Invalid("refresh_frames", "is only used with search_window > 0; remove it or set both");
}

// [capacities]
void ReadCapacitiesSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Int("route_frames", &c.capacities.route_frames, 1, 1000000);
  r.Enum("route_storage", &c.capacities.route_storage);
}

// [state]
void ReadStateSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Float("enter_confidence", &c.state.enter_confidence, 0.0, 1.0);
  r.Float("stay_confidence", &c.state.stay_confidence, 0.0, 1.0);
  r.Float("max_uniqueness", &c.state.max_uniqueness, 0.0, 1.0);
  r.Int("confirm_frames", &c.state.confirm_frames, 1, 1000);
  r.Int("drop_frames", &c.state.drop_frames, 1, 1000);
  r.Int("lost_frames", &c.state.lost_frames, 1, 10000);
  r.Double("index_tolerance", &c.state.index_tolerance, 0.0, 10000.0);
  if (r.ok() && c.state.stay_confidence > c.state.enter_confidence)
    r.Invalid("stay_confidence", "must not be above enter_confidence (hysteresis)");
}

// [status]
void ReadStatusSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Enum("kind", &c.status.kind);
  r.String("chip", &c.status.chip, false);
  r.Int("line_lost", &c.status.line_lost, 0, 511);
  r.Int("line_searching", &c.status.line_searching, 0, 511);
  r.Int("line_localised", &c.status.line_localised, 0, 511);
  r.Enum("encoding", &c.status.encoding);
  r.Bool("active_low", &c.status.active_low);
  r.Int("button_line", &c.status.button_line, -1, 511);
  r.Bool("button_active_low", &c.status.button_active_low);
  r.Int("button_debounce_ms", &c.status.button_debounce_ms, 0, 1000);
  if (r.ok() && c.status.encoding == drivers::StatusLineMode::kLinePerState) {
    if (c.status.line_localised == c.status.line_lost ||
        c.status.line_localised == c.status.line_searching)
      r.Invalid("line_localised", "must differ from line_lost and line_searching");
    else if (c.status.line_searching == c.status.line_lost)
      r.Invalid("line_searching", "must differ from line_lost");
  }
  // The button is an input: it cannot share a pin with a lit indicator.
  const StatusConfig& st = c.status;
  const bool per_state = st.encoding == drivers::StatusLineMode::kLinePerState;
  if (r.ok() && st.button_line >= 0 &&
      (st.button_line == st.line_localised ||
       (per_state && (st.button_line == st.line_lost || st.button_line == st.line_searching))))
    r.Invalid("button_line",
              per_state ? "must differ from line_lost, line_searching and line_localised "
                          "(-1: no button)"
                        : "must differ from line_localised, the blinking line (-1: no button)");
  if (r.ok() && st.button_line >= 0 && st.kind == StatusOutputKind::kNone)
    r.Invalid("button_line", "needs kind = \"gpio\" (the button is read on its chip), or -1");
}

// [realtime]
void ReadRealtimeSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Int("sched_fifo_priority", &c.realtime.sched_fifo_priority, 0, 99);
  r.Bool("mlockall", &c.realtime.mlockall);
  r.Int("cpu_affinity", &c.realtime.cpu_affinity, -1, 1023);
}

// [route_db]
void ReadRouteDbSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  r.Int("flush_every", &c.route_db.flush_every, 1, 100000);
}

// [attitude]
void ReadAttitudeSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  AttitudeConfig& a = c.attitude;
  r.Enum("kind", &a.kind);
  r.String("device", &a.device, true);
  r.String("gyro_device", &a.gyro_device, true);
  r.String("trigger", &a.trigger, true);
  r.Double("rate_hz", &a.rate_hz, 1.0, 10000.0);
  r.Double("mount_roll_deg", &a.mount_roll_deg, -180.0, 180.0);
  r.Double("mount_pitch_deg", &a.mount_pitch_deg, -180.0, 180.0);
  r.Double("mount_yaw_deg", &a.mount_yaw_deg, -180.0, 180.0);
  r.Double("max_tilt_deg", &a.max_tilt_deg, 0.0, 75.0);
  r.Double("cap_taper_deg", &a.cap_taper_deg, 0.0, 30.0);
  r.Double("filter_kp", &a.filter_kp, 0.0, 100.0);
  r.Double("filter_ki", &a.filter_ki, 0.0, 100.0);
  r.Double("accel_gate_mps2", &a.accel_gate_mps2, 0.0, 100.0);
  r.Int("stale_ms", &a.stale_ms, 1, 60000);
  if (r.ok() && a.kind == AttitudeKind::kIio && a.device.empty())
    r.Invalid("device",
              "must name the IMU when kind = \"iio\" (/dev/iio:deviceN or its IIO "
              "name, e.g. \"bmi160\")");
  // A real IMU's samples carry CLOCK_MONOTONIC, as a live camera's frames do; a simulated
  // or recorded run stamps its frames with the run's own time (from 0, or the recording's),
  // which has nothing in common with it: a frame would get no sample (the cap off for
  // good) or samples of another moment.
  if (r.ok() && a.kind == AttitudeKind::kIio &&
      (c.camera.kind == CameraKind::kSim || c.camera.kind == CameraKind::kDataset))
    r.Invalid("kind",
              "\"iio\" needs a live camera ([camera] kind = \"v4l2\" or \"libcamera\"): a "
              "simulated or recorded run stamps its frames with the run's own time, not the "
              "IMU's CLOCK_MONOTONIC (kind = \"sim\" simulates the run's IMU, \"dataset\" "
              "reads a dataset's roll and pitch)");
  if (r.ok() && a.kind == AttitudeKind::kDataset && c.camera.kind != CameraKind::kDataset)
    r.Invalid("kind",
              "\"dataset\" reads the replayed dataset's roll_deg,pitch_deg columns: "
              "it needs [camera] kind = \"dataset\"");
  if (r.ok() && a.kind == AttitudeKind::kSim && c.camera.kind != CameraKind::kSim)
    r.Invalid("kind",
              "\"sim\" simulates the IMU of the simulated camera's run: it needs "
              "[camera] kind = \"sim\"");
  // Distance sampling places a frame every metre of route at the camera's rate: the robot
  // drives at 1 m x fps and its speed steps at every frame, which an accelerometer reads as
  // tilt (pitch up to 10 degrees at 10 fps, 39 at 30 fps, on a level run). Time sampling
  // drives a speed profile with bounded acceleration.
  if (r.ok() && a.kind == AttitudeKind::kSim && c.camera.kind == CameraKind::kSim &&
      c.camera.sim.frames.sampling == sim::Sampling::kDistance)
    r.Invalid("kind",
              "\"sim\" needs [camera] sim_sampling = \"time\": distance sampling steps the "
              "simulated robot's speed at every frame, which its IMU reads as tilts of tens "
              "of degrees");
}

// [heading]
void ReadHeadingSection(SectionReader& r, const toml::table* /*table*/, Config& c) {
  dsp::HorizonStripOptions& h = c.heading.strip;
  dsp::HeadingOptions& e = c.heading.estimate;
  r.Int("strip_columns", &h.n_azimuth, 0, 4096);
  r.Int("band_rows", &h.band_rows, 1, 256);
  r.Double("elevation_min_deg", &h.elevation_min_deg, -90.0, 90.0);
  r.Double("elevation_max_deg", &h.elevation_max_deg, -90.0, 90.0);
  r.Bool("surf", &e.surf);
  r.Float("surf_threshold", &e.features.threshold, 0.0, 255.0);
  r.Int("surf_max_features", &e.max_features, 1, 4096);
  r.Int("surf_min_inliers", &e.min_surf_inliers, 2, 4096);
  if (r.ok() && h.n_azimuth != 0 && h.n_azimuth < 148)
    r.Invalid("strip_columns",
              "must be 0 (no heading) or at least 148: 1D SURF's widest filter spans 147 "
              "columns");
  if (r.ok() && h.elevation_min_deg > h.elevation_max_deg)
    r.Invalid("elevation_min_deg", "must not be above elevation_max_deg");
}

// [output] kinds = ["stdout", "socket", "dds"]: any of them, each once (an empty list:
// nothing but the status lines).
void ReadOutputKinds(SectionReader& r, const toml::table* table, OutputConfig& o) {
  if (table == nullptr || !r.Has("kinds"))
    return;
  const toml::array* kinds = table->get_as<toml::array>("kinds");
  if (kinds == nullptr) {
    r.Invalid("kinds",
              "must be a list of \"stdout\", \"socket\", \"dds\" (e.g. kinds = "
              "[\"stdout\", \"socket\"])");
    return;
  }
  o.to_stdout = o.to_socket = o.to_dds = false;
  for (const toml::node& kind : *kinds) {
    const std::optional<std::string_view> name = kind.value<std::string_view>();
    bool* flag = !name               ? nullptr
                 : *name == "stdout" ? &o.to_stdout
                 : *name == "socket" ? &o.to_socket
                 : *name == "dds"    ? &o.to_dds
                                     : nullptr;
    if (flag == nullptr) {
      r.Invalid("kinds", "lists something that is not \"stdout\", \"socket\" or \"dds\"");
      return;
    }
    if (*flag) {
      r.Invalid("kinds", "lists an output twice");
      return;
    }
    *flag = true;
  }
}

// [output]
void ReadOutputSection(SectionReader& r, const toml::table* table, Config& c) {
  OutputConfig& o = c.output;
  ReadOutputKinds(r, table, o);
  r.String("socket_path", &o.socket_path, false);
  r.Int("socket_max_readers", &o.socket_max_readers, 1, 64);
  r.String("ros_topic", &o.ros_topic, false);
  r.Int("ros_domain_id", &o.ros_domain_id, 0, 232);
  r.String("frame_id", &o.frame_id, true);
  if (r.ok() && (o.socket_path[0] != '/' || o.socket_path.size() > 107))
    r.Invalid("socket_path", "must be an absolute path of at most 107 characters");
  if (r.ok() && o.ros_topic[0] != '/')
    r.Invalid("ros_topic", "must be an absolute ROS 2 topic name (\"/skyloc/localisation\")");
  for (const char ch : o.ros_topic)
    if (r.ok() && !(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '/'))
      r.Invalid("ros_topic", "may hold letters, digits, '_' and '/' only (a ROS 2 name)");
}

// The sections in the order they are read ([attitude] checks [camera]'s kind).
struct ConfigSection {
  const char* name;
  void (*read)(SectionReader& r, const toml::table* table, Config& c);
};
constexpr ConfigSection kConfigSections[] = {
    {"camera", ReadCameraSection},         {"segmentation", ReadSegmentationSection},
    {"descriptor", ReadDescriptorSection}, {"seqslam", ReadSeqslamSection},
    {"capacities", ReadCapacitiesSection}, {"state", ReadStateSection},
    {"status", ReadStatusSection},         {"realtime", ReadRealtimeSection},
    {"route_db", ReadRouteDbSection},      {"attitude", ReadAttitudeSection},
    {"heading", ReadHeadingSection},       {"output", ReadOutputSection}};

// Every top-level item must be a known [section].
Status CheckSections(const toml::table& root, const std::string& source) {
  for (auto&& [k, node] : root) {
    const std::string name(k.str());
    if (!node.is_table()) {
      // A key above every [section] header (or a section written as a key).
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%u: key %s is not known at the top level: every key belongs in "
                           "a [section] (see config/skyloc.toml for where %s goes)",
                           source.c_str(), node.source().begin.line, name.c_str(), name.c_str());
    }
    bool known = false;
    std::string names;
    for (const ConfigSection& s : kConfigSections) {
      known = known || name == s.name;
      names += std::string(names.empty() ? "" : ", ") + s.name;
    }
    if (!known) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%u: [%s] is not a known section (known: %s)", source.c_str(),
                           node.source().begin.line, name.c_str(), names.c_str());
    }
  }
  return Status::Ok();
}

}  // namespace

Result<Config> ParseConfig(std::string_view text, std::string_view source_name) {
  const std::string source(source_name);
  SKYLOC_TRY_ASSIGN(const toml::table root, drivers::ParseTomlText(text, source.c_str()));
  SKYLOC_TRY(CheckSections(root, source));
  Config c;
  Status error;
  KeysRead keys;
  for (const ConfigSection& s : kConfigSections) {
    const toml::table* table = root.get_as<toml::table>(s.name);
    SectionReader r(table, s.name, source, &error, &keys);
    s.read(r, table, c);
    r.Finish();
  }
  if (!error.ok())
    return WithWhereTheKeyBelongs(error, keys, source);
  return c;
}

Status CheckPathKey(const Config& config, const char* key, const std::string& path, PathKind kind) {
  struct stat st {};
  const bool found = ::stat(path.c_str(), &st) == 0;
  const int saved = errno;
  const char* wrong = nullptr;
  if (!found)
    wrong = saved == ENOENT || saved == ENOTDIR ? "not found" : std::strerror(saved);
  else if (kind == PathKind::kFolder && !S_ISDIR(st.st_mode))
    wrong = "not a folder";
  else if (kind == PathKind::kFile && !S_ISREG(st.st_mode))
    wrong = S_ISDIR(st.st_mode) ? "a folder, not a file" : "not a regular file";
  if (wrong == nullptr)
    return Status::Ok();
  return Status::Error(found ? StatusCode::kInvalidArgument : StatusCode::kNotFound,
                       "%s: %s = \"%s\": %s; fix the path there (a relative path is relative "
                       "to the config file's folder)",
                       config.source.empty() ? "built-in defaults" : config.source.c_str(), key,
                       path.c_str(), wrong);
}

Result<Config> LoadConfigFile(const char* path) {
  // A directory opens and reads as empty: it would pass for a config of defaults.
  struct stat st {};
  if (::stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "config %s is %s, not a file: --config takes the configuration file "
                         "(e.g. /etc/skyloc/skyloc.toml, a copy of config/skyloc.toml)",
                         path, S_ISDIR(st.st_mode) ? "a directory" : "not a regular file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return Status::FromErrno(errno,
                             "cannot read config %s (use --config FILE, or copy "
                             "config/skyloc.toml there)",
                             path);
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    return Status::Error(StatusCode::kInvalidArgument, "cannot read config %s: read error", path);
  }
  Result<Config> c = ParseConfig(text.str(), path);
  if (!c.ok())
    return c;
  c->source = path;
  return c;
}

}  // namespace skyloc::firmware
