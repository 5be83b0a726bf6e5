#include "skyloc/drivers/dataset.h"

#include <dirent.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>
#include <system_error>
#include <utility>

#include "skyloc/drivers/image_file.h"
#include "skyloc/platform/regular_file.h"

namespace skyloc::drivers {
namespace {

constexpr int kPoseColumns = 6;

bool FileExists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// A dataset's optional files (frames.csv, camera.toml): present as a regular file (a
// symlink to one is fine), absent, or refused: anything else there is a mistake to name,
// not a missing file to silently do without.
Status CheckOptionalFile(const std::string& path, bool* present) {
  *present = false;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int saved = errno;
    if (saved == ENOENT)
      return Status::Ok();
    return Status::FromErrno(saved, "cannot check %s", path.c_str());
  }
  if (!S_ISREG(st.st_mode))
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s is %s, not a regular file: a dataset's frames.csv and camera.toml "
                         "are regular files (docs/DATASETS.md)",
                         path.c_str(), FileKindName(st.st_mode));
  *present = true;
  return Status::Ok();
}

bool DirExists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool HasImageExtension(std::string_view name) {
  auto ends = [&](std::string_view ext) {
    if (name.size() <= ext.size())
      return false;
    std::string_view tail = name.substr(name.size() - ext.size());
    return std::equal(tail.begin(), tail.end(), ext.begin(), ext.end(), [](char a, char b) {
      return (a >= 'A' && a <= 'Z' ? static_cast<char>(a - 'A' + 'a') : a) == b;
    });
  };
  return ends(".png") || ends(".pgm");
}

// Splits one CSV line at commas (the format has no quoting: file names may not contain
// commas, which ReadDataset reports).
std::vector<std::string_view> SplitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(line.substr(start));
      break;
    }
    fields.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
  return fields;
}

bool ParseDouble(std::string_view s, double* out) {
  if (s.empty())
    return false;
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, *out);
  return ec == std::errc() && ptr == end && std::isfinite(*out);
}

bool ParseInt(std::string_view s, int* out) {
  if (s.empty())
    return false;
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, *out);
  return ec == std::errc() && ptr == end;
}

Status ListFrames(const std::string& frames_dir, std::vector<std::string>* names) {
  DIR* d = ::opendir(frames_dir.c_str());
  if (d == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot list %s", frames_dir.c_str());
  }
  for (;;) {
    errno = 0;  // readdir returns null both at the end and on an error: errno tells which
    const dirent* e = ::readdir(d);
    if (e == nullptr) {
      const int saved = errno;
      ::closedir(d);
      if (saved != 0)
        return Status::FromErrno(saved, "cannot list %s", frames_dir.c_str());
      break;
    }
    const std::string_view name(e->d_name);
    if (name.empty() || name[0] == '.' || !HasImageExtension(name))
      continue;
    names->emplace_back(name);
  }
  std::sort(names->begin(), names->end());
  return Status::Ok();
}

Status ReadCsv(const std::string& csv_path, const std::string& frames_dir, Dataset* ds) {
  std::FILE* f = std::fopen(csv_path.c_str(), "rb");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot open %s", csv_path.c_str());
  }
  std::string text;
  char buffer[65536];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0)
    text.append(buffer, n);
  const bool read_error = std::ferror(f) != 0;
  const int saved = errno;
  std::fclose(f);
  if (read_error)
    return Status::FromErrno(saved, "cannot read %s", csv_path.c_str());

  SKYLOC_TRY(ParseDatasetCsv(text, csv_path, ds));
  // Every line after the header is a frame (an empty line is an error), so frame i is on
  // line i + 2.
  for (std::size_t i = 0; i < ds->frames.size(); ++i) {
    const std::string image_path = frames_dir + "/" + ds->frames[i].file;
    if (!FileExists(image_path)) {
      return Status::Error(StatusCode::kNotFound, "%s:%zu: image %s does not exist",
                           csv_path.c_str(), i + 2, image_path.c_str());
    }
  }
  return Status::Ok();
}

}  // namespace

