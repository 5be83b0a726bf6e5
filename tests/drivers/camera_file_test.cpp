#include "skyloc/drivers/camera_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "skyloc/drivers/toml_text.h"
#include "support/scratch_dir.h"

namespace skyloc::drivers {
namespace {

using ::testing::HasSubstr;

Result<dsp::LensParams> Parse(const std::string& text) {
  return ParseCameraFile(text, "cam.toml", ".");
}

std::string Message(const Result<dsp::LensParams>& r) {
  EXPECT_FALSE(r.ok());
  return r.ok() ? std::string() : std::string(r.status().message());
}

TEST(CameraFile, ShippedExampleLoads) {
  auto r = LoadCameraFile(SKYLOC_SOURCE_DIR "/config/camera-equidistant-185.toml");
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->model, dsp::LensModel::kEquidistant);
  EXPECT_EQ(r->width, 640);
  EXPECT_EQ(r->height, 480);
  EXPECT_EQ(r->fov_deg, 185.0);
  EXPECT_EQ(r->centre_x, 319.5);
  EXPECT_EQ(r->centre_y, 239.5);
  EXPECT_EQ(r->radius_px, 240.0);
}

TEST(CameraFile, AllKeysOfKannalaBrandtAndMount) {
  auto r = Parse(R"(
[image]
width = 1280
height = 960
[lens]
model = "kannala_brandt"
fx = 331
fy = 331.5
centre = [640.25, 481]
k = [0.02, -0.004, 0.001, -0.0002]
fov_deg = 190
radius_px = 470
[mount]
roll_deg = 1.5
pitch_deg = -2
yaw_deg = 90
)");
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->model, dsp::LensModel::kKannalaBrandt);
  EXPECT_EQ(r->fx, 331.0);
  EXPECT_EQ(r->fy, 331.5);
  EXPECT_EQ(r->centre_x, 640.25);
  EXPECT_EQ(r->k[1], -0.004);
  EXPECT_EQ(r->k[3], -0.0002);
  EXPECT_EQ(r->roll_deg, 1.5);
  EXPECT_EQ(r->pitch_deg, -2.0);
  EXPECT_EQ(r->yaw_deg, 90.0);
}

// What skyloc writes next to a recording reads back as the same lens, for every model it
// writes; an OCamCalib lens is refused (its polynomial lives in a file of its own).
TEST(CameraFile, WrittenTextReadsBackAsTheSameLens) {
  dsp::LensParams kb;
  kb.model = dsp::LensModel::kKannalaBrandt;
  kb.width = 640;
  kb.height = 480;
  kb.fx = 301.25;
  kb.fy = 299.5;
  kb.k = {0.01, -0.002, 0.0003, -0.00004};
  kb.centre_x = 322.5;
  kb.centre_y = 241.0;
  kb.fov_deg = 190;
  kb.roll_deg = 1.5;
  kb.pitch_deg = -2.25;
  kb.yaw_deg = 90;
  dsp::LensParams eq;  // defaults: centre and radius unset, written as their effective values
  eq.width = 96;
  eq.height = 72;
  dsp::LensParams pinhole;  // no radius_px written: the file refuses it for a pinhole
  pinhole.model = dsp::LensModel::kPinhole;
  pinhole.width = 640;
  pinhole.height = 480;
  pinhole.fov_deg = 47.8;
  pinhole.roll_deg = -90;
  pinhole.yaw_deg = -90;
  for (const dsp::LensParams& p : {kb, eq, pinhole}) {
    dsp::Lens lens;
    ASSERT_EQ(lens.Init(p), dsp::LensError::kOk);
    Result<std::string> text = CameraFileText(lens, "a test");
    ASSERT_TRUE(text.ok()) << text.status().message();
    Result<dsp::LensParams> back = ParseCameraFile(*text, "written", ".");
    ASSERT_TRUE(back.ok()) << back.status().message() << "\n" << *text;
    dsp::Lens again;
    ASSERT_EQ(again.Init(*back), dsp::LensError::kOk);
    EXPECT_EQ(back->model, p.model);
    EXPECT_EQ(back->width, p.width);
    EXPECT_EQ(back->height, p.height);
    EXPECT_NEAR(again.centre_x(), lens.centre_x(), 1e-6);
    EXPECT_NEAR(again.centre_y(), lens.centre_y(), 1e-6);
    EXPECT_NEAR(again.radius_px(), lens.radius_px(), 1e-6);
    EXPECT_NEAR(back->fov_deg, p.fov_deg, 1e-6);
    EXPECT_EQ(back->fx, p.fx);
    EXPECT_EQ(back->k, p.k);
    EXPECT_NEAR(back->yaw_deg, p.yaw_deg, 1e-6);
    EXPECT_NEAR(back->pitch_deg, p.pitch_deg, 1e-6);
  }
}

