#include "firmware/route_db.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <vector>

#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/spherical_harmonics.h"
#include "skyloc/platform/bytes.h"
#include "skyloc/platform/crc32.h"
#include "skyloc/platform/regular_file.h"

namespace skyloc::firmware {

// The file is little-endian (StoreBytes/LoadBytes, platform/bytes.h).

namespace {

// A frame record's pose: six little-endian values of T, x, y, z (m), roll, pitch, yaw
// (deg): doubles in versions 1-4, zero when the camera did not know it, floats in version 5
// (docs/ROUTE_DB.md).
template <typename T>
drivers::Pose LoadPose(const std::uint8_t* p) {
  drivers::Pose pose;
  double* const fields[6] = {&pose.x_m,      &pose.y_m,       &pose.z_m,
                             &pose.roll_deg, &pose.pitch_deg, &pose.yaw_deg};
  for (std::size_t i = 0; i < 6; ++i)
    *fields[i] = static_cast<double>(LoadBytes<T>(p + sizeof(T) * i));
  return pose;
}

// Version 5: the pose as six floats. The pose is the camera's own (simulator, recorded
// dataset) and only grades a repeat against the route; a float keeps a metre coordinate
// within 0.5 mm up to 8 km from the origin and an angle within 4e-6 degree.
void StorePoseFloats(const drivers::Pose& pose, std::uint8_t* p) {
  const double values[6] = {pose.x_m,      pose.y_m,       pose.z_m,
                            pose.roll_deg, pose.pitch_deg, pose.yaw_deg};
  for (int i = 0; i < 6; ++i)
    StoreBytes<float>(p + 4 * i, static_cast<float>(values[i]));
}

constexpr char kMagic[8] = {'S', 'K', 'Y', 'L', 'O', 'C', 'R', 'T'};
constexpr std::uint32_t kChunkMagic = 0x4B4E4843u;  // "CHNK"
constexpr std::uint32_t kChunkFrames = 1;
constexpr std::uint32_t kChunkCommit = 2;
constexpr std::uint32_t kMaxDim = 1u << 16;
constexpr std::uint32_t kHasPose = 1u;

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

// Lens record flags (offset 12 of the record).
constexpr std::uint32_t kLensKnown = 1u;     // the record describes the lens
constexpr std::uint32_t kLensOcamHash = 2u;  // ocam_hash holds the OCamCalib polynomials' hash
constexpr std::size_t kLensCrcOffset = kRouteDbLensRecordBytes - 4;

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
constexpr std::size_t kStripCrcOffset = kRouteDbStripRecordBytes - 4;
void EncodeStripRecord(const RouteDbStrip& strip, std::uint8_t* h) {
  std::memset(h, 0, kRouteDbStripRecordBytes);
  StoreBytes<std::uint32_t>(h + 0, strip.columns);
  StoreBytes<std::uint32_t>(h + 4, strip.band_rows);
  StoreBytes<std::int32_t>(h + 8, strip.elevation_min_cdeg);
  StoreBytes<std::int32_t>(h + 12, strip.elevation_max_cdeg);
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

Status CheckSettings(const RouteDbSettings& file, const RouteDbSettings& want) {
  if (file.gravity_cap_cdeg != want.gravity_cap_cdeg ||
      file.gravity_cap_taper_cdeg != want.gravity_cap_taper_cdeg) {
    auto describe = [](const RouteDbSettings& s, char* text, std::size_t size) {
      if (s.gravity_cap_cdeg == kNoGravityCap)
        std::snprintf(text, size, "no gravity cap");
      else
        std::snprintf(text, size, "a gravity cap above %.2f deg", s.gravity_cap_cdeg / 100.0);
    };
    // Short: the Status message holds 240 characters and the caller prefixes the path.
    char in_file[48], wanted[48];
    describe(file, in_file, sizeof in_file);
    describe(want, wanted, sizeof wanted);
    return Status::Error(StatusCode::kFailedPrecondition,
                         "taught with %s, this configuration has %s (taper %.2f/%.2f deg): set "
                         "[attitude] as taught, or teach again",
                         in_file, wanted, file.gravity_cap_taper_cdeg / 100.0,
                         want.gravity_cap_taper_cdeg / 100.0);
  }
  if (file.normalisation != want.normalisation) {
    // By name, with the setting to change: the default changed from "none" to "unit_l2" on
    // 2026-11-26, so a route taught before meets a configuration that does not say which.
    const auto name = [](std::uint32_t n) {
      return n <= static_cast<std::uint32_t>(dsp::AmplitudeNormalisation::kUnitL2)
                 ? dsp::AmplitudeNormalisationName(static_cast<dsp::AmplitudeNormalisation>(n))
                 : "?";
    };
    return Status::Error(StatusCode::kFailedPrecondition,
                         "taught with [descriptor] normalisation = \"%s\" but this configuration "
                         "has \"%s\": set normalisation = \"%s\" to repeat this route, or "
                         "teach again",
                         name(file.normalisation), name(want.normalisation),
                         name(file.normalisation));
  }
  struct Field {
    const char* name;
    std::uint64_t in_file, wanted;
    const char* fix;
  };
  // Short enough to survive a long route path in a Status (240 characters): the fix first.
  constexpr const char* kRerun = "run with the configuration it was taught with, or teach again";
  // The grid's rings and longitudes come from [descriptor] grid; a route taught with the
  // defaults before 2026-11-26 was sampled on grid = "auto".
  constexpr const char* kGridFix =
      "set [descriptor] grid as taught (\"auto\" was the default before 2026-11-26), or teach "
      "again";
  const Field fields[] = {{"descriptor kind", file.descriptor_kind, want.descriptor_kind, kRerun},
                          {"[descriptor] bands", file.bands, want.bands, kRerun},
                          {"[descriptor] rings", file.rings, want.rings, kGridFix},
                          {"[descriptor] longitudes", file.longitudes, want.longitudes, kGridFix},
                          {"descriptor size", file.dim, want.dim, kRerun}};
  for (const Field& f : fields) {
    if (f.in_file != f.wanted) {
      return Status::Error(StatusCode::kFailedPrecondition,
                           "taught with %s = %llu but this configuration has %llu: %s", f.name,
                           static_cast<unsigned long long>(f.in_file),
                           static_cast<unsigned long long>(f.wanted), f.fix);
    }
  }
  // A route without strips, or a configuration without heading, loads: heading is then
  // off (the caller says so once). Two different strips would give a wrong heading.
  if (file.strip.columns != 0 && want.strip.columns != 0 && !(file.strip == want.strip)) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "taught with a %u-column horizon strip over %.2f..%.2f deg (%u rows), "
                         "this configuration has %u columns over %.2f..%.2f deg (%u rows): set "
                         "[heading] as taught, or teach again",
                         file.strip.columns, file.strip.elevation_min_cdeg / 100.0,
                         file.strip.elevation_max_cdeg / 100.0, file.strip.band_rows,
                         want.strip.columns, want.strip.elevation_min_cdeg / 100.0,
                         want.strip.elevation_max_cdeg / 100.0, want.strip.band_rows);
  }
  if (file.lens.known && want.lens.known)
    return CheckRouteDbLens(file.lens, want.lens);
  if (file.lens_hash != want.lens_hash) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "taught with lens hash %016llx, this configuration has %016llx; the "
                         "file is older than version 3 and stores no lens parameters: use the "
                         "camera file it was taught with, or teach again",
                         static_cast<unsigned long long>(file.lens_hash),
                         static_cast<unsigned long long>(want.lens_hash));
  }
  return Status::Ok();
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Loading