Status ParseDatasetCsv(std::string_view text, const std::string& csv_path, Dataset* ds) {
  const std::string pose_header = std::string(kDatasetCsvHeader) + "," + kDatasetCsvPoseColumns;
  const std::string attitude_header =
      std::string(kDatasetCsvHeader) + "," + kDatasetCsvAttitudeColumns;
  std::size_t pos = 0;
  int line_no = 0;
  std::size_t expected_fields = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    const bool last = eol == std::string::npos;
    if (last)
      eol = text.size();
    std::string_view line(text.data() + pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r')
      line.remove_suffix(1);
    if (line_no == 1) {
      if (line == kDatasetCsvHeader) {
        expected_fields = 3;
      } else if (line == pose_header) {
        expected_fields = 3 + kPoseColumns;
        ds->has_poses = true;
        ds->has_attitude = true;
      } else if (line == attitude_header) {
        expected_fields = 5;
        ds->has_attitude = true;
      } else {
        return Status::Error(
            StatusCode::kInvalidArgument, "%s:1: header must be '%s', '%s' or '%s', got '%.*s'",
            csv_path.c_str(), kDatasetCsvHeader, pose_header.c_str(), attitude_header.c_str(),
            static_cast<int>(std::min<std::size_t>(line.size(), 60)), line.data());
      }
      continue;
    }
    if (line.empty()) {
      if (last || pos >= text.size())
        break;  // a trailing newline
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%d: empty line in the middle of the file", csv_path.c_str(),
                           line_no);
    }
    const std::vector<std::string_view> fields = SplitFields(line);
    if (fields.size() != expected_fields) {
      return Status::Error(StatusCode::kInvalidArgument, "%s:%d: expected %zu fields, got %zu",
                           csv_path.c_str(), line_no, expected_fields, fields.size());
    }
    DatasetFrame frame;
    if (!ParseInt(fields[0], &frame.index)) {
      return Status::Error(StatusCode::kInvalidArgument, "%s:%d: index '%.*s' is not an integer",
                           csv_path.c_str(), line_no, static_cast<int>(fields[0].size()),
                           fields[0].data());
    }
    const int expected_index = static_cast<int>(ds->frames.size());
    if (frame.index != expected_index) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%d: index %d out of order (expected %d: indices count 0, 1, 2, ...)",
                           csv_path.c_str(), line_no, frame.index, expected_index);
    }
    frame.file = std::string(fields[1]);
    if (frame.file.empty() || frame.file.find('/') != std::string::npos ||
        !HasImageExtension(frame.file)) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%d: file '%s' must be a .png or .pgm name inside frames/",
                           csv_path.c_str(), line_no, frame.file.c_str());
    }
    if (!ParseDouble(fields[2], &frame.timestamp_s)) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "%s:%d: timestamp_s '%.*s' is not a number", csv_path.c_str(), line_no,
                           static_cast<int>(fields[2].size()), fields[2].data());
    }
    if (!ds->frames.empty() && frame.timestamp_s < ds->frames.back().timestamp_s) {
      return Status::Error(
          StatusCode::kInvalidArgument, "%s:%d: timestamp_s %.6f goes backwards (previous %.6f)",
          csv_path.c_str(), line_no, frame.timestamp_s, ds->frames.back().timestamp_s);
    }
    if (ds->has_poses) {
      static constexpr const char* kNames[kPoseColumns] = {"x_m",      "y_m",       "z_m",
                                                           "roll_deg", "pitch_deg", "yaw_deg"};
      double v[kPoseColumns];
      for (int i = 0; i < kPoseColumns; ++i) {
        const std::string_view field = fields[static_cast<std::size_t>(3 + i)];
        if (!ParseDouble(field, &v[i])) {
          return Status::Error(StatusCode::kInvalidArgument, "%s:%d: %s '%.*s' is not a number",
                               csv_path.c_str(), line_no, kNames[i], static_cast<int>(field.size()),
                               field.data());
        }
      }
      frame.pose = Pose{v[0], v[1], v[2], v[3], v[4], v[5]};
    } else if (ds->has_attitude) {
      static constexpr const char* kNames[2] = {"roll_deg", "pitch_deg"};
      double v[2];
      for (int i = 0; i < 2; ++i) {
        const std::string_view field = fields[static_cast<std::size_t>(3 + i)];
        if (!ParseDouble(field, &v[i])) {
          return Status::Error(StatusCode::kInvalidArgument, "%s:%d: %s '%.*s' is not a number",
                               csv_path.c_str(), line_no, kNames[i], static_cast<int>(field.size()),
                               field.data());
        }
      }
      frame.pose.reset();
      frame.attitude = dsp::AttitudeFromRollPitch(0, v[0], v[1]);
    }
    if (frame.pose)
      frame.attitude = dsp::AttitudeFromRollPitch(0, frame.pose->roll_deg, frame.pose->pitch_deg);
    if (frame.attitude)
      frame.attitude->timestamp_ns = static_cast<std::int64_t>(frame.timestamp_s * 1e9 + 0.5);
    ds->frames.push_back(std::move(frame));
  }
  if (line_no == 0) {
    return Status::Error(StatusCode::kInvalidArgument, "%s: empty file (expected header '%s')",
                         csv_path.c_str(), kDatasetCsvHeader);
  }
  ds->has_timestamps = true;
  return Status::Ok();
}

