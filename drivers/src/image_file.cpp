#include "skyloc/drivers/image_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>

// The one translation unit that compiles stb's implementations. Only PNG is built
// in (PNM is read below); everything else stb could decode is rejected as "not an image".
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_NO_LINEAR
#define STBI_NO_HDR
#define STBI_FAILURE_USERMSG
#include <stb/stb_image.h>
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#include <stb/stb_image_write.h>

#include "skyloc/platform/regular_file.h"

namespace skyloc::drivers {
namespace {

constexpr int kMaxImageSide = 65535;  // OwnedImage::Allocate's limit
// A header is a promise a few bytes long: without a limit on the pixels, a 30-byte file
// that says 50000x50000 makes the reader allocate gigabytes before it finds the data
// missing (found by tests/fuzz/image_file_fuzz.cpp). 2^26 pixels (8192x8192, 192 MB as
// RGB) is well above any fisheye camera's frame.
constexpr std::int64_t kMaxImagePixels = std::int64_t{1} << 26;

Status TooLarge(const char* kind, const char* path, std::int64_t width, std::int64_t height) {
  return Status::Error(StatusCode::kInvalidArgument,
                       "%s '%s' is %lldx%lld pixels: too large, skyloc reads images of up to "
                       "%lld pixels (8192x8192) and sides up to %dx%d; scale it down",
                       kind, path, static_cast<long long>(width), static_cast<long long>(height),
                       static_cast<long long>(kMaxImagePixels), kMaxImageSide, kMaxImageSide);
}

bool IsTooLarge(std::int64_t width, std::int64_t height) {
  return width > kMaxImageSide || height > kMaxImageSide || width * height > kMaxImagePixels;
}

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// stb grows its buffer to a chunk's declared length before it reads the chunk, so a few
// bytes that declare a 2 GB IDAT make it allocate 2 GB (found by the fuzzer). Every chunk
// must fit in the file before stb sees it. `f` is left at the start.
Status CheckPngChunks(std::FILE* f, const char* path) {
  if (::fseeko(f, 0, SEEK_END) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot read image '%s'", path);
  }
  const off_t size = ::ftello(f);
  off_t at = 8;  // after the signature
  // Up to IEND, each chunk's length, type and CRC (12 bytes) and its data must be there
  // (a header cut off after its length field declared 1.8 GB, too).
  while (size >= 0 && at + 8 <= size) {
    unsigned char head[8];
    if (::fseeko(f, at, SEEK_SET) != 0 || std::fread(head, 1, sizeof head, f) != sizeof head)
      break;
    const std::uint32_t length = BigEndian32(head);
    char type[5];
    for (int i = 0; i < 4; ++i)
      type[i] = std::isalpha(head[4 + i]) != 0 ? static_cast<char>(head[4 + i]) : '?';
    type[4] = '\0';
    if (static_cast<std::int64_t>(length) + 12 > static_cast<std::int64_t>(size - at)) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "PNG '%s' is truncated or corrupt: its %s chunk at byte %lld declares "
                           "%u bytes, and the file ends %lld bytes after its header",
                           path, type, static_cast<long long>(at), static_cast<unsigned>(length),
                           static_cast<long long>(size - at - 8));
    }
    if (std::memcmp(head + 4, "IEND", 4) == 0)
      break;
    at += 12 + static_cast<off_t>(length);
  }
  std::rewind(f);
  return Status::Ok();
}

struct StbFree {
  void operator()(void* p) const { stbi_image_free(p); }
};

// Binary PGM/PPM are read here rather than by stb: stb 2.27 returns 16-bit PNM samples
// in host byte order (PNM is big-endian), ignores the maxval and does not notice a
// truncated file. Header: magic, width, height, maxval, separated by whitespace and
// '#' comments, then exactly one whitespace byte before the samples.
struct PnmHeader {
  int channels = 0;  // 0: not a binary PNM
  long width = 0, height = 0, maxval = 0;
};