namespace {

// The header, the lens record and the strip record: the file's version and settings into
// `r`, each checked (checksums, sizes); the chunks are not read.
Status ParseRouteDbHeader(std::span<const std::uint8_t> bytes, RouteDbLoadReport* r) {
  const std::size_t size = bytes.size();
  const std::uint8_t* b = bytes.data();
  if (size < kRouteDbHeaderBytes) {
    return Status::Error(StatusCode::kDataLoss,
                         "%zu bytes, shorter than the %zu-byte header: truncated, or not a "
                         "route database",
                         size, kRouteDbHeaderBytes);
  }
  if (std::memcmp(b, kMagic, sizeof kMagic) != 0)
    return Status::Error(StatusCode::kInvalidArgument, "not a skyloc route database (no magic)");
  const std::uint32_t version = LoadBytes<std::uint32_t>(b + 8);
  if (version < 1 || version > kRouteDbVersion) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "route database version %u; this skyloc reads versions 1 to %u: %s",
                         version, kRouteDbVersion,
                         version > kRouteDbVersion ? "use the skyloc that taught it, or teach "
                                                     "the route again"
                                                   : "teach the route again");
  }
  const std::size_t data_offset = RouteDbDataOffset(version);
  if (!CrcMatches(LoadBytes<std::uint32_t>(b + 60), b, 60) ||
      LoadBytes<std::uint32_t>(b + 12) != data_offset) {
    return Status::Error(StatusCode::kDataLoss,
                         "header (offset 0): checksum mismatch, the file "
                         "is corrupt");
  }
  if (size < data_offset) {
    return Status::Error(StatusCode::kDataLoss,
                         "%zu bytes, shorter than the header and lens record (%zu bytes): "
                         "truncated",
                         size, data_offset);
  }
  const std::uint8_t* lens_record = b + kRouteDbHeaderBytes;
  if (version >= 3 && !CrcMatches(LoadBytes<std::uint32_t>(lens_record + kLensCrcOffset),
                                  lens_record, kLensCrcOffset)) {
    return Status::Error(StatusCode::kDataLoss,
                         "lens record (offset %zu): checksum mismatch, the file is corrupt",
                         kRouteDbHeaderBytes);
  }
  r->version = version;
  RouteDbSettings& s = r->settings;
  s.descriptor_kind = LoadBytes<std::uint32_t>(b + 16);
  s.bands = LoadBytes<std::uint32_t>(b + 20);
  s.rings = LoadBytes<std::uint32_t>(b + 24);
  s.longitudes = LoadBytes<std::uint32_t>(b + 28);
  s.dim = LoadBytes<std::uint32_t>(b + 32);
  s.normalisation = LoadBytes<std::uint32_t>(b + 36);
  s.lens_hash = LoadBytes<std::uint64_t>(b + 40);
  s.gravity_cap_cdeg = version >= 2 ? LoadBytes<std::uint32_t>(b + 52) : kNoGravityCap;
  s.gravity_cap_taper_cdeg = version >= 2 ? LoadBytes<std::uint32_t>(b + 56) : 0;
  if (version >= 3)
    s.lens = DecodeLensRecord(lens_record);
  if (version >= 4) {
    const std::uint8_t* strip_record = lens_record + kRouteDbLensRecordBytes;
    if (!CrcMatches(LoadBytes<std::uint32_t>(strip_record + kStripCrcOffset), strip_record,
                    kStripCrcOffset)) {
      return Status::Error(StatusCode::kDataLoss,
                           "strip record (offset %zu): checksum mismatch, the file is corrupt",
                           kRouteDbHeaderBytes + kRouteDbLensRecordBytes);
    }
    s.strip = DecodeStripRecord(strip_record);
    if (s.strip.columns > kMaxDim) {
      return Status::Error(StatusCode::kDataLoss, "strip record: %u strip columns is invalid",
                           s.strip.columns);
    }
  }
  if (s.dim == 0 || s.dim > kMaxDim ||
      LoadBytes<std::uint32_t>(b + 48) != RouteDbRecordBytes(version, s.dim, s.strip.columns)) {
    return Status::Error(StatusCode::kDataLoss,
                         "header (offset 0): descriptor size %u is "
                         "invalid",
                         s.dim);
  }
  return Status::Ok();
}