namespace {

Status MakeDirs(const std::string& path) {
  std::string partial;
  std::size_t pos = 0;
  while (pos <= path.size()) {
    std::size_t slash = path.find('/', pos);
    if (slash == std::string::npos)
      slash = path.size();
    partial = path.substr(0, slash);
    pos = slash + 1;
    if (partial.empty())
      continue;
    if (::mkdir(partial.c_str(), 0777) != 0) {
      const int saved = errno;
      if (saved != EEXIST)
        return Status::FromErrno(saved, "cannot create folder %s", partial.c_str());
      if (!DirExists(partial))
        return Status::Error(StatusCode::kInvalidArgument, "%s exists and is not a folder",
                             partial.c_str());
    }
  }
  return Status::Ok();
}

}  // namespace

std::string Dataset::FramePath(std::size_t i) const {
  return dir + "/frames/" + frames[i].file;
}

Result<Dataset> ReadDataset(const std::string& dir) {
  Dataset ds;
  ds.dir = dir;
  while (ds.dir.size() > 1 && ds.dir.back() == '/')
    ds.dir.pop_back();
  if (!DirExists(ds.dir)) {
    struct stat st {};
    if (::stat(ds.dir.c_str(), &st) == 0)
      return Status::Error(StatusCode::kInvalidArgument,
                           "dataset %s is not a folder (a dataset is a folder holding frames/ "
                           "and frames.csv, docs/DATASETS.md)",
                           ds.dir.c_str());
    return Status::Error(StatusCode::kNotFound, "dataset folder %s does not exist", ds.dir.c_str());
  }
  const std::string frames_dir = ds.dir + "/frames";
  if (!DirExists(frames_dir)) {
    return Status::Error(StatusCode::kNotFound,
                         "%s: no frames/ folder (a dataset is DIR/frames/*.png|*.pgm plus "
                         "DIR/frames.csv, see docs/DATASETS.md)",
                         ds.dir.c_str());
  }
  const std::string csv_path = ds.dir + "/frames.csv";
  bool has_csv = false;
  SKYLOC_TRY(CheckOptionalFile(csv_path, &has_csv));
  if (has_csv) {
    SKYLOC_TRY(ReadCsv(csv_path, frames_dir, &ds));
    if (ds.frames.empty()) {
      return Status::Error(StatusCode::kInvalidArgument, "%s: no frames after the header",
                           csv_path.c_str());
    }
  } else {
    std::vector<std::string> names;
    SKYLOC_TRY(ListFrames(frames_dir, &names));
    if (names.empty()) {
      return Status::Error(StatusCode::kNotFound, "%s: no .png or .pgm images and no %s",
                           frames_dir.c_str(), csv_path.c_str());
    }
    for (std::size_t i = 0; i < names.size(); ++i) {
      DatasetFrame frame;
      frame.index = static_cast<int>(i);
      frame.file = names[i];
      frame.timestamp_s = static_cast<double>(i) / 10.0;
      ds.frames.push_back(std::move(frame));
    }
  }
  const std::string camera = ds.dir + "/camera.toml";
  bool has_camera = false;
  SKYLOC_TRY(CheckOptionalFile(camera, &has_camera));
  if (has_camera)
    ds.camera_toml = camera;
  return ds;
}

DatasetWriter::~DatasetWriter() {
  (void)Close();
}

DatasetWriter::DatasetWriter(DatasetWriter&& other) noexcept
    : dir_(std::move(other.dir_)),
      csv_(std::exchange(other.csv_, nullptr)),
      columns_(other.columns_),
      next_index_(other.next_index_) {}

DatasetWriter& DatasetWriter::operator=(DatasetWriter&& other) noexcept {
  if (this != &other) {
    (void)Close();
    dir_ = std::move(other.dir_);
    csv_ = std::exchange(other.csv_, nullptr);
    columns_ = other.columns_;
    next_index_ = other.next_index_;
  }
  return *this;
}