PnmHeader ReadPnmHeader(std::FILE* f) {
  PnmHeader h;
  char magic[2];
  if (std::fread(magic, 1, 2, f) != 2 || magic[0] != 'P' || (magic[1] != '5' && magic[1] != '6'))
    return h;
  long* values[3] = {&h.width, &h.height, &h.maxval};
  for (long* v : values) {
    int c = std::fgetc(f);
    for (;;) {
      if (c == '#') {
        while (c != EOF && c != '\n')
          c = std::fgetc(f);
      } else if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
        c = std::fgetc(f);
      } else {
        break;
      }
    }
    if (c < '0' || c > '9')
      return h;
    while (c >= '0' && c <= '9' && *v < 1000000) {
      *v = *v * 10 + (c - '0');
      c = std::fgetc(f);
    }
    if (v == values[2] && c != ' ' && c != '\t' && c != '\n' && c != '\r')
      return h;
  }
  h.channels = magic[1] == '5' ? 1 : 3;
  return h;
}

Result<OwnedImage> ReadPnm(std::FILE* f, const PnmHeader& h, const char* path) {
  if (h.width <= 0 || h.height <= 0)
    return Status::Error(StatusCode::kInvalidArgument, "PNM image '%s' has a bad size %ldx%ld",
                         path, h.width, h.height);
  if (IsTooLarge(h.width, h.height))
    return TooLarge("PNM image", path, h.width, h.height);
  if (h.maxval <= 0 || h.maxval > 65535)
    return Status::Error(StatusCode::kInvalidArgument,
                         "PNM image '%s' has unsupported depth (maxval %ld; 1..65535 allowed)",
                         path, h.maxval);
  const std::size_t count = static_cast<std::size_t>(h.width) * static_cast<std::size_t>(h.height) *
                            static_cast<std::size_t>(h.channels);
  const std::size_t sample_bytes = h.maxval > 255 ? 2 : 1;
  // The samples must be in the file before the image is allocated for them.
  const off_t start = ::ftello(f);
  if (start >= 0 && ::fseeko(f, 0, SEEK_END) == 0) {
    const off_t end = ::ftello(f);
    const std::size_t present =
        end >= start ? static_cast<std::size_t>(end - start) / sample_bytes : 0;
    if (present < count)
      return Status::Error(StatusCode::kInvalidArgument,
                           "PNM image '%s' is truncated: %zu of %zu samples present", path, present,
                           count);
    if (::fseeko(f, start, SEEK_SET) != 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "cannot read image '%s'", path);
    }
  }
  SKYLOC_TRY_ASSIGN(
      OwnedImage image,
      OwnedImage::Allocate(static_cast<int>(h.width), static_cast<int>(h.height),
                           h.channels == 1 ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24));
  std::uint8_t* out = image.mutable_view().data;
  const auto maxval = static_cast<unsigned>(h.maxval);
  // Decoded through a small stack buffer: 16-bit samples are big-endian, any maxval scales.
  std::uint8_t chunk[4096];
  std::size_t done = 0;
  while (done < count) {
    const std::size_t samples = std::min(count - done, sizeof chunk / sample_bytes);
    const std::size_t got = std::fread(chunk, sample_bytes, samples, f);
    if (got != samples)
      return Status::Error(StatusCode::kInvalidArgument,
                           "PNM image '%s' is truncated: %zu of %zu samples present", path,
                           done + got, count);
    for (std::size_t i = 0; i < samples; ++i) {
      unsigned v = sample_bytes == 2 ? (unsigned{chunk[2 * i]} << 8) | chunk[2 * i + 1] : chunk[i];
      if (v > maxval)
        v = maxval;
      out[done + i] = static_cast<std::uint8_t>((v * 255u + maxval / 2) / maxval);
    }
    done += samples;
  }
  return image;
}

}  // namespace

