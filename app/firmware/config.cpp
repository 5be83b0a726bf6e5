#include "firmware/config.h"

#include <sys/stat.h>
#include <toml++/toml.h>

#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>

#include "skyloc/drivers/toml_text.h"
#include "skyloc/dsp/sh_grid.h"

namespace skyloc::firmware {
namespace {

template <typename E>
struct EnumName {
  const char* name;
  E value;
};

constexpr EnumName<CameraKind> kCameraKinds[] = {{"sim", CameraKind::kSim},
                                                 {"v4l2", CameraKind::kV4l2},
                                                 {"libcamera", CameraKind::kLibcamera},
                                                 {"dataset", CameraKind::kDataset}};
constexpr EnumName<SegmentationMethod> kSegmentationMethods[] = {
    {"otsu", SegmentationMethod::kOtsu}, {"fixed", SegmentationMethod::kFixed}};
constexpr EnumName<GridPreset> kGridPresets[] = {{"oversampled", GridPreset::kOversampled},
                                                 {"auto", GridPreset::kAuto},
                                                 {"paper", GridPreset::kPaper},
                                                 {"custom", GridPreset::kCustom}};
constexpr EnumName<dsp::AmplitudeNormalisation> kNormalisations[] = {
    {dsp::AmplitudeNormalisationName(dsp::AmplitudeNormalisation::kNone),
     dsp::AmplitudeNormalisation::kNone},
    {dsp::AmplitudeNormalisationName(dsp::AmplitudeNormalisation::kDivideByA0),
     dsp::AmplitudeNormalisation::kDivideByA0},
    {dsp::AmplitudeNormalisationName(dsp::AmplitudeNormalisation::kUnitL2),
     dsp::AmplitudeNormalisation::kUnitL2}};
constexpr EnumName<StatusOutputKind> kStatusOutputKinds[] = {{"none", StatusOutputKind::kNone},
                                                             {"sim", StatusOutputKind::kSim},
                                                             {"gpio", StatusOutputKind::kGpio}};
constexpr EnumName<StatusEncoding> kStatusEncodings[] = {{"per-state", StatusEncoding::kPerState},
                                                         {"blink", StatusEncoding::kBlink}};
constexpr EnumName<Matcher> kMatchers[] = {{"filter", Matcher::kRouteFilter},
                                           {"openseqslam", Matcher::kOpenSeqSlam}};
constexpr EnumName<AttitudeKind> kAttitudeKinds[] = {{"none", AttitudeKind::kNone},
                                                     {"iio", AttitudeKind::kIio},
                                                     {"dataset", AttitudeKind::kDataset},
                                                     {"sim", AttitudeKind::kSim}};
constexpr EnumName<dsp::ReferenceStorage> kRouteStorages[] = {
    {"float32", dsp::ReferenceStorage::kFloat32}, {"bfloat16", dsp::ReferenceStorage::kBFloat16}};

template <typename E, std::size_t N>
const char* NameOf(const EnumName<E> (&names)[N], E value) {
  for (const auto& n : names)
    if (n.value == value)
      return n.name;
  return "?";
}

template <typename E, std::size_t N>
bool ValueOf(const EnumName<E> (&names)[N], std::string_view name, E* out) {
  for (const auto& n : names) {
    if (name == n.name) {
      *out = n.value;
      return true;
    }
  }
  return false;
}

template <typename E, std::size_t N>
std::string Choices(const EnumName<E> (&names)[N]) {
  std::string s;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0)
      s += i + 1 == N ? " or " : ", ";
    s += '"';
    s += names[i].name;
    s += '"';
  }
  return s;
}

// Reads the keys of one [section], remembering which it consumed so that anything left
// over is reported as unknown. The first error wins; later reads are no-ops.
class SectionReader {
 public:
  SectionReader(const toml::table* table, const char* section, std::string_view source,
                Status* error)
      : table_(table), section_(section), source_(source), error_(error) {}