// A frames chunk's `count` records at `payload` appended to `out` (its strips when
// `keep_strips`); kResourceExhausted when `out` is full (`chunk` names the chunk). `codes`:
// room for a version-5 record's dim codes.
Status AppendRecords(const std::uint8_t* payload, std::uint32_t count, std::size_t record_bytes,
                     std::uint32_t version, std::uint32_t dim, bool keep_strips, std::size_t chunk,
                     std::span<std::uint16_t> codes, RouteFrames* out) {
  if (out->size() + count > out->capacity()) {
    return Status::Error(StatusCode::kResourceExhausted,
                         "the route has more than %zu frames (chunk %zu): raise [capacities] "
                         "route_frames",
                         out->capacity(), chunk);
  }
  const std::size_t fixed_bytes = RouteDbRecordFixedBytes(version);
  const std::size_t strip_at = fixed_bytes + RouteDbDescriptorValueBytes(version) * dim;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint8_t* rec = payload + std::size_t{i} * record_bytes;
    RouteFrameMeta meta;
    meta.timestamp_ns = LoadBytes<std::uint64_t>(rec);
    if (version >= 5) {
      if ((rec[8] & kHasPose) != 0)
        meta.pose = LoadPose<float>(rec + 10);
    } else if ((LoadBytes<std::uint32_t>(rec + 8) & kHasPose) != 0) {
      meta.pose = LoadPose<double>(rec + 16);
    }
    const RouteFrames::Slot slot = out->Emplace(meta, keep_strips);
    if (slot.descriptor.size() != dim)
      return Status::Error(StatusCode::kInternal, "route frames rejected a record");
    if (version >= 5) {
      // Decoded exactly (a code times a power of two); a matcher holding 16-bit codes
      // encodes the floats back to the same codes (dsp::EncodeCodes is idempotent).
      for (std::size_t k = 0; k < dim; ++k)
        codes[k] = LoadBytes<std::uint16_t>(rec + fixed_bytes + 2 * k);  // any alignment
      dsp::DecodeCodes(std::span<const std::uint16_t>(codes.data(), dim),
                       static_cast<std::int8_t>(rec[9]), slot.descriptor);
    } else {
      // Copied byte-wise: the input need not be aligned for float.
      std::memcpy(slot.descriptor.data(), rec + fixed_bytes, slot.descriptor.size_bytes());
    }
    if (keep_strips)
      std::memcpy(slot.strip.data(), rec + strip_at, slot.strip.size());
    if (Status added = out->Complete(slot); !added.ok()) {
      return Status::Error(added.code(), "route frame %zu: %s", out->size() - 1, added.message());
    }
  }
  return Status::Ok();
}