namespace {

Status RecordingExists(const std::string& csv_path) {
  return Status::Error(StatusCode::kAlreadyExists,
                       "%s already exists: choose a new folder (a recording is never "
                       "overwritten)",
                       csv_path.c_str());
}

}  // namespace

Status CheckNewDatasetFolder(const std::string& dir) {
  std::string d = dir;
  while (d.size() > 1 && d.back() == '/')
    d.pop_back();
  struct stat st {};
  if (::stat(d.c_str(), &st) != 0)
    return Status::Ok();  // made by Open
  if (!S_ISDIR(st.st_mode))
    return Status::Error(StatusCode::kInvalidArgument, "%s exists and is not a folder", d.c_str());
  const std::string csv_path = d + "/frames.csv";
  if (::lstat(csv_path.c_str(), &st) == 0)
    return RecordingExists(csv_path);
  return Status::Ok();
}

Status DatasetWriter::Open(const std::string& dir, Columns columns) {
  if (csv_ != nullptr) {
    return Status::Error(StatusCode::kFailedPrecondition, "dataset writer: %s is already open",
                         dir_.c_str());
  }
  dir_ = dir;
  while (dir_.size() > 1 && dir_.back() == '/')
    dir_.pop_back();
  SKYLOC_TRY(MakeDirs(dir_ + "/frames"));
  const std::string csv_path = dir_ + "/frames.csv";
  // "x": fail if the file exists, so an earlier recording is never overwritten.
  csv_ = std::fopen(csv_path.c_str(), "wx");
  if (csv_ == nullptr) {
    const int saved = errno;
    if (saved == EEXIST)
      return RecordingExists(csv_path);
    return Status::FromErrno(saved, "cannot create %s", csv_path.c_str());
  }
  columns_ = columns;
  next_index_ = 0;
  int written;
  switch (columns) {
    case Columns::kPose:
      written = std::fprintf(csv_, "%s,%s\n", kDatasetCsvHeader, kDatasetCsvPoseColumns);
      break;
    case Columns::kAttitude:
      written = std::fprintf(csv_, "%s,%s\n", kDatasetCsvHeader, kDatasetCsvAttitudeColumns);
      break;
    case Columns::kNone:
    default:
      written = std::fprintf(csv_, "%s\n", kDatasetCsvHeader);
      break;
  }
  if (written < 0 || std::fflush(csv_) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot write %s", csv_path.c_str());
  }
  return Status::Ok();
}

Status DatasetWriter::Append(const dsp::ImageView& image, double timestamp_s,
                             const std::optional<Pose>& pose) {
  if (csv_ == nullptr)
    return Status::Error(StatusCode::kFailedPrecondition, "dataset writer: Append() before Open()");
  if (image.empty()) {
    return Status::Error(StatusCode::kInvalidArgument, "dataset %s: frame %d is an empty image",
                         dir_.c_str(), next_index_);
  }
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", next_index_);
  const std::string path = dir_ + "/frames/" + name;
  // SavePng writes a temporary file and renames it: the row below is only appended once
  // the complete image is in place.
  SKYLOC_TRY(SavePng(path.c_str(), image));
  return AppendRow(name, timestamp_s, pose);
}

Status DatasetWriter::AppendRow(const std::string& file, double timestamp_s,
                                const std::optional<Pose>& pose) {
  if (csv_ == nullptr) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "dataset writer: AppendRow() before Open()");
  }
  if (file.empty() || file.find(',') != std::string::npos || file.find('/') != std::string::npos ||
      !HasImageExtension(file)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "dataset %s: frame file '%s' must be a .png/.pgm name without ',' or '/'",
                         dir_.c_str(), file.c_str());
  }
  if (!std::isfinite(timestamp_s)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "dataset %s: frame %d timestamp is not finite", dir_.c_str(), next_index_);
  }
  const bool with_poses = columns_ == Columns::kPose;
  if (columns_ == Columns::kAttitude || with_poses != pose.has_value()) {
    return Status::Error(
        StatusCode::kInvalidArgument,
        "dataset %s: frame %d %s a pose but the dataset was opened %s", dir_.c_str(), next_index_,
        pose ? "has" : "lacks",
        with_poses ? "with poses"
                   : (columns_ == Columns::kAttitude ? "with attitudes" : "without poses"));
  }
  // %.17g round-trips a double exactly; timestamps get microsecond text.
  int written;
  if (pose) {
    written = std::fprintf(csv_, "%d,%s,%.6f,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", next_index_,
                           file.c_str(), timestamp_s, pose->x_m, pose->y_m, pose->z_m,
                           pose->roll_deg, pose->pitch_deg, pose->yaw_deg);
  } else {
    written = std::fprintf(csv_, "%d,%s,%.6f\n", next_index_, file.c_str(), timestamp_s);
  }
  if (written < 0 || std::fflush(csv_) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot append to %s/frames.csv", dir_.c_str());
  }
  ++next_index_;
  return Status::Ok();
}