  void Int(const char* key, int* out, std::int64_t lo, std::int64_t hi) {
    std::int64_t v = *out;
    Int64(key, &v, lo, hi);
    *out = static_cast<int>(v);
  }
  void Int64(const char* key, std::int64_t* out, std::int64_t lo, std::int64_t hi) {
    const toml::node* node = Find(key);
    if (node == nullptr)
      return;
    const auto* value = node->as_integer();
    if (value == nullptr) {
      Fail(node, key, "must be an integer in %lld..%lld (default %lld)", Ll(lo), Ll(hi), Ll(*out));
      return;
    }
    const std::int64_t v = value->get();
    if (v < lo || v > hi) {
      Fail(node, key, "= %lld is out of range: must be %lld..%lld (default %lld)", Ll(v), Ll(lo),
           Ll(hi), Ll(*out));
      return;
    }
    *out = v;
  }
  void Double(const char* key, double* out, double lo, double hi) {
    const toml::node* node = Find(key);
    if (node == nullptr)
      return;
    double v = 0;
    if (const auto* f = node->as_floating_point()) {
      v = f->get();
    } else if (const auto* i = node->as_integer()) {
      v = static_cast<double>(i->get());
    } else {
      Fail(node, key, "must be a number in %g..%g (default %g)", lo, hi, *out);
      return;
    }
    if (!std::isfinite(v) || v < lo || v > hi) {
      Fail(node, key, "= %g is out of range: must be %g..%g (default %g)", v, lo, hi, *out);
      return;
    }
    *out = v;
  }
  // A float parameter of dsp (the state machine's thresholds): read as a double, range
  // checked, then rounded to float once.
  void Float(const char* key, float* out, double lo, double hi) {
    double v = static_cast<double>(*out);
    Double(key, &v, lo, hi);
    *out = static_cast<float>(v);
  }
  void Bool(const char* key, bool* out) {
    const toml::node* node = Find(key);
    if (node == nullptr)
      return;
    const auto* value = node->as_boolean();
    if (value == nullptr) {
      Fail(node, key, "must be true or false (default %s)", *out ? "true" : "false");
      return;
    }
    *out = value->get();
  }
  void String(const char* key, std::string* out, bool allow_empty) {
    const toml::node* node = Find(key);
    if (node == nullptr)
      return;
    const auto* value = node->as_string();
    if (value == nullptr) {
      Fail(node, key, "must be a string (default \"%s\")", out->c_str());
      return;
    }
    if (!allow_empty && value->get().empty()) {
      Fail(node, key, "must not be empty (default \"%s\")", out->c_str());
      return;
    }
    *out = value->get();
  }
  template <typename E, std::size_t N>
  void Enum(const char* key, E* out, const EnumName<E> (&names)[N]) {
    const toml::node* node = Find(key);
    if (node == nullptr)
      return;
    const auto* value = node->as_string();
    if (value != nullptr && ValueOf(names, value->get(), out))
      return;
    Fail(node, key, "must be one of %s (default \"%s\")", Choices(names).c_str(),
         NameOf(names, *out));
  }
  void OneOf(const char* key, std::string* out, std::initializer_list<const char*> allowed) {
    const toml::node* node = Find(key);
    if (node == nullptr)
      return;
    const auto* value = node->as_string();
    if (value != nullptr) {
      for (const char* a : allowed) {
        if (value->get() == a) {
          *out = a;
          return;
        }
      }
    }
    std::string choices;
    for (const char* a : allowed) {
      choices += choices.empty() ? "\"" : ", \"";
      choices += a;
      choices += '"';
    }
    Fail(node, key, "must be one of %s (default \"%s\")", choices.c_str(), out->c_str());
  }

  // An error about a combination of keys, reported at `key`.
  void Invalid(const char* key, const char* message) {
    // The key may be missing (its default is what clashes): then point at the section.
    const toml::node* node = table_ == nullptr ? nullptr : table_->get(key);
    Fail(node != nullptr ? node : table_, key, "%s", message);
  }

