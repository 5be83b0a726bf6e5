#include "skyloc/drivers/image_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "skyloc/drivers/camera_file.h"
#include "skyloc/platform/alloc_counter.h"
#include "support/scratch_dir.h"

namespace skyloc::drivers {
namespace {

class ImageFileTest : public ::testing::Test {
 protected:
  std::string Path(const char* name) const { return dir_ + "/" + name; }
  void WriteBytes(const std::string& path, const std::string& bytes) const {
    std::ofstream(path, std::ios::binary) << bytes;
  }
  skyloc::testing::ScratchDir scratch_{"skyloc_image_file_"};
  const std::string& dir_ = scratch_.path();
};

OwnedImage Gradient(int w, int h, dsp::PixelFormat format) {
  auto r = OwnedImage::Allocate(w, h, format);
  EXPECT_TRUE(r.ok()) << r.status().message();
  OwnedImage image = std::move(r).value();
  dsp::MutableImageView v = image.mutable_view();
  const std::size_t row_bytes = dsp::ImageView(v).RowBytes();
  for (int y = 0; y < h; ++y)
    for (std::size_t i = 0; i < row_bytes; ++i)
      v.Row(y)[i] = static_cast<std::uint8_t>((static_cast<std::size_t>(y) * 7 + i * 3) & 0xff);
  return image;
}

TEST_F(ImageFileTest, GreyPngRoundTripsExactly) {
  OwnedImage image = Gradient(37, 21, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(SavePng(Path("g.png").c_str(), image.view()).ok());
  auto loaded = LoadImage(Path("g.png").c_str());
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  ASSERT_EQ(loaded->format(), dsp::PixelFormat::kGrey8);
  ASSERT_EQ(loaded->width(), 37);
  ASSERT_EQ(loaded->height(), 21);
  for (int y = 0; y < 21; ++y)
    for (int x = 0; x < 37; ++x)
      ASSERT_EQ(loaded->view().Row(y)[x], image.view().Row(y)[x]);
}

TEST_F(ImageFileTest, BgrIsWrittenAsRgb) {
  OwnedImage image = Gradient(5, 3, dsp::PixelFormat::kBgr24);
  ASSERT_TRUE(SavePng(Path("c.png").c_str(), image.view()).ok());
  auto loaded = LoadImage(Path("c.png").c_str());
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  ASSERT_EQ(loaded->format(), dsp::PixelFormat::kRgb24);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      const std::uint8_t* bgr = image.view().Row(y) + 3 * x;
      const std::uint8_t* rgb = loaded->view().Row(y) + 3 * x;
      EXPECT_EQ(rgb[0], bgr[2]);
      EXPECT_EQ(rgb[1], bgr[1]);
      EXPECT_EQ(rgb[2], bgr[0]);
    }
  }
}

TEST_F(ImageFileTest, YuyvIsWrittenAsItsLumaPlane) {
  OwnedImage image = Gradient(6, 2, dsp::PixelFormat::kYuyv);
  ASSERT_TRUE(SavePng(Path("y.png").c_str(), image.view()).ok());
  auto loaded = LoadImage(Path("y.png").c_str());
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  ASSERT_EQ(loaded->format(), dsp::PixelFormat::kGrey8);
  ASSERT_EQ(loaded->width(), 6);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 6; ++x)
      EXPECT_EQ(loaded->view().Row(y)[x], image.view().Row(y)[2 * x]);
}