// After the chunks: what `policy` makes of damage (`problem`, found at `offset`), of bytes
// after the commit record and of a missing commit record; damage kept is counted in `r`.
Status CheckEndOfChunks(std::span<const std::uint8_t> bytes, const Status& problem,
                        std::size_t offset, RouteDbLoadPolicy policy, RouteDbLoadReport* r) {
  if (!problem.ok()) {
    // Damage followed by an intact chunk header is in the middle of the route: dropping
    // the tail would hide the frames after it, so only --salvage does that. Searched at
    // every byte: a version-5 record (34 + 2 dim + columns bytes) leaves chunks at any
    // alignment.
    std::size_t intact_after = 0;
    for (std::size_t o = offset + 1; o + kRouteDbChunkHeaderBytes <= bytes.size(); ++o) {
      if (ChunkHeaderIntact(bytes.data() + o)) {
        intact_after = o;
        break;
      }
    }
    if (intact_after != 0 && policy != RouteDbLoadPolicy::kSalvage) {
      // Short: the Status holds 240 characters and the caller puts the path in front.
      return Status::Error(StatusCode::kDataLoss,
                           "%s; intact data follows at offset %zu: damaged mid-file, not cut "
                           "short; 'route recover --salvage' keeps the %zu frames before it",
                           problem.message(), intact_after, r->frames);
    }
    if (policy == RouteDbLoadPolicy::kStrict)
      return problem;
    r->dropped_bytes = bytes.size() - r->valid_bytes;
    r->damaged_mid_file = intact_after != 0;
  } else if (r->trailing_bytes > 0 && policy == RouteDbLoadPolicy::kStrict) {
    return Status::Error(StatusCode::kDataLoss,
                         "%zu trailing bytes after the commit record at offset %zu: the %zu "
                         "frames are complete but something was appended; 'skyloc route "
                         "recover' cuts the trailing bytes off",
                         r->trailing_bytes, r->valid_bytes, r->frames);
  } else if (!r->committed && policy == RouteDbLoadPolicy::kStrict) {
    return Status::Error(StatusCode::kDataLoss,
                         "no commit record after chunk %zu (offset %zu): teach was interrupted "
                         "or the file truncated; 'skyloc route recover' keeps its %zu frames",
                         r->chunks, r->valid_bytes, r->frames);
  }
  return Status::Ok();
}

}  // namespace