  // Reports the first key nobody asked for.
  void Finish() {
    if (table_ == nullptr || !error_->ok())
      return;
    for (auto&& [k, node] : *table_) {
      bool known = false;
      for (std::size_t i = 0; i < known_count_; ++i)
        known = known || k.str() == known_[i];
      if (!known) {
        const std::string name(k.str());
        const int line = static_cast<int>(node.source().begin.line);
        const std::string source(source_);
        *error_ = Status::Error(StatusCode::kInvalidArgument,
                                "%s:%d: key %s is not known in [%s]: check its spelling and "
                                "section against config/skyloc.toml",
                                source.c_str(), line, name.c_str(), section_);
        return;
      }
    }
  }

 private:
  static long long Ll(std::int64_t v) { return static_cast<long long>(v); }

  const toml::node* Find(const char* key) {
    if (known_count_ < kMaxKeys)
      known_[known_count_++] = key;
    if (table_ == nullptr || !error_->ok())
      return nullptr;
    return table_->get(key);
  }

  void Fail(const toml::node* node, const char* key, const char* format, ...)
      __attribute__((format(printf, 4, 5))) {
    if (!error_->ok())
      return;
    char detail[160];
    va_list args;
    va_start(args, format);
    std::vsnprintf(detail, sizeof detail, format, args);
    va_end(args);
    const int line = node != nullptr ? static_cast<int>(node->source().begin.line) : 0;
    const std::string source(source_);
    if (line > 0) {
      *error_ = Status::Error(StatusCode::kInvalidArgument, "%s:%d: [%s] %s %s", source.c_str(),
                              line, section_, key, detail);
    } else {
      *error_ = Status::Error(StatusCode::kInvalidArgument, "%s: [%s] %s %s", source.c_str(),
                              section_, key, detail);
    }
  }

  static constexpr std::size_t kMaxKeys = 32;  // [camera] has 19
  const toml::table* table_;
  const char* section_;
  std::string_view source_;
  Status* error_;
  const char* known_[kMaxKeys] = {};
  std::size_t known_count_ = 0;
};

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

const char* CameraKindName(CameraKind kind) {
  return NameOf(kCameraKinds, kind);
}
const char* SegmentationMethodName(SegmentationMethod method) {
  return NameOf(kSegmentationMethods, method);
}
const char* GridPresetName(GridPreset preset) {
  return NameOf(kGridPresets, preset);
}
bool GridPresetFromName(std::string_view name, GridPreset* out) {
  return ValueOf(kGridPresets, name, out);
}
bool NormalisationFromName(std::string_view name, dsp::AmplitudeNormalisation* out) {
  return ValueOf(kNormalisations, name, out);
}
const char* StatusOutputKindName(StatusOutputKind kind) {
  return NameOf(kStatusOutputKinds, kind);
}
const char* StatusEncodingName(StatusEncoding encoding) {
  return NameOf(kStatusEncodings, encoding);
}
const char* AttitudeKindName(AttitudeKind kind) {
  return NameOf(kAttitudeKinds, kind);
}

Config DefaultConfig() {
  Config c;
  ResolveDescriptorGrid(&c.descriptor);
  return c;
}