TEST_F(ImageFileTest, SaveReplacesInPlaceAndLeavesNoTemporaryFiles) {
  OwnedImage image = Gradient(8, 8, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(SavePng(Path("a.png").c_str(), image.view()).ok());
  ASSERT_TRUE(SavePng(Path("a.png").c_str(), image.view()).ok());
  int files = 0;
  FILE* ls = popen(("ls -A '" + dir_ + "'").c_str(), "r");
  ASSERT_NE(ls, nullptr);
  char line[256];
  while (fgets(line, sizeof line, ls) != nullptr)
    ++files;
  pclose(ls);
  EXPECT_EQ(files, 1);
}

TEST_F(ImageFileTest, SaveIntoMissingDirectoryNamesThePath) {
  OwnedImage image = Gradient(8, 8, dsp::PixelFormat::kGrey8);
  const std::string path = Path("no/such/dir/x.png");
  Status s = SavePng(path.c_str(), image.view());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(std::string(s.message()).find(path), std::string::npos) << s.message();
}

TEST_F(ImageFileTest, PgmAt8And16BitAndOddMaxvalScalesTo255) {
  // 2x1 P5 at maxval 255, 65535 (big-endian samples) and 1023: all become 0..255.
  WriteBytes(Path("a.pgm"), std::string("P5\n# comment\n2 1\n255\n") + '\x10' + '\xf0');
  WriteBytes(Path("b.pgm"), std::string("P5 2 1 65535\n") + '\x12' + '\x34' + '\xff' + '\xff');
  WriteBytes(Path("c.pgm"), std::string("P5 2 1 1023\n") + '\x01' + '\xff' + '\x03' + '\xff');
  auto a = LoadImage(Path("a.pgm").c_str());
  auto b = LoadImage(Path("b.pgm").c_str());
  auto c = LoadImage(Path("c.pgm").c_str());
  ASSERT_TRUE(a.ok()) << a.status().message();
  ASSERT_TRUE(b.ok()) << b.status().message();
  ASSERT_TRUE(c.ok()) << c.status().message();
  EXPECT_EQ(a->view().data[0], 0x10);
  EXPECT_EQ(a->view().data[1], 0xf0);
  EXPECT_EQ(b->view().data[0], (0x1234 * 255 + 65535 / 2) / 65535);
  EXPECT_EQ(b->view().data[1], 255);
  EXPECT_EQ(c->view().data[0], (511 * 255 + 1023 / 2) / 1023);
  EXPECT_EQ(c->view().data[1], 255);
}

TEST_F(ImageFileTest, PpmLoadsAsRgb) {
  WriteBytes(Path("a.ppm"), std::string("P6\n1 1\n255\n") + '\x01' + '\x02' + '\x03');
  auto a = LoadImage(Path("a.ppm").c_str());
  ASSERT_TRUE(a.ok()) << a.status().message();
  EXPECT_EQ(a->format(), dsp::PixelFormat::kRgb24);
  EXPECT_EQ(a->view().data[0], 1);
  EXPECT_EQ(a->view().data[1], 2);
  EXPECT_EQ(a->view().data[2], 3);
}

TEST_F(ImageFileTest, ErrorsNameTheFileAndTheProblem) {
  const std::string missing = Path("missing.png");
  auto r = LoadImage(missing.c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(std::string(r.status().message()).find(missing), std::string::npos);

  WriteBytes(Path("text.png"), "this is not an image\n");
  auto t = LoadImage(Path("text.png").c_str());
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(t.status().message()).find("text.png"), std::string::npos);

  WriteBytes(Path("short.pgm"), "P5 4 4 255\nab");  // truncated pixel data
  auto s = LoadImage(Path("short.pgm").c_str());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(std::string(s.status().message()).find("short.pgm"), std::string::npos);
  // The samples that are there are counted (not the whole 4 KiB blocks read so far).
  EXPECT_NE(std::string(s.status().message()).find("2 of 16 samples present"), std::string::npos)
      << s.status().message();
}

// A FIFO (or any file that is not a regular one) named as an image or a camera file is
// refused at once, naming it; opening it must not wait for a writer that never comes.
TEST_F(ImageFileTest, AFifoIsRefusedWithoutWaiting) {
  const std::string fifo = Path("fifo.png");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ::alarm(10);  // a hang fails the test instead of blocking ctest
  auto r = LoadImage(fifo.c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(r.status().message()).find(fifo + " is a FIFO, not a regular file"),
            std::string::npos)
      << r.status().message();
  auto c = LoadCameraFile(fifo.c_str());
  ASSERT_FALSE(c.ok());
  EXPECT_NE(std::string(c.status().message()).find("is a FIFO, not a regular file"),
            std::string::npos)
      << c.status().message();
  auto d = LoadImage(dir_.c_str());
  ASSERT_FALSE(d.ok());
  EXPECT_NE(std::string(d.status().message()).find("is a directory"), std::string::npos)
      << d.status().message();
  ::alarm(0);
}

// A PNG larger than skyloc reads is "too large" with the limit, not "not a PNG".
TEST_F(ImageFileTest, APngTooLargeIsSaidToBeTooLarge) {
  for (const std::uint32_t width : {70000u, 1u << 25}) {
    std::string png("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16);
    for (const std::uint32_t v : {width, 10u})
      for (int shift = 24; shift >= 0; shift -= 8)
        png += static_cast<char>((v >> shift) & 0xff);
    png += std::string("\x08\0\0\0\0\0\0\0\0", 9);  // grey 8-bit; CRC not checked here
    WriteBytes(Path("huge.png"), png);
    auto r = LoadImage(Path("huge.png").c_str());
    ASSERT_FALSE(r.ok());
    const std::string m = r.status().message();
    EXPECT_NE(m.find("huge.png"), std::string::npos) << m;
    EXPECT_NE(m.find(std::to_string(width) + "x10 pixels: too large"), std::string::npos) << m;
    EXPECT_NE(m.find("65535x65535"), std::string::npos) << m;
    EXPECT_EQ(m.find("not a PNG"), std::string::npos) << m;
  }
}

// A header is a few bytes: a PNM that promises 50000x50000 pixels, or a PNG of more
// pixels than skyloc reads, is refused before anything is allocated for it (the fuzzer
// found the PNM allocating 8 GB for a 29-byte file).
TEST_F(ImageFileTest, AHeaderPromisingMorePixelsThanThereAreAllocatesNothing) {
  WriteBytes(Path("promise.ppm"), "P6\n20000 3000\n255\n\x01\x02\x03");
  ASSERT_TRUE(AllocationCounterActive());
  AllocationScope scope;
  auto r = LoadImage(Path("promise.ppm").c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_LT(scope.bytes(), std::uint64_t{1} << 20);  // the FILE's buffer, the message
  EXPECT_NE(std::string(r.status().message()).find("truncated: 3 of 180000000 samples present"),
            std::string::npos)
      << r.status().message();
  // A PNG of 4x3 pixels whose IDAT chunk declares 1.3 GB: stb would allocate that much.
  std::string png(
      "\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\0\x04\0\0\0\x03\x08\0\0\0\0"
      "\x91\x9f\xf1\x1a\x50\0\0\0IDATx\x9c\x63\x60",
      45);
  // Behind a first chunk that is not IHDR (stb reads Apple's CgBI chunk first).
  {
    const std::string cgbi =
        png.substr(0, 8) + std::string("\0\0\0\0CgBI\0\0\0\0", 12) + png.substr(8);
    WriteBytes(Path("cgbi.png"), cgbi);
    AllocationScope cgbi_scope;
    auto c = LoadImage(Path("cgbi.png").c_str());
    ASSERT_FALSE(c.ok());
    EXPECT_LT(cgbi_scope.bytes(), std::uint64_t{1} << 20);
    EXPECT_NE(std::string(c.status().message()).find("its IDAT chunk at byte 45 declares"),
              std::string::npos)
        << c.status().message();
  }
  // Whole, and cut off right after the chunk's type (no data, no CRC).
  for (const std::size_t length : {png.size(), std::size_t{41}}) {
    WriteBytes(Path("greedy.png"), png.substr(0, length));
    AllocationScope png_scope;
    auto g = LoadImage(Path("greedy.png").c_str());
    ASSERT_FALSE(g.ok()) << length;
    EXPECT_LT(png_scope.bytes(), std::uint64_t{1} << 20) << length;
    EXPECT_NE(std::string(g.status().message()).find("its IDAT chunk at byte 33 declares"),
              std::string::npos)
        << g.status().message();
  }
  WriteBytes(Path("vast.pgm"), "P5 50000 50000 255\n\x01");
  auto v = LoadImage(Path("vast.pgm").c_str());
  ASSERT_FALSE(v.ok());
  EXPECT_NE(std::string(v.status().message()).find("50000x50000 pixels: too large"),
            std::string::npos)
      << v.status().message();
}

}  // namespace
}  // namespace skyloc::drivers