Status ParseRouteDb(std::span<const std::uint8_t> bytes, const RouteDbSettings* expected,
                    RouteDbLoadPolicy policy, RouteFrames* out, RouteDbLoadReport* report) {
  RouteDbLoadReport r;
  SKYLOC_TRY(ParseRouteDbHeader(bytes, &r));
  const std::size_t size = bytes.size();
  const std::uint8_t* b = bytes.data();
  const RouteDbSettings& s = r.settings;
  const std::size_t data_offset = RouteDbDataOffset(r.version);
  if (expected != nullptr)
    SKYLOC_TRY(CheckSettings(s, *expected));
  if (out != nullptr) {
    if (out->dim() != s.dim) {
      return Status::Error(StatusCode::kFailedPrecondition,
                           "descriptor size %u, but memory was set up for %zu", s.dim, out->dim());
    }
    out->Clear();
  }
  // The strips are kept when memory has room for exactly these; a route or configuration
  // without them loads the descriptors only (CheckSettings refuses two different strips).
  const bool keep_strips =
      out != nullptr && s.strip.columns != 0 && out->strip_columns() == s.strip.columns;
  const std::uint32_t version = r.version;
  const std::size_t record_bytes = RouteDbRecordBytes(version, s.dim, s.strip.columns);
  std::vector<std::uint16_t> codes(version >= 5 ? s.dim : 0);  // a version-5 record's codes

  std::size_t offset = data_offset;
  std::size_t chunk = 0;  // 1-based number of the chunk being read, for messages
  Status problem;
  while (offset < size) {
    ++chunk;
    const std::size_t left = size - offset;
    const std::uint8_t* h = b + offset;
    if (left < kRouteDbChunkHeaderBytes) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: truncated header "
                              "(%zu of %zu bytes)",
                              chunk, offset, left, kRouteDbChunkHeaderBytes);
      break;
    }
    if (!ChunkHeaderIntact(h)) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: header checksum mismatch", chunk, offset);
      break;
    }
    const std::uint32_t type = LoadBytes<std::uint32_t>(h + 4);
    const std::uint64_t first = LoadBytes<std::uint64_t>(h + 8);
    const std::uint32_t count = LoadBytes<std::uint32_t>(h + 16);
    const std::uint32_t payload_bytes = LoadBytes<std::uint32_t>(h + 20);
    const std::uint32_t payload_crc = LoadBytes<std::uint32_t>(h + 24);
    if (first != r.frames) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: starts at frame "
                              "%llu, expected %zu",
                              chunk, offset, static_cast<unsigned long long>(first), r.frames);
      break;
    }
    if (type == kChunkCommit) {
      if (count != 0 || payload_bytes != 0) {
        problem = Status::Error(StatusCode::kDataLoss,
                                "chunk %zu at offset %zu: malformed commit record", chunk, offset);
        break;
      }
      offset += kRouteDbChunkHeaderBytes;
      r.committed = true;
      r.valid_bytes = offset;
      r.trailing_bytes = size - offset;
      break;
    }
    if (type != kChunkFrames || count == 0 ||
        static_cast<std::uint64_t>(payload_bytes) != std::uint64_t{count} * record_bytes) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: malformed (type %u, %u frames, %u bytes)",
                              chunk, offset, type, count, payload_bytes);
      break;
    }
    if (left - kRouteDbChunkHeaderBytes < payload_bytes) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: truncated (%zu of "
                              "%u payload bytes)",
                              chunk, offset, left - kRouteDbChunkHeaderBytes, payload_bytes);
      break;
    }
    const std::uint8_t* payload = h + kRouteDbChunkHeaderBytes;
    if (!CrcMatches(payload_crc, payload, payload_bytes)) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: checksum mismatch "
                              "(frames %zu..%zu)",
                              chunk, offset, r.frames, r.frames + count - 1);
      break;
    }
    if (out != nullptr)
      SKYLOC_TRY(AppendRecords(payload, count, record_bytes, version, s.dim, keep_strips, chunk,
                               codes, out));
    r.frames += count;
    ++r.chunks;
    offset += kRouteDbChunkHeaderBytes + payload_bytes;
    r.valid_bytes = offset;
  }
  if (r.valid_bytes == 0)
    r.valid_bytes = data_offset;

  SKYLOC_TRY(CheckEndOfChunks(bytes, problem, offset, policy, &r));
  if (report != nullptr)
    *report = r;
  return Status::Ok();
}