TEST(CameraFile, PinholeNeedsItsFieldOfViewAndHasNoImageCircle) {
  const std::string image = "[image]\nwidth = 640\nheight = 480\n";
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"pinhole\"\n")),
              HasSubstr("needs lens.fov_deg"));
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"pinhole\"\nfov_deg = 200\n")),
              HasSubstr("below 180"));
  EXPECT_THAT(
      Message(Parse(image + "[lens]\nmodel = \"pinhole\"\nfov_deg = 60\nradius_px = 200\n")),
      HasSubstr("lens.radius_px"));
  Result<dsp::LensParams> ok = Parse(image + "[lens]\nmodel = \"pinhole\"\nfov_deg = 47.8\n");
  ASSERT_TRUE(ok.ok()) << ok.status().message();
  EXPECT_EQ(ok->model, dsp::LensModel::kPinhole);
}

TEST(CameraFile, ErrorsNameTheFileTheKeyAndTheFix) {
  const std::string image = "[image]\nwidth = 640\nheight = 480\n";
  // Unknown key (a typo) with its line and the allowed keys.
  std::string m = Message(Parse(image + "[lens]\nfov_dg = 185\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:5"));
  EXPECT_THAT(m, HasSubstr("fov_dg"));
  EXPECT_THAT(m, HasSubstr("fov_deg"));
  // Unknown table.
  EXPECT_THAT(Message(Parse(image + "[lenz]\n")), HasSubstr("'lenz'"));
  // Out of range.
  m = Message(Parse(image + "[lens]\nfov_deg = 400\n"));
  EXPECT_THAT(m, HasSubstr("lens.fov_deg"));
  EXPECT_THAT(m, HasSubstr("(0, 360]"));
  EXPECT_THAT(Message(Parse(image + "[lens]\nradius_px = -1\n")), HasSubstr("lens.radius_px"));
  EXPECT_THAT(Message(Parse("[image]\nwidth = 0\nheight = 480\n")), HasSubstr("image.width"));
  EXPECT_THAT(Message(Parse(image + "[mount]\nyaw_deg = 1000\n")), HasSubstr("mount.yaw_deg"));
  // Wrong types.
  EXPECT_THAT(Message(Parse(image + "[lens]\nfov_deg = \"wide\"\n")),
              HasSubstr("must be a number"));
  EXPECT_THAT(Message(Parse("[image]\nwidth = 640.5\nheight = 480\n")), HasSubstr("image.width"));
  EXPECT_THAT(Message(Parse(image + "[lens]\ncentre = [1]\n")), HasSubstr("lens.centre"));
  // Model names and model-specific keys.
  m = Message(Parse(image + "[lens]\nmodel = \"fisheye\"\n"));
  EXPECT_THAT(m, HasSubstr("lens.model"));
  EXPECT_THAT(m, HasSubstr("\"equisolid\""));
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"kannala_brandt\"\nfx = 300\n")),
              HasSubstr("lens.fy"));
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"equidistant\"\nk = [0, 0, 0, 0]\n")),
              HasSubstr("does not apply"));
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"equirectangular\"\nfov_deg = 180\n")),
              HasSubstr("lens.fov_deg"));
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"ocamcalib\"\n")),
              HasSubstr("ocamcalib_file"));
  // Missing [image]; TOML syntax error with its line.
  EXPECT_THAT(Message(Parse("[lens]\nmodel = \"equidistant\"\n")), HasSubstr("[image]"));
  EXPECT_THAT(Message(Parse(image + "[lens\n")), HasSubstr("cam.toml:4"));
  // Lens validation after parsing (Kannala-Brandt folding back).
  EXPECT_THAT(Message(Parse(image + "[lens]\nmodel = \"kannala_brandt\"\nfx = 200\nfy = 200\n"
                                    "k = [-1, 0, 0, 0]\n")),
              HasSubstr("folds back"));
}