Result<Config> ParseConfig(std::string_view text, std::string_view source_name) {
  const std::string source(source_name);
  SKYLOC_TRY_ASSIGN(const toml::table root, drivers::ParseTomlText(text, source.c_str()));
  Config c;
  Status error;

  constexpr const char* kSections[] = {"camera",     "segmentation", "descriptor", "seqslam",
                                       "capacities", "state",        "status",     "realtime",
                                       "route_db",   "attitude",     "heading"};
  for (auto&& [k, node] : root) {
    if (!node.is_table()) {
      // A key above every [section] header (or a section written as a key).
      const std::string key(k.str());
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%u: key %s is not known at the top level: every key belongs in "
                           "a [section] (see config/skyloc.toml for where %s goes)",
                           source.c_str(), node.source().begin.line, key.c_str(), key.c_str());
    }
    bool known = false;
    for (const char* s : kSections)
      known = known || k.str() == s;
    const std::string name(k.str());
    if (!known) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%u: [%s] is not a known section (known: camera, segmentation, "
                           "descriptor, seqslam, capacities, state, status, realtime, route_db, "
                           "attitude, heading)",
                           source.c_str(), node.source().begin.line, name.c_str());
    }
    if (!node.is_table()) {
      return Status::Error(StatusCode::kInvalidArgument, "%s:%u: %s must be a table [%s]",
                           source.c_str(), node.source().begin.line, name.c_str(), name.c_str());
    }
  }
  auto section = [&](const char* name) { return root.get_as<toml::table>(name); };

  {
    SectionReader r(section("camera"), "camera", source_name, &error);
    r.Enum("kind", &c.camera.kind, kCameraKinds);
    r.String("device", &c.camera.device, false);
    r.String("dataset", &c.camera.dataset, true);
    r.String("lens_file", &c.camera.lens_file, true);
    r.OneOf("sim_world", &c.camera.sim_world, {"city", "forest", "repetitive", "street"});
    r.Int64("sim_seed", &c.camera.sim_seed, 0, INT64_MAX);
    r.OneOf("sim_sampling", &c.camera.sim_sampling, {"distance", "time"});
    r.Double("sim_speed_mps", &c.camera.sim_speed_mps, 0.01, 100.0);
    r.Double("sim_speed_band", &c.camera.sim_speed_band, 0.0, 0.99);
    r.Double("sim_accel_mps2", &c.camera.sim_accel_mps2, 0.01, 100.0);
    r.Double("sim_start_stop_s", &c.camera.sim_start_stop_s, 0.0, 3600.0);
    r.Int("sim_stops", &c.camera.sim_stops, 0, 1000);
    r.Double("sim_stop_min_s", &c.camera.sim_stop_min_s, 0.0, 3600.0);
    r.Double("sim_stop_max_s", &c.camera.sim_stop_max_s, 0.0, 3600.0);
    if (error.ok() && c.camera.sim_stop_min_s > c.camera.sim_stop_max_s)
      r.Invalid("sim_stop_min_s", "must not exceed sim_stop_max_s");
    r.Int("width", &c.camera.width, 16, 8192);
    r.Int("height", &c.camera.height, 16, 8192);
    r.Double("fps", &c.camera.fps, 0.1, 1000.0);
    r.Int("frame_timeout_ms", &c.camera.frame_timeout_ms, 1, 60000);
    r.Int("reconnect_timeout_ms", &c.camera.reconnect_timeout_ms, 0, 600000);
    if (error.ok() && c.camera.kind == CameraKind::kDataset && c.camera.dataset.empty())
      r.Invalid("dataset", "must name the dataset folder when kind = \"dataset\"");
    r.Finish();
  }
  {
    SectionReader r(section("segmentation"), "segmentation", source_name, &error);
    r.Enum("method", &c.segmentation.method, kSegmentationMethods);
    r.Int("threshold", &c.segmentation.threshold, 0, 254);
    r.Finish();
  }
  {
    SectionReader r(section("descriptor"), "descriptor", source_name, &error);
    r.Int("bands", &c.descriptor.bands, 1, 256);
    r.Enum("grid", &c.descriptor.grid, kGridPresets);
    r.Int("rings", &c.descriptor.rings, 0, 1024);
    r.Int("longitudes", &c.descriptor.longitudes, 0, 4096);
    r.Enum("normalisation", &c.descriptor.normalisation, kNormalisations);
    if (error.ok() && c.descriptor.grid == GridPreset::kCustom) {
      if (c.descriptor.rings < 1)
        r.Invalid("rings", "must be 1..1024 when grid = \"custom\"");
      else if (c.descriptor.longitudes < 4)
        r.Invalid("longitudes", "must be 4..4096 when grid = \"custom\"");
    } else if (error.ok() && (c.descriptor.rings != 0 || c.descriptor.longitudes != 0)) {
      r.Invalid(c.descriptor.rings != 0 ? "rings" : "longitudes",
                "is only used with grid = \"custom\"; remove it or set grid = \"custom\"");
    }
    const toml::table* t = section("descriptor");
    if (error.ok() && c.descriptor.grid == GridPreset::kPaper && t != nullptr &&
        t->contains("bands") && c.descriptor.bands != 120)
      r.Invalid("bands", "must be 120 (or left out) with grid = \"paper\"");
    ResolveDescriptorGrid(&c.descriptor);
    r.Finish();
  }
  {
    SectionReader r(section("seqslam"), "seqslam", source_name, &error);
    r.Enum("matcher", &c.seqslam.matcher, kMatchers);
    dsp::RouteFilterParams& filter = c.seqslam.filter;
    dsp::SeqSlamParams& open = c.seqslam.openseqslam;
    int ds = c.seqslam.ds(), rwindow = c.seqslam.rwindow();
    r.Int("ds", &ds, 1, 100);
    c.seqslam.set_ds(ds);
    r.Int("max_advance", &filter.max_advance, 1, 64);
    r.Float("keyframe_noise_factor", &filter.keyframe_noise_factor, 0.0, 100.0);
    r.Float("vmin", &open.v_min, 0.1, 10.0);
    r.Float("vmax", &open.v_max, 0.1, 10.0);
    r.Float("vstep", &open.v_step, 0.01, 10.0);
    r.Int("rwindow", &rwindow, 0, 1000);
    filter.uniqueness_window = rwindow;
    open.uniqueness_window = rwindow;
    r.Int("contrast_r", &open.contrast_window, 0, 1000);
    if (error.ok() && open.v_max < open.v_min)
      r.Invalid("vmax", "must not be smaller than vmin");
    r.Finish();
  }
  {
    SectionReader r(section("capacities"), "capacities", source_name, &error);
    r.Int("route_frames", &c.capacities.route_frames, 1, 1000000);
    r.Enum("route_storage", &c.capacities.route_storage, kRouteStorages);
    r.Finish();
  }
  {
    SectionReader r(section("state"), "state", source_name, &error);
    r.Float("enter_confidence", &c.state.enter_confidence, 0.0, 1.0);
    r.Float("stay_confidence", &c.state.stay_confidence, 0.0, 1.0);
    r.Float("max_uniqueness", &c.state.max_uniqueness, 0.0, 1.0);
    r.Int("confirm_frames", &c.state.confirm_frames, 1, 1000);
    r.Int("drop_frames", &c.state.drop_frames, 1, 1000);
    r.Int("lost_frames", &c.state.lost_frames, 1, 10000);
    r.Double("index_tolerance", &c.state.index_tolerance, 0.0, 10000.0);
    if (error.ok() && c.state.stay_confidence > c.state.enter_confidence)
      r.Invalid("stay_confidence", "must not be above enter_confidence (hysteresis)");
    r.Finish();
  }
  {
    SectionReader r(section("status"), "status", source_name, &error);
    r.Enum("kind", &c.status.kind, kStatusOutputKinds);
    r.String("chip", &c.status.chip, false);
    r.Int("line_lost", &c.status.line_lost, 0, 511);
    r.Int("line_searching", &c.status.line_searching, 0, 511);
    r.Int("line_localised", &c.status.line_localised, 0, 511);
    r.Enum("encoding", &c.status.encoding, kStatusEncodings);
    r.Bool("active_low", &c.status.active_low);
    r.Int("button_line", &c.status.button_line, -1, 511);
    r.Bool("button_active_low", &c.status.button_active_low);
    r.Int("button_debounce_ms", &c.status.button_debounce_ms, 0, 1000);
    if (error.ok() && c.status.encoding == StatusEncoding::kPerState) {
      if (c.status.line_localised == c.status.line_lost ||
          c.status.line_localised == c.status.line_searching)
        r.Invalid("line_localised", "must differ from line_lost and line_searching");
      else if (c.status.line_searching == c.status.line_lost)
        r.Invalid("line_searching", "must differ from line_lost");
    }
    // The button is an input: it cannot share a pin with a lit indicator.
    const StatusConfig& st = c.status;
    const bool per_state = st.encoding == StatusEncoding::kPerState;
    if (error.ok() && st.button_line >= 0 &&
        (st.button_line == st.line_localised ||
         (per_state && (st.button_line == st.line_lost || st.button_line == st.line_searching))))
      r.Invalid("button_line",
                per_state ? "must differ from line_lost, line_searching and line_localised "
                            "(-1: no button)"
                          : "must differ from line_localised, the blinking line (-1: no button)");
    if (error.ok() && st.button_line >= 0 && st.kind == StatusOutputKind::kNone)
      r.Invalid("button_line", "needs kind = \"gpio\" (the button is read on its chip), or -1");
    r.Finish();
  }
  {
    SectionReader r(section("realtime"), "realtime", source_name, &error);
    r.Int("sched_fifo_priority", &c.realtime.sched_fifo_priority, 0, 99);
    r.Bool("mlockall", &c.realtime.mlockall);
    r.Int("cpu_affinity", &c.realtime.cpu_affinity, -1, 1023);
    r.Finish();
  }
  {
    SectionReader r(section("route_db"), "route_db", source_name, &error);
    r.Int("flush_every", &c.route_db.flush_every, 1, 100000);
    r.Finish();
  }
  {
    SectionReader r(section("attitude"), "attitude", source_name, &error);
    AttitudeConfig& a = c.attitude;
    r.Enum("kind", &a.kind, kAttitudeKinds);
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
    if (error.ok() && a.kind == AttitudeKind::kIio && a.device.empty())
      r.Invalid("device",
                "must name the IMU when kind = \"iio\" (/dev/iio:deviceN or its IIO "
                "name, e.g. \"bmi160\")");
    if (error.ok() && a.kind == AttitudeKind::kDataset && c.camera.kind != CameraKind::kDataset)
      r.Invalid("kind",
                "\"dataset\" reads the replayed dataset's roll_deg,pitch_deg columns: "
                "it needs [camera] kind = \"dataset\"");
    if (error.ok() && a.kind == AttitudeKind::kSim && c.camera.kind != CameraKind::kSim)
      r.Invalid("kind",
                "\"sim\" simulates the IMU of the simulated camera's run: it needs "
                "[camera] kind = \"sim\"");
    r.Finish();
  }
  {
    SectionReader r(section("heading"), "heading", source_name, &error);
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
    if (error.ok() && h.n_azimuth != 0 && h.n_azimuth < 148)
      r.Invalid("strip_columns",
                "must be 0 (no heading) or at least 148: 1D SURF's widest filter spans 147 "
                "columns");
    if (error.ok() && h.elevation_min_deg > h.elevation_max_deg)
      r.Invalid("elevation_min_deg", "must not be above elevation_max_deg");
    r.Finish();
  }
  if (!error.ok())
    return error;
  return c;
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
  // A relative lens_file is the config file's neighbour, whatever the working directory
  // (systemd starts skyloc in /).
  std::string& lens = c->camera.lens_file;
  if (!lens.empty() && lens[0] != '/') {
    const std::string dir(path);
    const std::size_t slash = dir.rfind('/');
    if (slash != std::string::npos)
      lens = dir.substr(0, slash + 1) + lens;
  }
  return c;
}

}  // namespace skyloc::firmware
