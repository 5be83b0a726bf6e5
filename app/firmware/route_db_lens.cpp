// The route's lens record in words: how a taught lens and today's differ (repeat refuses a
// route taught through another lens, naming what changed) and the record as `route info`
// prints it. The record's bytes are route_db.cpp's.
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <iterator>

#include "firmware/route_db.h"

namespace skyloc::firmware {

namespace {

struct LensDiff {
  // Whole items only, short enough that the fix and the caller's path still fit the
  // 240-character Status message; the rest is counted.
  static constexpr std::size_t kRoom = 100;
  char text[kRoom + 1] = {};
  std::size_t used = 0;
  int count = 0;
  int left_out = 0;
};

// Appends "; " and one difference if it fits whole, else counts it as left out.
[[gnu::format(printf, 2, 3)]] void AddLensDiff(LensDiff* d, const char* format, ...) {
  ++d->count;
  char item[96];
  std::va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(item, sizeof item, format, args);
  va_end(args);
  const std::size_t separator = d->used > 0 ? 2 : 0;
  if (n < 0 || d->used + separator + static_cast<std::size_t>(n) > LensDiff::kRoom) {
    ++d->left_out;
    return;
  }
  std::snprintf(d->text + d->used, sizeof d->text - d->used, "%s%s", separator > 0 ? "; " : "",
                item);
  d->used += separator + static_cast<std::size_t>(n);
}

}  // namespace

const char* RouteDbLensModelName(std::uint32_t model) {
  static constexpr const char* kNames[] = {"equidistant", "equisolid",       "kannala_brandt",
                                           "ocamcalib",   "equirectangular", "pinhole"};
  return model < std::size(kNames) ? kNames[model] : "unknown";
}

Status CheckRouteDbLens(const RouteDbLens& taught, const RouteDbLens& now) {
  // What differs, in words, taught value first; as much as fits the Status message.
  LensDiff d;
  auto near = [](double a, double b, double tolerance) {
    return std::fabs(a - b) <= tolerance;  // false for NaN
  };
  auto near_relative = [](double a, double b) {
    return std::fabs(a - b) <=
           kRouteDbLensRelativeTolerance * std::max(std::fabs(a), std::fabs(b)) + 1e-12;
  };
  if (taught.model != now.model)
    AddLensDiff(&d, "model %s vs %s", RouteDbLensModelName(taught.model),
                RouteDbLensModelName(now.model));
  if (taught.width != now.width || taught.height != now.height)
    AddLensDiff(&d, "image size %ux%u vs %ux%u", taught.width, taught.height, now.width,
                now.height);
  if (!near(taught.fov_deg, now.fov_deg, kRouteDbLensDegreeTolerance))
    AddLensDiff(&d, "fov %.2f vs %.2f degrees", taught.fov_deg, now.fov_deg);
  if (!near(taught.centre_x, now.centre_x, kRouteDbLensPixelTolerance))
    AddLensDiff(&d, "centre x %.2f vs %.2f px", taught.centre_x, now.centre_x);
  if (!near(taught.centre_y, now.centre_y, kRouteDbLensPixelTolerance))
    AddLensDiff(&d, "centre y %.2f vs %.2f px", taught.centre_y, now.centre_y);
  if (!near(taught.radius_px, now.radius_px, kRouteDbLensPixelTolerance))
    AddLensDiff(&d, "radius %.2f vs %.2f px", taught.radius_px, now.radius_px);
  if (!near_relative(taught.fx, now.fx) || !near_relative(taught.fy, now.fy))
    AddLensDiff(&d, "fx/fy %g/%g vs %g/%g px", taught.fx, taught.fy, now.fx, now.fy);
  for (std::size_t i = 0; i < taught.k.size(); ++i) {
    if (!near_relative(taught.k[i], now.k[i]))
      AddLensDiff(&d, "k%zu %g vs %g", i + 1, taught.k[i], now.k[i]);
  }
  if (taught.ocam_hash != now.ocam_hash)
    AddLensDiff(&d, "OCamCalib polynomials (hash %016llx vs %016llx)",
                static_cast<unsigned long long>(taught.ocam_hash),
                static_cast<unsigned long long>(now.ocam_hash));
  const double taught_mount[] = {taught.roll_deg, taught.pitch_deg, taught.yaw_deg};
  const double now_mount[] = {now.roll_deg, now.pitch_deg, now.yaw_deg};
  const char* mount_names[] = {"roll", "pitch", "yaw"};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!near(taught_mount[i], now_mount[i], kRouteDbLensDegreeTolerance))
      AddLensDiff(&d, "mount %s %.2f vs %.2f degrees", mount_names[i], taught_mount[i],
                  now_mount[i]);
  }
  if (d.count == 0)
    return Status::Ok();
  // Short: the Status holds 240 characters and the caller puts the path in front.
  return Status::Error(StatusCode::kFailedPrecondition,
                       "lens differs (taught vs now): %s%s: use the camera file it was taught "
                       "with, or teach again",
                       d.text, d.left_out > 0 ? "; and more" : "");
}

void FormatRouteDbLens(const RouteDbLens& l, char* out, std::size_t size) {
  if (!l.known) {
    std::snprintf(out, size, "not stored (format older than version 3: only the lens hash)");
    return;
  }
  const int n = std::snprintf(
      out, size,
      "%s %ux%u, fov %.2f degrees, centre %.2f %.2f px, radius %.2f px, mount roll %.2f "
      "pitch %.2f yaw %.2f degrees",
      RouteDbLensModelName(l.model), l.width, l.height, l.fov_deg, l.centre_x, l.centre_y,
      l.radius_px, l.roll_deg, l.pitch_deg, l.yaw_deg);
  if (n < 0 || static_cast<std::size_t>(n) >= size)
    return;
  const auto used = static_cast<std::size_t>(n);
  if (l.fx != 0 || l.fy != 0) {
    std::snprintf(out + used, size - used, ", fx %.6g fy %.6g, k %.6g %.6g %.6g %.6g", l.fx, l.fy,
                  l.k[0], l.k[1], l.k[2], l.k[3]);
  } else if (l.ocam_hash != 0) {
    std::snprintf(out + used, size - used, ", OCamCalib polynomials hash %016llx",
                  static_cast<unsigned long long>(l.ocam_hash));
  }
}

}  // namespace skyloc::firmware
