#include "firmware/route_db_records.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iterator>

#include "skyloc/platform/crc32.h"
#include "skyloc/platform/unique_fd.h"

namespace skyloc::firmware::route_file {

// Version 5: the pose as six floats. The pose is the camera's own (simulator, recorded
// dataset) and only grades a repeat against the route; a float keeps a metre coordinate
// within 0.5 mm up to 8 km from the origin and an angle within 4e-6 degree.
void StorePoseFloats(const drivers::Pose& pose, std::uint8_t* p) {
  const double values[6] = {pose.x_m,      pose.y_m,       pose.z_m,
                            pose.roll_deg, pose.pitch_deg, pose.yaw_deg};
  for (int i = 0; i < 6; ++i)
    StoreBytes<float>(p + 4 * i, static_cast<float>(values[i]));
}

std::uint32_t CrcOf(const std::uint8_t* p, std::size_t n) {
  return Crc32(std::span<const std::uint8_t>(p, n));
}

// The fuzz target (tests/fuzz/route_db_fuzz.cpp) is built with this defined, so random
// mutations are not all stopped by the checksums and reach the parsing behind them.
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr bool kVerifyChecksums = false;
#else
constexpr bool kVerifyChecksums = true;
#endif
bool CrcMatches(std::uint32_t stored, const std::uint8_t* p, std::size_t n) {
  return !kVerifyChecksums || stored == CrcOf(p, n);
}

// The lens record (docs/ROUTE_DB.md): h points just after the 64-byte header.
void EncodeLensRecord(const RouteDbLens& l, std::uint8_t* h) {
  std::memset(h, 0, kRouteDbLensRecordBytes);
  if (l.known) {
    StoreBytes<std::uint32_t>(h + 0, l.model);
    StoreBytes<std::uint32_t>(h + 4, l.width);
    StoreBytes<std::uint32_t>(h + 8, l.height);
    StoreBytes<std::uint32_t>(h + 12, kLensKnown | (l.ocam_hash != 0 ? kLensOcamHash : 0u));
    const double values[] = {l.centre_x, l.centre_y,  l.radius_px, l.fov_deg, l.fx,
                             l.fy,       l.k[0],      l.k[1],      l.k[2],    l.k[3],
                             l.roll_deg, l.pitch_deg, l.yaw_deg};
    for (std::size_t i = 0; i < std::size(values); ++i)
      StoreBytes<double>(h + 16 + 8 * i, values[i]);
    StoreBytes<std::uint64_t>(h + 120, l.ocam_hash);
  }
  StoreBytes<std::uint32_t>(h + kLensCrcOffset, CrcOf(h, kLensCrcOffset));
}

RouteDbLens DecodeLensRecord(const std::uint8_t* h) {
  RouteDbLens l;
  const std::uint32_t flags = LoadBytes<std::uint32_t>(h + 12);
  if ((flags & kLensKnown) == 0)
    return l;
  l.known = true;
  l.model = LoadBytes<std::uint32_t>(h + 0);
  l.width = LoadBytes<std::uint32_t>(h + 4);
  l.height = LoadBytes<std::uint32_t>(h + 8);
  double* values[] = {&l.centre_x, &l.centre_y,  &l.radius_px, &l.fov_deg, &l.fx,
                      &l.fy,       &l.k[0],      &l.k[1],      &l.k[2],    &l.k[3],
                      &l.roll_deg, &l.pitch_deg, &l.yaw_deg};
  for (std::size_t i = 0; i < std::size(values); ++i)
    *values[i] = LoadBytes<double>(h + 16 + 8 * i);
  l.ocam_hash = (flags & kLensOcamHash) != 0 ? LoadBytes<std::uint64_t>(h + 120) : 0;
  return l;
}

// The strip record (version 4, docs/ROUTE_DB.md): h points just after the lens record.
void EncodeStripRecord(const RouteDbStrip& strip, std::uint8_t* h) {
  std::memset(h, 0, kRouteDbStripRecordBytes);
  StoreBytes<std::uint32_t>(h + 0, strip.columns);
  StoreBytes<std::uint32_t>(h + 4, strip.band_rows);
  StoreBytes<std::int32_t>(h + 8, strip.elevation_min_cdeg);
  StoreBytes<std::int32_t>(h + 12, strip.elevation_max_cdeg);
  StoreBytes<std::uint32_t>(h + kStripBitsOffset, RouteDbStripBits(kRouteDbVersion));
  StoreBytes<std::uint32_t>(h + kStripCrcOffset, CrcOf(h, kStripCrcOffset));
}

RouteDbStrip DecodeStripRecord(const std::uint8_t* h) {
  RouteDbStrip strip;
  strip.columns = LoadBytes<std::uint32_t>(h + 0);
  strip.band_rows = LoadBytes<std::uint32_t>(h + 4);
  strip.elevation_min_cdeg = LoadBytes<std::int32_t>(h + 8);
  strip.elevation_max_cdeg = LoadBytes<std::int32_t>(h + 12);
  return strip;
}

void EncodeHeader(const RouteDbSettings& s, std::uint8_t* h) {
  std::memset(h, 0, kRouteDbHeaderBytes);
  std::memcpy(h, kMagic, sizeof kMagic);
  StoreBytes<std::uint32_t>(h + 8, kRouteDbVersion);
  StoreBytes<std::uint32_t>(h + 12, static_cast<std::uint32_t>(RouteDbDataOffset(kRouteDbVersion)));
  StoreBytes<std::uint32_t>(h + 16, s.descriptor_kind);
  StoreBytes<std::uint32_t>(h + 20, s.bands);
  StoreBytes<std::uint32_t>(h + 24, s.rings);
  StoreBytes<std::uint32_t>(h + 28, s.longitudes);
  StoreBytes<std::uint32_t>(h + 32, s.dim);
  StoreBytes<std::uint32_t>(h + 36, s.normalisation);
  StoreBytes<std::uint64_t>(h + 40, s.lens_hash);
  StoreBytes<std::uint32_t>(h + 48, static_cast<std::uint32_t>(RouteDbRecordBytes(
                                        kRouteDbVersion, s.dim, s.strip.columns)));
  StoreBytes<std::uint32_t>(h + 52, s.gravity_cap_cdeg);
  StoreBytes<std::uint32_t>(h + 56, s.gravity_cap_taper_cdeg);
  StoreBytes<std::uint32_t>(h + 60, CrcOf(h, 60));
  EncodeLensRecord(s.lens, h + kRouteDbHeaderBytes);
  EncodeStripRecord(s.strip, h + kRouteDbHeaderBytes + kRouteDbLensRecordBytes);
}

void EncodeChunkHeader(std::uint32_t type, std::uint64_t first, std::uint32_t count,
                       std::uint32_t payload_bytes, std::uint32_t payload_crc, std::uint8_t* h) {
  StoreBytes<std::uint32_t>(h + 0, kChunkMagic);
  StoreBytes<std::uint32_t>(h + 4, type);
  StoreBytes<std::uint64_t>(h + 8, first);
  StoreBytes<std::uint32_t>(h + 16, count);
  StoreBytes<std::uint32_t>(h + 20, payload_bytes);
  StoreBytes<std::uint32_t>(h + 24, payload_crc);
  StoreBytes<std::uint32_t>(h + 28, CrcOf(h, 28));
}

bool ChunkHeaderIntact(const std::uint8_t* h) {
  return LoadBytes<std::uint32_t>(h) == kChunkMagic &&
         CrcMatches(LoadBytes<std::uint32_t>(h + 28), h, 28);
}

Status WriteAll(int fd, const std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR)
      continue;
    if (w < 0)
      return Status::FromErrno(errno, "write failed");
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return Status::Ok();
}

Status SyncDirectoryOf(const char* path) {
  char dir[256];
  std::snprintf(dir, sizeof dir, "%s", path);
  char* slash = std::strrchr(dir, '/');
  if (slash == nullptr) {
    std::snprintf(dir, sizeof dir, ".");
  } else if (slash == dir) {
    dir[1] = '\0';
  } else {
    *slash = '\0';
  }
  UniqueFd fd(::open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (!fd.is_valid() || ::fsync(fd.get()) != 0)
    return Status::FromErrno(errno, "cannot sync directory %s", dir);
  return Status::Ok();
}

}  // namespace skyloc::firmware::route_file