Result<OwnedImage> OwnedImage::Allocate(int width, int height, dsp::PixelFormat format) {
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535 ||
      (format == dsp::PixelFormat::kYuyv && width % 2 != 0)) {
    return Status::Error(StatusCode::kInvalidArgument, "image size %dx%d (%s) is not allowed",
                         width, height, dsp::PixelFormatName(format));
  }
  OwnedImage image;
  image.width_ = width;
  image.height_ = height;
  image.format_ = format;
  image.stride_ = dsp::ImageView{nullptr, width, height, 0, format}.RowBytes();
  image.pixels_.reset(new (std::nothrow)
                          std::uint8_t[image.stride_ * static_cast<std::size_t>(height)]());
  if (!image.pixels_)
    return Status::Error(StatusCode::kResourceExhausted, "no memory for a %dx%d image", width,
                         height);
  return image;
}

Result<OwnedImage> LoadImage(const char* path) {
  // A FIFO or device named as an image is refused, not waited on.
  UniqueFd fd;
  SKYLOC_TRY(OpenRegularFile(path, O_RDONLY, "image", &fd));
  std::FILE* f = ::fdopen(fd.get(), "rb");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot open image '%s'", path);
  }
  (void)fd.release();  // the FILE owns it now
  const PnmHeader pnm = ReadPnmHeader(f);
  if (pnm.channels != 0) {
    Result<OwnedImage> image = ReadPnm(f, pnm, path);
    std::fclose(f);
    return image;
  }
  std::rewind(f);
  // A PNG's size is in its IHDR chunk (bytes 16..23, big-endian): one larger than skyloc
  // reads is said to be too large, not "not a PNG" (stb refuses it as corrupt).
  {
    constexpr unsigned char kPngMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char head[24];
    const std::size_t got = std::fread(head, 1, sizeof head, f);
    const bool png = got >= sizeof kPngMagic && std::memcmp(head, kPngMagic, sizeof kPngMagic) == 0;
    if (png && got == sizeof head && std::memcmp(head + 12, "IHDR", 4) == 0) {
      const std::uint32_t w = BigEndian32(head + 16), h = BigEndian32(head + 20);
      if (IsTooLarge(w, h)) {
        std::fclose(f);
        return TooLarge("PNG", path, w, h);
      }
    }
    // Every PNG, also one whose first chunk is not IHDR (stb reads Apple's CgBI chunk
    // first: the fuzzer's fifth find in images allocated 2 GB behind one).
    if (png) {
      if (Status chunks = CheckPngChunks(f, path); !chunks.ok()) {
        std::fclose(f);
        return chunks;
      }
    }
    std::rewind(f);
  }
  int width = 0, height = 0, channels = 0;
  if (stbi_info_from_file(f, &width, &height, &channels) == 0) {
    const char* why = stbi_failure_reason();
    std::fclose(f);
    return Status::Error(StatusCode::kInvalidArgument,
                         "'%s' is not a PNG, binary PGM (P5) or binary PPM (P6) image (%s); "
                         "convert it, e.g. 'convert IN OUT.png'",
                         path, why != nullptr ? why : "unknown format");
  }
  if (IsTooLarge(width, height)) {  // a size stb found later than IHDR's usual place
    std::fclose(f);
    return TooLarge("image", path, width, height);
  }
  const bool grey = channels <= 2;
  const int want = grey ? 1 : 3;
  // stb reduces 16-bit PNGs to their high byte and drops alpha.
  std::unique_ptr<void, StbFree> decoded(stbi_load_from_file(f, &width, &height, &channels, want));
  std::fclose(f);
  if (!decoded) {
    const char* why = stbi_failure_reason();
    return Status::Error(StatusCode::kInvalidArgument, "cannot decode image '%s': %s", path,
                         why != nullptr ? why : "corrupt or truncated file");
  }
  SKYLOC_TRY_ASSIGN(OwnedImage image,
                    OwnedImage::Allocate(
                        width, height, grey ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24));
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                            static_cast<std::size_t>(want);
  std::memcpy(image.mutable_view().data, decoded.get(), count);
  return image;
}

