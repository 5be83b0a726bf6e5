// The dataset folder: how recorded or simulated runs are stored, read by `skyloc eval` and
// `skyloc replay`, written by the simulator and the recorder. Format: docs/DATASETS.md.
//
//   DIR/frames/000000.pgm ...   the images (PGM or PNG), in frame order
//   DIR/frames.csv              index,file,timestamp_s[,x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg]
//   DIR/camera.toml             optional: the lens/camera description (`skyloc describe`)
//
// Reading is strict: any malformed line, missing image or out-of-order index is ONE error
// naming the file and line. Writing appends one row per frame and flushes it, so a
// recorder or simulator that is killed leaves a valid prefix of the run on disk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/image.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

struct DatasetFrame {
  int index = 0;             // 0, 1, 2, ... in file order
  std::string file;          // name inside DIR/frames/, e.g. "000042.pgm"
  double timestamp_s = 0;    // seconds since the start of the run (0, 0.1, ... if unknown)
  std::optional<Pose> pose;  // present for every frame or for none
  // Roll and pitch: from the pose columns, or the attitude-only columns (a recording with
  // an IMU and no position); present for every frame or for none.
  std::optional<dsp::Attitude> attitude;
};

struct Dataset {
  std::string dir;
  std::vector<DatasetFrame> frames;
  bool has_poses = false;
  bool has_attitude = false;  // every frame has roll and pitch (pose or attitude columns)
  // False when DIR/frames.csv is absent and the frames were listed from DIR/frames/
  // (sorted by name); timestamp_s is then index / 10 (an assumed 10 Hz).
  bool has_timestamps = false;
  std::string camera_toml;  // "DIR/camera.toml" when that file exists, empty otherwise

  std::string FramePath(std::size_t i) const;  // DIR/frames/<file>
};

// The header line of frames.csv, without and with poses.
inline constexpr const char* kDatasetCsvHeader = "index,file,timestamp_s";
inline constexpr const char* kDatasetCsvPoseColumns = "x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg";
// Attitude only (an IMU's roll and pitch, no position): the third header.
inline constexpr const char* kDatasetCsvAttitudeColumns = "roll_deg,pitch_deg";

// Reads DIR/frames.csv (or lists DIR/frames/ when there is no frames.csv) and checks that
// every image file exists. kNotFound for a missing folder or image, kInvalidArgument for a
// malformed frames.csv ("DIR/frames.csv:12: ..."). An empty dataset is an error.
Result<Dataset> ReadDataset(const std::string& dir);

// Parses the text of a frames.csv into ds->frames (and has_poses, has_attitude,
// has_timestamps), without touching the disk: ReadDataset then checks that each image
// exists. Errors are kInvalidArgument, "<csv_path>:12: ...". Also what the fuzzer drives.
Status ParseDatasetCsv(std::string_view text, const std::string& csv_path, Dataset* ds);

// What DatasetWriter::Open would refuse in DIR, found without creating anything: so a
// command that also writes other files (teach --record: the route) refuses before it
// makes any of them.
Status CheckNewDatasetFolder(const std::string& dir);

// Writes a dataset folder frame by frame.
class DatasetWriter {
 public:
  DatasetWriter() = default;
  ~DatasetWriter();
  DatasetWriter(DatasetWriter&& other) noexcept;
  DatasetWriter& operator=(DatasetWriter&& other) noexcept;
  DatasetWriter(const DatasetWriter&) = delete;
  DatasetWriter& operator=(const DatasetWriter&) = delete;

  // What each row carries besides index, file and timestamp.
  enum class Columns : std::uint8_t {
    kNone,
    kPose,      // x,y,z,roll,pitch,yaw: every Append must carry a pose (the simulator)
    kAttitude,  // roll,pitch: every AppendRow an attitude (a live camera with an IMU)
  };

  // Creates DIR (and parents), DIR/frames/ and DIR/frames.csv with its header. Refuses
  // (kFailedPrecondition) when DIR/frames.csv already exists: a recording is never
  // overwritten. With `with_poses` every Append must carry a pose.
  Status Open(const std::string& dir, bool with_poses) {
    return Open(dir, with_poses ? Columns::kPose : Columns::kNone);
  }
  Status Open(const std::string& dir, Columns columns);

  // Writes the image as frames/NNNNNN.png (SavePng: grey stays grey, RGB/BGR as RGB,
  // YUYV as its Y plane) and then appends its row, flushed.
  Status Append(const dsp::ImageView& image, double timestamp_s, const std::optional<Pose>& pose);

  // Appends a row for an image the caller already wrote into DIR/frames/ (its name).
  Status AppendRow(const std::string& file, double timestamp_s, const std::optional<Pose>& pose);
  // The same for Columns::kAttitude (roll and pitch from the attitude's zenith).
  Status AppendRow(const std::string& file, double timestamp_s, const dsp::Attitude& attitude);

  // Flushes and closes frames.csv. Also done by the destructor (errors then are lost).
  Status Close();

  bool is_open() const { return csv_ != nullptr; }
  int frames_written() const { return next_index_; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::FILE* csv_ = nullptr;
  Columns columns_ = Columns::kNone;
  int next_index_ = 0;
};

// Plays a dataset folder as a camera: Capture() returns the frames in order, each with
// its pose when the dataset has poses, and kOutOfRange after the last one. Timestamps are
// the dataset's timestamp_s (as nanoseconds since the start of the run). Frames come as
// LoadImage gives them (kGrey8 or kRgb24); every frame must have the first one's size and
// format (kDataLoss otherwise, for that frame). Sequence numbers are frame indices: they go
// on across Stop()/Start() and start again at 0 after Open().
//
// Replay is a laptop tool, and the one camera camera.h lets allocate in Capture(): each
// Capture() decodes the next file (a PNG decoder allocates). Why not a decoder thread (yet):
// docs/DRIVERS.md, "The camera contract".
class DatasetCamera final : public Camera {
 public:
  explicit DatasetCamera(std::string dir) : dir_(std::move(dir)) {}

  const Dataset& dataset() const { return dataset_; }

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<Frame> DoCapture(Nanoseconds timeout) override;
  void DoStop() override;
  void DoClose() override;

  std::string dir_;
  Dataset dataset_;
  std::size_t next_ = 0;
  OwnedImage current_;  // the frame Capture() returned last
};

}  // namespace skyloc::drivers