// toml++ 3.3.0 reaches __builtin_unreachable() on some non-ASCII characters between tokens
// (the config fuzz target found it). Camera files go through the same guarded reader as the
// configuration: such text is refused with its position before toml++ sees it, while
// comments and strings may hold other UTF-8 (U+738B here; the code points toml++ misreads
// everywhere are refused even there, config_test.cpp).
TEST(CameraFile, NonAsciiOutsideStringsIsRefusedWithItsPosition) {
  // The config fuzzer's input: U+FCFF inside a table header.
  std::string m =
      Message(Parse("[im\xef\xb3\xbf"
                    "age]\nwidth = 640\nheight = 480\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:1:4: the character U+FCFF cannot be read"));
  // U+00A0 (no-break space) where toml++ looks for whitespace, after a value.
  m = Message(Parse("[image]\nwidth = 640\xc2\xa0\nheight = 480\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:2:12: a non-ASCII"));
  // The camera-file fuzzer's input: a quote after a malformed value opens no string, and
  // toml++ reads the U+0430 after it as code.
  m = Message(Parse("[lens]\ncentre = 3PP\"\xe7\x8e\x8b\"\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:2:14: a non-ASCII"));
  m = Message(Parse("[lens]\ncentre = [38.59.'''\xe7\x8e\x8b'''\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:2:20: a non-ASCII"));
  m = Message(Parse("[lens]\ncentre = 3P#\xe7\x8e\x8b\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:2:13: a non-ASCII"));
  // Inside a multi-line string, the first character kept after a line-ending backslash
  // (toml++ trims the whitespace after it with the same check).
  m = Message(Parse("n = \"\"\"a\\\n  \xe7\x8e\x8b\"\"\"\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:2:3: a non-ASCII"));
  // ...and right after a backslash, in either kind of basic string.
  m = Message(Parse("n = \"\"\"a\\\xe7\x8e\x8b\"\"\"\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:1:10: a non-ASCII"));
  m = Message(Parse("n = \"a\\ \xe7\x8e\x8b\"\n"));
  EXPECT_THAT(m, HasSubstr("cam.toml:1:9: a non-ASCII"));
  // Strings open where TOML lets them: after '=', '[', ',', '{', '.' or at a line's start.
  auto strings = ParseTomlText(
      "\"cl\xe7\x8e\x8b\" = [ \"\xe7\x8e\x8bt\xe7\x8e\x8b\",\n  '\xe7\x8e\x8b' ]# "
      "\xe7\x8e\x8b\na.b = { c = "
      "\"\xe7\x8e\x8b\" }\n"
      "c = \"\"\"\n\xe7\x8e\x8b \\\n  x\xe7\x8e\x8b\"\"\"\n",
      "text.toml");
  ASSERT_TRUE(strings.ok()) << strings.status().message();
  EXPECT_EQ(strings->size(), 3u);

  auto ok = Parse(
      "# Kamera UV \xe2\x80\x94 a comment\n[image]\nwidth = 640  # \xe7\x8e\x8b\n"
      "height = 480\n[lens]\nmodel = \"equidistant\"\n");
  ASSERT_TRUE(ok.ok()) << ok.status().message();
  EXPECT_EQ(ok->width, 640);
}