namespace {

struct PngSink {
  std::FILE* file = nullptr;
  bool failed = false;
  int saved_errno = 0;
};

void WriteToSink(void* context, void* data, int size) {
  auto* sink = static_cast<PngSink*>(context);
  if (sink->failed || size <= 0)
    return;
  if (std::fwrite(data, 1, static_cast<std::size_t>(size), sink->file) !=
      static_cast<std::size_t>(size)) {
    sink->failed = true;
    sink->saved_errno = errno;
  }
}

}  // namespace

Status SavePng(const char* path, dsp::ImageView image) {
  if (image.empty())
    return Status::Error(StatusCode::kInvalidArgument, "cannot write an empty image to '%s'", path);
  // stb writes packed grey or RGB: convert BGR and YUYV into a temporary copy.
  int channels = 1;
  std::unique_ptr<std::uint8_t[]> converted;
  const std::uint8_t* pixels = image.data;
  int stride = static_cast<int>(image.stride);
  const std::size_t w = static_cast<std::size_t>(image.width);
  if (image.format == dsp::PixelFormat::kRgb24 || image.format == dsp::PixelFormat::kBgr24)
    channels = 3;
  if (image.format == dsp::PixelFormat::kBgr24 || image.format == dsp::PixelFormat::kYuyv) {
    const std::size_t row_bytes = w * static_cast<std::size_t>(channels);
    converted.reset(new (std::nothrow)
                        std::uint8_t[row_bytes * static_cast<std::size_t>(image.height)]);
    if (!converted)
      return Status::Error(StatusCode::kResourceExhausted, "no memory to convert '%s'", path);
    for (int y = 0; y < image.height; ++y) {
      const std::uint8_t* in = image.Row(y);
      std::uint8_t* out = converted.get() + row_bytes * static_cast<std::size_t>(y);
      for (std::size_t x = 0; x < w; ++x) {
        if (image.format == dsp::PixelFormat::kYuyv) {
          out[x] = in[2 * x];
        } else {
          out[3 * x + 0] = in[3 * x + 2];
          out[3 * x + 1] = in[3 * x + 1];
          out[3 * x + 2] = in[3 * x + 0];
        }
      }
    }
    pixels = converted.get();
    stride = static_cast<int>(row_bytes);
  }

  std::string temp = std::string(path) + ".XXXXXX";
  const int fd = mkstemp(temp.data());
  if (fd < 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot create a temporary file next to '%s'", path);
  }
  PngSink sink;
  sink.file = fdopen(fd, "wb");
  if (sink.file == nullptr) {
    const int saved = errno;
    close(fd);
    unlink(temp.c_str());
    return Status::FromErrno(saved, "cannot write '%s'", temp.c_str());
  }
  const int written = stbi_write_png_to_func(WriteToSink, &sink, image.width, image.height,
                                             channels, pixels, stride);
  if (!sink.failed && std::fflush(sink.file) != 0) {
    sink.failed = true;
    sink.saved_errno = errno;
  }
  if (!sink.failed && fsync(fileno(sink.file)) != 0) {
    sink.failed = true;
    sink.saved_errno = errno;
  }
  if (std::fclose(sink.file) != 0 && !sink.failed) {
    sink.failed = true;
    sink.saved_errno = errno;
  }
  if (written == 0 || sink.failed) {
    unlink(temp.c_str());
    if (sink.failed)
      return Status::FromErrno(sink.saved_errno, "cannot write PNG '%s'", path);
    return Status::Error(StatusCode::kInternal, "PNG encoder failed for '%s'", path);
  }
  // mkstemp creates 0600; give the image the usual permissions (umask applies).
  const mode_t mask = umask(0);
  umask(mask);
  chmod(temp.c_str(), 0666 & ~mask);  // a failure only leaves the file private
  if (std::rename(temp.c_str(), path) != 0) {
    const int saved = errno;
    unlink(temp.c_str());
    return Status::FromErrno(saved, "cannot rename '%s' to '%s'", temp.c_str(), path);
  }
  return Status::Ok();
}

}  // namespace skyloc::drivers