Status DatasetWriter::AppendRow(const std::string& file, double timestamp_s,
                                const dsp::Attitude& attitude) {
  if (csv_ == nullptr || columns_ != Columns::kAttitude) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "dataset writer: an attitude row needs Open() with Columns::kAttitude");
  }
  if (file.empty() || file.find(',') != std::string::npos || file.find('/') != std::string::npos ||
      !HasImageExtension(file) || !std::isfinite(timestamp_s)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "dataset %s: frame %d: a .png/.pgm name without ',' or '/' and a finite "
                         "timestamp are needed",
                         dir_.c_str(), next_index_);
  }
  const int written = std::fprintf(csv_, "%d,%s,%.6f,%.17g,%.17g\n", next_index_, file.c_str(),
                                   timestamp_s, attitude.roll_deg, attitude.pitch_deg);
  if (written < 0 || std::fflush(csv_) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot append to %s/frames.csv", dir_.c_str());
  }
  ++next_index_;
  return Status::Ok();
}

Status DatasetWriter::Close() {
  if (csv_ == nullptr)
    return Status::Ok();
  std::FILE* f = std::exchange(csv_, nullptr);
  if (std::fclose(f) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot close %s/frames.csv", dir_.c_str());
  }
  return Status::Ok();
}

// ---- DatasetCamera ---------------------------------------------------------------------

Status DatasetCamera::DoOpen() {
  std::snprintf(info_.name, sizeof info_.name, "dataset:%s", dir_.c_str());
  SKYLOC_TRY_ASSIGN(dataset_, ReadDataset(dir_));
  SKYLOC_TRY_ASSIGN(current_, LoadImage(dataset_.FramePath(0).c_str()));
  info_.width = current_.width();
  info_.height = current_.height();
  info_.format = current_.format();
  next_ = 0;
  return Status::Ok();
}

Status DatasetCamera::DoStart() {
  return Status::Ok();  // a stopped replay goes on where it stopped, as a camera's stream does
}

Result<Frame> DatasetCamera::DoCapture(Nanoseconds /*timeout*/) {
  if (next_ >= dataset_.frames.size()) {
    return Status::Error(StatusCode::kOutOfRange, "camera %s: end of the %zu frames", info_.name,
                         dataset_.frames.size());
  }
  const std::size_t i = next_++;
  const DatasetFrame& f = dataset_.frames[i];
  Result<OwnedImage> loaded = LoadImage(dataset_.FramePath(i).c_str());
  if (!loaded.ok())
    return Status(loaded.status()).AddContext("camera %s", info_.name);
  current_ = std::move(*loaded);
  if (current_.width() != info_.width || current_.height() != info_.height ||
      current_.format() != info_.format) {
    return Status::Error(StatusCode::kDataLoss,
                         "camera %s: frame %zu (%s) is %dx%d %s, expected %dx%d %s like the "
                         "first frame: re-record it or remove it from frames.csv",
                         info_.name, i, f.file.c_str(), current_.width(), current_.height(),
                         dsp::PixelFormatName(current_.format()), info_.width, info_.height,
                         dsp::PixelFormatName(info_.format));
  }
  Frame frame;
  frame.image = current_.view();
  frame.sequence = static_cast<std::uint64_t>(i);
  frame.timestamp = Nanoseconds(static_cast<std::int64_t>(std::llround(f.timestamp_s * 1e9)));
  frame.pose = f.pose;
  frame.attitude = f.attitude;
  return frame;
}

void DatasetCamera::DoStop() {}

void DatasetCamera::DoClose() {
  dataset_ = Dataset{};
  current_ = OwnedImage{};
}

}  // namespace skyloc::drivers
