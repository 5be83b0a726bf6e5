// Test fixture for 'skyloc describe' (no binary images are committed):
//   describe_fixture generate DIR       writes the test images into DIR
//   describe_fixture compare FILE MAX   reads two JSON lines of 'describe --json' output and
//                                       exits 0 when their amplitudes differ by < MAX
//                                       (relative L2), 1 otherwise
//   describe_fixture differ FILE MIN    exits 0 when they differ by > MIN
//   describe_fixture bands FILE N       exits 0 when every line has N amplitudes
//
// The images are an analytic sky (a street canyon with a tree and a tower, so nothing is
// symmetric) drawn through an equidistant 185-degree fisheye with the circle touching the
// short side, its exact 90-degree pixel rotation, a different place, a colour 640x480
// version, an equirectangular panorama and a file that is not an image.
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/lens.h"

namespace {

using skyloc::drivers::OwnedImage;
using skyloc::dsp::PixelFormat;

constexpr double kDeg = std::numbers::pi / 180.0;

// Body-frame sky: open above two walls (different heights) along x, minus a tree cap and
// a tower; `narrow` makes a different place (higher walls, no tree).
bool Sky(const Eigen::Vector3d& d, bool narrow) {
  if (d(2) <= 0.0)
    return false;
  const double wall = d(1) > 0 ? (narrow ? 2.2 : 1.2) : (narrow ? 1.8 : 0.7);
  if (std::fabs(d(1)) * wall > d(2))
    return false;
  if (!narrow &&
      d.dot(Eigen::Vector3d(std::cos(35 * kDeg), 0.0, std::sin(35 * kDeg))) > std::cos(14 * kDeg))
    return false;
  const double azimuth = std::atan2(d(1), d(0));
  const double elevation = std::asin(d(2));
  return !(std::fabs(azimuth - 2.5) < 0.15 && elevation < 70 * kDeg);
}

OwnedImage Draw(int width, int height, PixelFormat format, bool narrow) {
  skyloc::dsp::LensParams p;
  p.width = width;
  p.height = height;
  p.fov_deg = 185.0;
  if (width == 2 * height)
    p.model = skyloc::dsp::LensModel::kEquirectangular;
  skyloc::dsp::Lens lens;
  if (lens.Init(p) != skyloc::dsp::LensError::kOk)
    std::abort();
  OwnedImage image = std::move(OwnedImage::Allocate(width, height, format)).value();
  const skyloc::dsp::MutableImageView v = image.mutable_view();
  Eigen::Vector3d ray;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      // Sky 200..230, ground 30..60 (a little texture), outside the circle black.
      const int texture = (x * 7 + y * 13) % 31;
      const int value = !lens.PixelToRay(x, y, &ray) ? 0
                        : Sky(ray, narrow)           ? 200 + texture
                                                     : 30 + texture;
      if (format == PixelFormat::kGrey8) {
        v.Row(y)[x] = static_cast<std::uint8_t>(value);
      } else {
        std::uint8_t* px = v.Row(y) + 3 * x;
        px[0] = static_cast<std::uint8_t>(value > 20 ? value - 20 : value);
        px[1] = static_cast<std::uint8_t>(value);
        px[2] = static_cast<std::uint8_t>(value > 20 ? value + 20 : value);
      }
    }
  }
  return image;
}

// Exact 90-degree rotation of a square grey image: out(x, y) = in(y, N-1-x).
OwnedImage Rotate90(const OwnedImage& in) {
  const int n = in.width();
  OwnedImage out = std::move(OwnedImage::Allocate(n, n, PixelFormat::kGrey8)).value();
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      out.mutable_view().Row(y)[x] = in.view().Row(n - 1 - x)[y];
  return out;
}

bool Save(const std::string& path, const OwnedImage& image) {
  const skyloc::Status s = skyloc::drivers::SavePng(path.c_str(), image.view());
  if (!s.ok())
    std::fprintf(stderr, "%s\n", s.message());
  return s.ok();
}

std::vector<double> Amplitudes(const std::string& line) {
  std::vector<double> a;
  const std::size_t start = line.find("\"amplitudes\":[");
  if (start == std::string::npos)
    return a;
  std::istringstream in(line.substr(start + 14));
  double v;
  char sep;
  while (in >> v) {
    a.push_back(v);
    if (!(in >> sep) || sep != ',')
      break;
  }
  return a;
}

int CompareFile(const char* file, double bound, bool want_close) {
  std::ifstream in(file);
  std::string l1, l2;
  std::getline(in, l1);
  std::getline(in, l2);
  const std::vector<double> a = Amplitudes(l1), b = Amplitudes(l2);
  if (a.empty() || a.size() != b.size()) {
    std::fprintf(stderr, "%s: expected two JSON lines with equal-length amplitudes\n", file);
    return 1;
  }
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff += (a[i] - b[i]) * (a[i] - b[i]);
    norm += a[i] * a[i];
  }
  const double rel = std::sqrt(diff / norm);
  std::printf("relative L2 difference %.6f (%s %.6f)\n", rel,
              want_close ? "must be <" : "must be >", bound);
  return (want_close ? rel < bound : rel > bound) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "generate") == 0) {
    const std::string dir = argv[2];
    const OwnedImage sky = Draw(480, 480, PixelFormat::kGrey8, false);
    bool ok = Save(dir + "/sky.png", sky) && Save(dir + "/sky_rot90.png", Rotate90(sky)) &&
              Save(dir + "/other_place.png", Draw(480, 480, PixelFormat::kGrey8, true)) &&
              Save(dir + "/sky_640x480_rgb.png", Draw(640, 480, PixelFormat::kRgb24, false)) &&
              Save(dir + "/panorama.png", Draw(720, 360, PixelFormat::kGrey8, false));
    std::ofstream(dir + "/not_an_image.png") << "this is text, not a PNG\n";
    // A FIFO where an image is expected: describe must refuse it, not wait on it.
    const std::string fifo = dir + "/fifo.png";
    if (::access(fifo.c_str(), F_OK) != 0 && ::mkfifo(fifo.c_str(), 0600) != 0)
      ok = false;
    return ok ? 0 : 1;
  }
  if (argc == 4 && std::strcmp(argv[1], "bands") == 0) {
    std::ifstream in(argv[2]);
    std::string line;
    int lines = 0;
    while (std::getline(in, line)) {
      ++lines;
      if (Amplitudes(line).size() != static_cast<std::size_t>(std::atoi(argv[3]))) {
        std::fprintf(stderr, "line %d has %zu amplitudes, not %s\n", lines, Amplitudes(line).size(),
                     argv[3]);
        return 1;
      }
    }
    return lines > 0 ? 0 : 1;
  }
  if (argc == 4 && (std::strcmp(argv[1], "compare") == 0 || std::strcmp(argv[1], "differ") == 0))
    return CompareFile(argv[2], std::atof(argv[3]), std::strcmp(argv[1], "compare") == 0);
  std::fprintf(stderr, "usage: describe_fixture generate DIR | compare|differ|bands FILE BOUND\n");
  return 2;
}