namespace {

Status ReadAll(const char* path, int fd, std::vector<std::uint8_t>* bytes) {
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    return Status::FromErrno(errno, "cannot stat %s", path);
  bytes->resize(static_cast<std::size_t>(st.st_size));
  std::size_t done = 0;
  while (done < bytes->size()) {
    const ssize_t n = ::read(fd, bytes->data() + done, bytes->size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      return Status::FromErrno(errno, "cannot read %s", path);
    if (n == 0)
      break;
    done += static_cast<std::size_t>(n);
  }
  bytes->resize(done);
  return Status::Ok();
}

Status ReadWholeFile(const char* path, std::vector<std::uint8_t>* bytes) {
  UniqueFd fd;
  SKYLOC_TRY(OpenRegularFile(path, O_RDONLY, "route database", &fd));
  return ReadAll(path, fd.get(), bytes);
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

}  // namespace

Status LoadRouteDb(const char* path, const RouteDbSettings* expected, RouteDbLoadPolicy policy,
                   RouteFrames* out, RouteDbLoadReport* report) {
  std::vector<std::uint8_t> bytes;
  SKYLOC_TRY(ReadWholeFile(path, &bytes));
  Status s = ParseRouteDb(bytes, expected, policy, out, report);
  if (!s.ok())
    s.AddContext("route database %s", path);
  return s;
}

Status RecoverRouteDb(const char* path, RouteDbLoadReport* report, bool salvage) {
  UniqueFd fd;
  SKYLOC_TRY(OpenRegularFile(path, O_RDWR, "route database", &fd));
  // A running teach holds this lock while it writes: recovering under it would cut the
  // chunk it is appending.
  if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    if (e == EWOULDBLOCK)
      return Status::Error(StatusCode::kUnavailable,
                           "%s is being written by a running teach (it holds the file's lock): "
                           "stop that teach (SIGINT commits it) instead of recovering",
                           path);
    return Status::FromErrno(e, "cannot lock %s", path);
  }
  std::vector<std::uint8_t> bytes;
  SKYLOC_TRY(ReadAll(path, fd.get(), &bytes));
  RouteDbLoadReport r;
  Status s = ParseRouteDb(
      bytes, nullptr,
      salvage ? RouteDbLoadPolicy::kSalvage : RouteDbLoadPolicy::kRecoverInterrupted, nullptr, &r);
  if (!s.ok())
    return s.AddContext("route database %s", path);
  if (!r.committed && r.frames == 0) {
    return Status::Error(StatusCode::kDataLoss,
                         "route database %s: no intact frame to recover (%zu bytes after the "
                         "header are damaged or torn); the file is left as it was: teach the "
                         "route again",
                         path, r.dropped_bytes);
  }
  if (r.damaged_mid_file) {
    // Salvage drops intact data after the damage: keep the original beside it first.
    char copy[300];
    std::snprintf(copy, sizeof copy, "%s.damaged", path);
    UniqueFd out(::open(copy, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644));
    if (!out.is_valid())
      return Status::FromErrno(errno, "cannot keep the damaged original as %s (remove or move it)",
                               copy);
    if (Status w = WriteAll(out.get(), bytes.data(), bytes.size()); !w.ok())
      return w.AddContext("%s", copy);
    if (::fsync(out.get()) != 0)
      return Status::FromErrno(errno, "cannot sync %s", copy);
  }
  if (!r.committed || r.trailing_bytes > 0) {
    if (::ftruncate(fd.get(), static_cast<off_t>(r.valid_bytes)) != 0 ||
        ::lseek(fd.get(), 0, SEEK_END) < 0)
      return Status::FromErrno(errno, "cannot cut the torn tail of %s", path);
  }
  if (!r.committed) {
    std::uint8_t commit[kRouteDbChunkHeaderBytes];
    EncodeChunkHeader(kChunkCommit, r.frames, 0, 0, Crc32({}), commit);
    // Not SKYLOC_TRY(x.AddContext()): that binds a reference to a destroyed temporary.
    if (Status w = WriteAll(fd.get(), commit, sizeof commit); !w.ok())
      return w.AddContext("%s", path);
  }
  if ((!r.committed || r.trailing_bytes > 0) && ::fdatasync(fd.get()) != 0)
    return Status::FromErrno(errno, "cannot sync %s", path);
  if (report != nullptr)
    *report = r;
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------
// A teach's left-over FILE.db.tmp (the route's lock: route_lock.cpp)

RouteTmpReport InspectRouteTmp(const char* route_path) {
  RouteTmpReport r;
  char tmp[300];
  std::snprintf(tmp, sizeof tmp, "%s.tmp", route_path);
  struct stat st {};
  if (::lstat(tmp, &st) != 0)
    return r;
  r.exists = true;
  r.bytes = static_cast<std::uint64_t>(st.st_size);
  std::vector<std::uint8_t> bytes;
  if (!ReadWholeFile(tmp, &bytes).ok())
    return r;
  RouteDbLoadReport parsed;
  r.loads =
      ParseRouteDb(bytes, nullptr, RouteDbLoadPolicy::kRecoverInterrupted, nullptr, &parsed).ok();
  r.frames = r.loads ? parsed.frames : 0;
  return r;
}

// ---------------------------------------------------------------------------------------
// Writing

RouteDbWriter::~RouteDbWriter() = default;

Status RouteDbWriter::Create(const char* path, const RouteDbSettings& settings,
                             std::size_t flush_every, bool overwrite) {
  if (settings.dim == 0 || settings.dim > kMaxDim) {
    return Status::Error(StatusCode::kInvalidArgument, "descriptor size %u is not 1..%u",
                         settings.dim, kMaxDim);
  }
  if (flush_every == 0 || flush_every > (1u << 20))
    return Status::Error(StatusCode::kInvalidArgument, "flush_every %zu is invalid", flush_every);
  if (std::strlen(path) + 5 >= sizeof path_)
    return Status::Error(StatusCode::kInvalidArgument, "path too long: %s", path);
  // The lock first: what is at the path, and FILE.tmp, are looked at and changed only by
  // the one teach that holds it.
  SKYLOC_TRY(lock_.Acquire(path));
  Status created = CreateLocked(path, settings, flush_every, overwrite);
  if (!created.ok())
    lock_.Release();
  return created;
}

Status RouteDbWriter::CreateLocked(const char* path, const RouteDbSettings& settings,
                                   std::size_t flush_every, bool overwrite) {
  // An existing route is replaced only with `overwrite`, and only if it is a regular file:
  // a symlink, device node or FIFO at the path is not ours to replace.
  bool replacing = false;
  struct stat existing {};
  if (::lstat(path, &existing) == 0) {
    if (!S_ISREG(existing.st_mode)) {
      return Status::Error(StatusCode::kFailedPrecondition,
                           "%s is %s, not a route database file: teach does not replace it; "
                           "give --route the path of a regular file",
                           path, FileKindName(existing.st_mode));
    }
    if (!overwrite) {
      return Status::Error(StatusCode::kAlreadyExists,
                           "%s already exists: not replacing a taught route", path);
    }
    replacing = true;
  } else if (errno != ENOENT) {
    return Status::FromErrno(errno, "cannot check %s", path);
  }
  const std::size_t record_bytes =
      RouteDbRecordBytes(kRouteDbVersion, settings.dim, settings.strip.columns);
  SKYLOC_TRY(chunk_.Allocate(kRouteDbChunkHeaderBytes + flush_every * record_bytes));
  SKYLOC_TRY(codes_.Allocate(settings.dim));

  char tmp[sizeof write_path_];
  std::snprintf(tmp, sizeof tmp, "%s.tmp", path);
  // No teach holds the lock, so a FILE.tmp here was left by one that was killed: say what
  // it held before it is replaced.
  replaced_tmp_ = InspectRouteTmp(path);
  // A symlink or FIFO planted at FILE.tmp is refused, not followed or waited on.
  UniqueFd fd;
  SKYLOC_TRY(CreateRegularFile(tmp, O_WRONLY | O_TRUNC, 0644, "the teach's temporary file",
                               "remove it so a teach can write the route", &fd));
  // Held until the writer closes: `route recover` refuses the file meanwhile.
  if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0)
    return Status::FromErrno(errno, "cannot lock %s", tmp);
  std::uint8_t header[RouteDbDataOffset(kRouteDbVersion)];
  EncodeHeader(settings, header);
  if (Status w = WriteAll(fd.get(), header, sizeof header); !w.ok())
    return w.AddContext("%s", tmp);
  if (::fsync(fd.get()) != 0)
    return Status::FromErrno(errno, "cannot sync %s", tmp);
  if (!replacing) {
    // A new route: it appears under its name at once, so a crash leaves a recoverable
    // FILE.db. A route being replaced stays untouched until Commit() renames FILE.db.tmp
    // over it: a teach killed early must not cost the old route.
    if (::rename(tmp, path) != 0) {
      const int e = errno;
      ::unlink(tmp);
      return Status::FromErrno(e, "cannot rename %s to %s", tmp, path);
    }
    SKYLOC_TRY(SyncDirectoryOf(path));
  }

  fd_ = std::move(fd);
  committed_ = false;
  discarded_ = false;
  lost_ = 0;
  std::snprintf(path_, sizeof path_, "%s", path);
  std::snprintf(write_path_, sizeof write_path_, "%s", replacing ? tmp : path);
  replacing_ = replacing;
  settings_ = settings;
  flush_every_ = flush_every;
  pending_ = 0;
  appended_ = 0;
  durable_ = 0;
  return Status::Ok();
}

Status RouteDbWriter::Append(const RouteFrameMeta& meta, std::span<const float> descriptor,
                             std::span<const std::uint8_t> strip) {
  if (!fd_.is_valid())
    return Status::Error(StatusCode::kFailedPrecondition, "route database is not open");
  if (descriptor.size() != settings_.dim) {
    return Status::Error(StatusCode::kInvalidArgument, "descriptor has %zu values, expected %u",
                         descriptor.size(), settings_.dim);
  }
  if (strip.size() != settings_.strip.columns) {
    return Status::Error(StatusCode::kInvalidArgument, "horizon strip has %zu columns, expected %u",
                         strip.size(), settings_.strip.columns);
  }
  std::uint8_t* rec =
      chunk_.data() + kRouteDbChunkHeaderBytes +
      pending_ * RouteDbRecordBytes(kRouteDbVersion, settings_.dim, settings_.strip.columns);
  constexpr std::size_t kFixed = RouteDbRecordFixedBytes(kRouteDbVersion);
  std::memset(rec, 0, kFixed);
  StoreBytes<std::uint64_t>(rec, meta.timestamp_ns);
  rec[8] = meta.pose ? static_cast<std::uint8_t>(kHasPose) : std::uint8_t{0};
  if (meta.pose)
    StorePoseFloats(*meta.pose, rec + 10);
  const std::int8_t exponent = dsp::EncodeCodes(descriptor, codes_.span());
  for (std::size_t k = 0; k < descriptor.size(); ++k)
    StoreBytes<std::uint16_t>(rec + kFixed + 2 * k, codes_[k]);  // little-endian
  rec[9] = static_cast<std::uint8_t>(exponent);
  if (!strip.empty())
    std::memcpy(rec + kFixed + 2 * descriptor.size(), strip.data(), strip.size());
  ++pending_;
  ++appended_;
  if (pending_ == flush_every_)
    return Flush();
  return Status::Ok();
}

Status RouteDbWriter::WriteChunk(std::uint32_t type, std::uint64_t first, std::uint32_t count,
                                 std::size_t payload_bytes) {
  std::uint8_t* h = chunk_.data();
  const std::uint32_t crc = Crc32({h + kRouteDbChunkHeaderBytes, payload_bytes});
  EncodeChunkHeader(type, first, count, static_cast<std::uint32_t>(payload_bytes), crc, h);
  const off_t before = ::lseek(fd_.get(), 0, SEEK_CUR);
  Status s = WriteAll(fd_.get(), h, kRouteDbChunkHeaderBytes + payload_bytes);
  if (s.ok() && ::fdatasync(fd_.get()) != 0)
    s = Status::FromErrno(errno, "fdatasync failed");
  if (!s.ok()) {
    // Cut a partly written chunk off again, so that a later retry appends after intact
    // data (a torn chunk in the middle would make the file unloadable).
    if (before >= 0 && ::ftruncate(fd_.get(), before) == 0)
      (void)::lseek(fd_.get(), before, SEEK_SET);
    return s.AddContext("route database %s", write_path_);
  }
  return Status::Ok();
}

Status RouteDbWriter::Flush() {
  if (!fd_.is_valid())
    return Status::Error(StatusCode::kFailedPrecondition, "route database is not open");
  if (pending_ == 0)
    return Status::Ok();
  SKYLOC_TRY(WriteChunk(
      kChunkFrames, durable_, static_cast<std::uint32_t>(pending_),
      pending_ * RouteDbRecordBytes(kRouteDbVersion, settings_.dim, settings_.strip.columns)));
  durable_ += pending_;
  pending_ = 0;
  return Status::Ok();
}

Status RouteDbWriter::Commit() {
  if (!fd_.is_valid())
    return Status::Error(StatusCode::kFailedPrecondition, "route database is not open");
  // The last chunk may not fit (disk full, RLIMIT_FSIZE); WriteChunk has cut it off again.
  // The 32-byte commit record may still fit: commit the frames already on the disk.
  Status flushed = Flush();
  lost_ = pending_;
  pending_ = 0;
  if (durable_ == 0) {
    // Nothing taught is on the disk: an empty route would replace the old one, or block
    // the next teach of a new path. The file this writer made goes (under the lock).
    const int removed = ::unlink(write_path_);
    const int e = errno;
    fd_.reset();
    lock_.Release();
    discarded_ = true;
    if (removed != 0)
      return Status::FromErrno(e, "cannot remove %s (it holds no frame)", write_path_);
    return flushed;
  }
  if (Status c = WriteChunk(kChunkCommit, durable_, 0, 0); !c.ok()) {
    fd_.reset();  // closed uncommitted: `route recover` keeps the durable frames
    lock_.Release();
    return c;
  }
  committed_ = true;
  if (replacing_) {
    // The new route is complete and durable: now, atomically, it replaces the old one.
    if (::rename(write_path_, path_) != 0)
      return Status::FromErrno(errno, "cannot rename %s to %s (the new route is complete in %s)",
                               write_path_, path_, write_path_);
    SKYLOC_TRY(SyncDirectoryOf(path_));
    replacing_ = false;
  }
  fd_.reset();
  lock_.Release();
  return flushed;
}

}  // namespace skyloc::firmware