TEST(CameraFile, MissingFileIsNotFound) {
  auto r = LoadCameraFile("/nonexistent/camera.toml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_THAT(r.status().message(), HasSubstr("/nonexistent/camera.toml"));
}

// The layout the OCamCalib toolbox writes (values from a published 1024x1024 calibration).
constexpr char kCalibResults[] =
    R"(#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by cam2world

5 -4.167604e+02 0.000000e+00 1.190213e-03 -1.534627e-06 3.137860e-09 

#polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB). These are used by world2cam

12 562.102870 266.095519 -26.584752 56.736554 9.341520 6.790452 14.809291 -21.675851 -10.308973 24.528996 20.092843 4.259172 

#center: "row" and "column", starting from 0 (C convention)

497.570118 508.063716

#affine parameters "c", "d", "e"

0.997772 -0.011575 0.011638

#image size: "height" and "width"

1024 1024
)";

class OCamCalibFileTest : public ::testing::Test {
 protected:
  void Write(const char* name, const std::string& text) {
    std::ofstream(dir_ + "/" + name) << text;
  }
  skyloc::testing::ScratchDir scratch_{"skyloc_camera_file_"};
  const std::string& dir_ = scratch_.path();
};

TEST_F(OCamCalibFileTest, ToolboxFileLoadsRelativeToTheCameraFile) {
  Write("calib_results.txt", kCalibResults);
  Write("camera.toml",
        "[image]\nwidth = 1024\nheight = 1024\n[lens]\nmodel = \"ocamcalib\"\n"
        "ocamcalib_file = \"calib_results.txt\"\nradius_px = 500\n");
  auto r = LoadCameraFile((dir_ + "/camera.toml").c_str());
  ASSERT_TRUE(r.ok()) << r.status().message();
  const dsp::OCamCalibModel& o = r->ocam;
  EXPECT_EQ(o.ss_count, 5);
  EXPECT_EQ(o.ss[0], -4.167604e+02);
  EXPECT_EQ(o.ss[4], 3.137860e-09);
  EXPECT_EQ(o.invpol_count, 12);
  EXPECT_EQ(o.invpol[11], 4.259172);
  EXPECT_EQ(o.row_centre, 497.570118);
  EXPECT_EQ(o.column_centre, 508.063716);
  EXPECT_EQ(o.d, -0.011575);
  EXPECT_EQ(o.height, 1024);
  // The real calibration gives a usable lens: the centre pixel looks along the axis.
  dsp::Lens lens;
  ASSERT_TRUE(InitLens(*r, "camera.toml", &lens).ok());
  Eigen::Vector3d ray;
  ASSERT_TRUE(lens.PixelToCameraRay(o.column_centre, o.row_centre, &ray));
  EXPECT_NEAR(ray(2), 1.0, 1e-12);
}

TEST_F(OCamCalibFileTest, BrokenFilesNameTheLineAndWhatWasExpected) {
  std::string broken = kCalibResults;
  broken.replace(broken.find("5 -4.1676"), 1, "6");  // count does not match
  Write("bad.txt", broken);
  auto r = LoadOCamCalibFile((dir_ + "/bad.txt").c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("bad.txt' line 3"));
  EXPECT_THAT(r.status().message(), HasSubstr("ss polynomial"));

  Write("short.txt",
        std::string(kCalibResults).substr(0, std::string(kCalibResults).find("#center")));
  r = LoadOCamCalibFile((dir_ + "/short.txt").c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("centre"));

  Write("camera.toml",
        "[image]\nwidth = 1024\nheight = 1024\n[lens]\nmodel = \"ocamcalib\"\n"
        "ocamcalib_file = \"missing.txt\"\n");
  auto c = LoadCameraFile((dir_ + "/camera.toml").c_str());
  ASSERT_FALSE(c.ok());
  EXPECT_THAT(c.status().message(), HasSubstr("lens.ocamcalib_file"));
  EXPECT_THAT(c.status().message(), HasSubstr("missing.txt"));

  // A calibration for another image size.
  Write("calib_results.txt", kCalibResults);
  Write("camera.toml",
        "[image]\nwidth = 640\nheight = 480\n[lens]\nmodel = \"ocamcalib\"\n"
        "ocamcalib_file = \"calib_results.txt\"\n");
  c = LoadCameraFile((dir_ + "/camera.toml").c_str());
  ASSERT_FALSE(c.ok());
  EXPECT_THAT(c.status().message(), HasSubstr("image size"));
}

}  // namespace
}  // namespace skyloc::drivers
