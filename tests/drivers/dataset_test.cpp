#include "skyloc/drivers/dataset.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "support/scratch_dir.h"

namespace skyloc::drivers {
namespace {

using skyloc::testing::ScratchDir;

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// A grey test image whose pixels encode the frame number.
std::vector<std::uint8_t> Pixels(int frame) {
  std::vector<std::uint8_t> px(8 * 6);
  for (std::size_t i = 0; i < px.size(); ++i)
    px[i] = static_cast<std::uint8_t>(frame * 10 + static_cast<int>(i));
  return px;
}

TEST(Dataset, WriteThenReadWithPoses) {
  const ScratchDir scratch("skyloc_dataset_");
  const std::string dir = scratch.path() + "/run1";
  DatasetWriter writer;
  ASSERT_TRUE(writer.Open(dir, /*with_poses=*/true).ok());
  for (int i = 0; i < 3; ++i) {
    const std::vector<std::uint8_t> px = Pixels(i);
    const Pose pose{1.5 * i, -2.0, 0.25, 1.0, -3.0, 0.1 * i};
    const Status s =
        writer.Append(dsp::ImageView{px.data(), 8, 6, 8, dsp::PixelFormat::kGrey8}, 0.1 * i, pose);
    ASSERT_TRUE(s.ok()) << s.message();
  }
  EXPECT_EQ(writer.frames_written(), 3);
  ASSERT_TRUE(writer.Close().ok());

  Result<Dataset> ds = ReadDataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ASSERT_EQ(ds->frames.size(), 3u);
  EXPECT_TRUE(ds->has_poses);
  EXPECT_TRUE(ds->has_timestamps);
  EXPECT_TRUE(ds->camera_toml.empty());
  EXPECT_EQ(ds->frames[2].file, "000002.png");
  EXPECT_DOUBLE_EQ(ds->frames[2].timestamp_s, 0.2);
  ASSERT_TRUE(ds->frames[2].pose.has_value());
  EXPECT_DOUBLE_EQ(ds->frames[2].pose->x_m, 3.0);  // %.17g round-trips exactly
  EXPECT_DOUBLE_EQ(ds->frames[2].pose->yaw_deg, 0.1 * 2);
  EXPECT_EQ(ds->FramePath(1), dir + "/frames/000001.png");

  // The camera plays the frames in order with their poses, then reports the end.
  DatasetCamera camera(dir);
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  for (int i = 0; i < 3; ++i) {
    Result<Frame> f = camera.Capture(Nanoseconds(0));
    ASSERT_TRUE(f.ok()) << f.status().message();
    EXPECT_EQ(f->sequence, static_cast<std::uint64_t>(i));
    EXPECT_EQ(f->timestamp, Nanoseconds(100'000'000LL * i));
    ASSERT_EQ(f->image.width, 8);
    EXPECT_EQ(f->image.Row(0)[0], static_cast<std::uint8_t>(i * 10));
    ASSERT_TRUE(f->pose.has_value());
    EXPECT_DOUBLE_EQ(f->pose->x_m, 1.5 * i);
  }
  Result<Frame> end = camera.Capture(Nanoseconds(0));
  ASSERT_FALSE(end.ok());
  EXPECT_EQ(end.status().code(), StatusCode::kOutOfRange);
  camera.Close();
}

TEST(Dataset, KilledWriterLeavesAValidPrefixAndIsNeverOverwritten) {
  const ScratchDir scratch("skyloc_dataset_");
  const std::string& dir = scratch.path();
  {
    DatasetWriter writer;
    ASSERT_TRUE(writer.Open(dir, false).ok());
    const std::vector<std::uint8_t> px = Pixels(0);
    for (int i = 0; i < 2; ++i) {
      ASSERT_TRUE(
          writer.Append(dsp::ImageView{px.data(), 8, 6, 8, dsp::PixelFormat::kGrey8}, i, {}).ok());
    }
    // Read while the writer is still open (as after a kill): both rows are on disk.
    Result<Dataset> ds = ReadDataset(dir);
    ASSERT_TRUE(ds.ok()) << ds.status().message();
    EXPECT_EQ(ds->frames.size(), 2u);
    EXPECT_FALSE(ds->has_poses);
    // A pose on a dataset opened without poses is refused.
    const Status s =
        writer.Append(dsp::ImageView{px.data(), 8, 6, 8, dsp::PixelFormat::kGrey8}, 2.0, Pose{});
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  }
  DatasetWriter again;
  const Status s = again.Open(dir, false);
  EXPECT_EQ(s.code(), StatusCode::kAlreadyExists);
  EXPECT_NE(std::string(s.message()).find("already exists"), std::string::npos) << s.message();
}

struct BadCsv {
  const char* name;
  std::string csv;
  const char* expect;  // in the message
};

TEST(Dataset, CsvErrorsNameFileAndLine) {
  const std::string pose_header = "index,file,timestamp_s,x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg\n";
  const std::vector<BadCsv> cases = {
      {"header", "idx,file,time\n0,a.png,0\n", "frames.csv:1: header must be"},
      {"fields", "index,file,timestamp_s\n0,a.png\n", "frames.csv:2: expected 3 fields, got 2"},
      {"index", "index,file,timestamp_s\n0,a.png,0\n2,b.png,1\n",
       "frames.csv:3: index 2 out of order"},
      {"index_text", "index,file,timestamp_s\nzero,a.png,0\n", "frames.csv:2: index 'zero'"},
      {"timestamp", "index,file,timestamp_s\n0,a.png,0\n1,b.png,1.5s\n",
       "frames.csv:3: timestamp_s '1.5s' is not a number"},
      {"backwards", "index,file,timestamp_s\n0,a.png,2\n1,b.png,1\n",
       "frames.csv:3: timestamp_s 1.000000 goes backwards"},
      {"pose", pose_header + "0,a.png,0,1,2,3,4,five,6\n", "frames.csv:2: pitch_deg 'five'"},
      {"attitude", "index,file,timestamp_s,roll_deg,pitch_deg\n0,a.png,0,1,x\n",
       "frames.csv:2: pitch_deg 'x'"},
      {"attitude_fields", "index,file,timestamp_s,roll_deg,pitch_deg\n0,a.png,0,1\n",
       "frames.csv:2: expected 5 fields, got 4"},
      {"missing_image", "index,file,timestamp_s\n0,a.png,0\n1,gone.png,1\n", "frames.csv:3: image"},
      {"extension", "index,file,timestamp_s\n0,a.jpg,0\n", "frames.csv:2: file 'a.jpg'"},
      {"blank_line", "index,file,timestamp_s\n0,a.png,0\n\n1,b.png,1\n",
       "frames.csv:3: empty line"},
      {"empty", "", "frames.csv: empty file"},
      {"no_frames", "index,file,timestamp_s\n", "no frames after the header"},
  };
  for (const BadCsv& c : cases) {
    const ScratchDir scratch("skyloc_dataset_");
    const std::string& dir = scratch.path();
    ASSERT_EQ(::system(("mkdir -p " + dir + "/frames").c_str()), 0);
    WriteText(dir + "/frames/a.png", "x");
    WriteText(dir + "/frames/b.png", "x");
    WriteText(dir + "/frames.csv", c.csv);
    Result<Dataset> ds = ReadDataset(dir);
    ASSERT_FALSE(ds.ok()) << c.name;
    const std::string msg = ds.status().message();
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(dir), std::string::npos) << c.name << ": " << msg;
    // The text alone (what the fuzzer drives) gives the same error, unless the error is
    // about the folder: an image that is not there, or no frames at all.
    if (std::string(c.name) == "missing_image" || std::string(c.name) == "no_frames")
      continue;
    Dataset parsed;
    const Status from_text = ParseDatasetCsv(c.csv, dir + "/frames.csv", &parsed);
    ASSERT_FALSE(from_text.ok()) << c.name;
    EXPECT_EQ(std::string(from_text.message()), msg) << c.name;
  }
}

// The attitude-only header (an IMU's roll and pitch, no position), and the attitude the pose
// columns give: both reach the replay camera's frames for [attitude] kind = "dataset".
TEST(Dataset, RollAndPitchColumnsGiveEachFrameItsAttitude) {
  const ScratchDir scratch("skyloc_dataset_");
  const std::string& dir = scratch.path();
  ASSERT_EQ(::system(("mkdir -p " + dir + "/frames").c_str()), 0);
  WriteText(dir + "/frames/a.png", "x");
  WriteText(dir + "/frames/b.png", "x");
  WriteText(dir + "/frames.csv",
            "index,file,timestamp_s,roll_deg,pitch_deg\n0,a.png,0,10,-20\n1,b.png,0.5,0,30\n");
  Result<Dataset> ds = ReadDataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  EXPECT_TRUE(ds->has_attitude);
  EXPECT_FALSE(ds->has_poses);
  ASSERT_TRUE(ds->frames[1].attitude.has_value());
  EXPECT_FALSE(ds->frames[1].pose.has_value());
  EXPECT_EQ(ds->frames[1].attitude->timestamp_ns, 500'000'000);
  EXPECT_DOUBLE_EQ(ds->frames[0].attitude->roll_deg, 10.0);
  EXPECT_DOUBLE_EQ(ds->frames[0].attitude->pitch_deg, -20.0);
  // up = (sin p, cos p sin r, cos p cos r) for p = 30 degrees, r = 0.
  EXPECT_NEAR(ds->frames[1].attitude->up[0], 0.5, 1e-12);
  EXPECT_NEAR(ds->frames[1].attitude->up[2], std::sqrt(0.75), 1e-12);

  WriteText(dir + "/frames.csv",
            "index,file,timestamp_s,x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg\n"
            "0,a.png,0,1,2,3,-5,7,90\n1,b.png,1,1,2,3,0,0,0\n");
  ds = ReadDataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  EXPECT_TRUE(ds->has_attitude);
  EXPECT_DOUBLE_EQ(ds->frames[0].attitude->roll_deg, -5.0);
  EXPECT_DOUBLE_EQ(ds->frames[0].attitude->pitch_deg, 7.0);

  WriteText(dir + "/frames.csv", "index,file,timestamp_s\n0,a.png,0\n");
  ds = ReadDataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  EXPECT_FALSE(ds->has_attitude);
  EXPECT_FALSE(ds->frames[0].attitude.has_value());
}

TEST(Dataset, FolderWithoutCsvIsListedByName) {
  const ScratchDir scratch("skyloc_dataset_");
  const std::string& dir = scratch.path();
  ASSERT_EQ(::system(("mkdir -p " + dir + "/frames").c_str()), 0);
  for (const char* name : {"b.pgm", "a.png", "c.PNG", "notes.txt"})
    WriteText(dir + "/frames/" + name, "x");
  WriteText(dir + "/camera.toml", "model = \"equidistant\"\n");
  Result<Dataset> ds = ReadDataset(dir);
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ASSERT_EQ(ds->frames.size(), 3u);
  EXPECT_EQ(ds->frames[0].file, "a.png");
  EXPECT_EQ(ds->frames[1].file, "b.pgm");
  EXPECT_EQ(ds->frames[2].file, "c.PNG");
  EXPECT_FALSE(ds->has_timestamps);
  EXPECT_EQ(ds->camera_toml, dir + "/camera.toml");

  Result<Dataset> missing = ReadDataset(dir + "/nope");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
}

// teach --record checks the folder before it creates the route, without creating anything.
TEST(Dataset, CheckNewDatasetFolderRefusesAnEarlierRecordingAndCreatesNothing) {
  const ScratchDir scratch("skyloc_dataset_");
  const std::string& dir = scratch.path();
  EXPECT_TRUE(CheckNewDatasetFolder(dir + "/new").ok());
  EXPECT_NE(::access((dir + "/new").c_str(), F_OK), 0) << "the check created the folder";
  WriteText(dir + "/frames.csv", "index,file,timestamp_s\n");
  const Status s = CheckNewDatasetFolder(dir + "/");
  EXPECT_EQ(s.code(), StatusCode::kAlreadyExists);
  EXPECT_NE(std::string(s.message()).find("frames.csv already exists"), std::string::npos)
      << s.message();
  WriteText(dir + "/file", "x");
  EXPECT_EQ(CheckNewDatasetFolder(dir + "/file").code(), StatusCode::kInvalidArgument);
}

// A FIFO (or anything but a regular file) in place of frames.csv or camera.toml is
// refused naming it, not taken for a missing file: a missing frames.csv would have the
// frames listed by name with made-up timestamps, a missing camera.toml the default lens.
TEST(Dataset, AFifoInPlaceOfFramesCsvOrCameraTomlIsRefused) {
  const ScratchDir scratch("skyloc_dataset_");
  const std::string& dir = scratch.path();
  ASSERT_EQ(::system(("mkdir -p " + dir + "/frames").c_str()), 0);
  WriteText(dir + "/frames/a.png", "x");
  ASSERT_EQ(::mkfifo((dir + "/frames.csv").c_str(), 0600), 0);
  ::alarm(10);  // a hang fails the test instead of blocking ctest
  Result<Dataset> ds = ReadDataset(dir);
  ASSERT_FALSE(ds.ok());
  EXPECT_EQ(ds.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(ds.status().message()).find("frames.csv is a FIFO, not a regular file"),
            std::string::npos)
      << ds.status().message();

  ASSERT_EQ(::unlink((dir + "/frames.csv").c_str()), 0);
  ASSERT_EQ(::mkfifo((dir + "/camera.toml").c_str(), 0600), 0);
  ds = ReadDataset(dir);
  ASSERT_FALSE(ds.ok());
  EXPECT_NE(std::string(ds.status().message()).find("camera.toml is a FIFO, not a regular file"),
            std::string::npos)
      << ds.status().message();
  ::alarm(0);
}

}  // namespace
}  // namespace skyloc::drivers
