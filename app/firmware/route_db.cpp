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
#include <utility>
#include <vector>

#include "firmware/route_db_records.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/spherical_harmonics.h"
#include "skyloc/platform/bytes.h"
#include "skyloc/platform/crc32.h"
#include "skyloc/platform/regular_file.h"

namespace skyloc::firmware {
using namespace route_file;

namespace {

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
    const char* fix;  // nullptr: set the key to the route's value (a setting of its own)
  };
  // Short enough to survive a long route path in a Status (240 characters): the fix first.
  constexpr const char* kRerun = "run with the configuration it was taught with, or teach again";
  // The grid's rings and longitudes come from [descriptor] grid; a route taught with the
  // defaults before 2026-11-26 was sampled on grid = "auto".
  constexpr const char* kGridFix =
      "set [descriptor] grid as taught (\"auto\" was the default before 2026-11-26), or teach "
      "again";
  // bands names the route's value in its fix: the default changed from 64 to 120 on
  // 2026-11-28, so a route taught before meets a configuration that does not say which.
  const Field fields[] = {{"descriptor kind", file.descriptor_kind, want.descriptor_kind, kRerun},
                          {"[descriptor] bands", file.bands, want.bands, nullptr},
                          {"[descriptor] rings", file.rings, want.rings, kGridFix},
                          {"[descriptor] longitudes", file.longitudes, want.longitudes, kGridFix},
                          {"descriptor size", file.dim, want.dim, kRerun}};
  for (const Field& f : fields) {
    if (f.in_file == f.wanted)
      continue;
    const auto in_file = static_cast<unsigned long long>(f.in_file);
    char set_as_taught[64];
    if (f.fix == nullptr)
      std::snprintf(set_as_taught, sizeof set_as_taught, "set %s = %llu or teach again", f.name,
                    in_file);
    return Status::Error(StatusCode::kFailedPrecondition,
                         "taught with %s = %llu but this configuration has %llu: %s", f.name,
                         in_file, static_cast<unsigned long long>(f.wanted),
                         f.fix != nullptr ? f.fix : set_as_taught);
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
// `r`, each checked (checksums, sizes); the chunks are not read. `head`: the file's first
// min(size, RouteDbDataOffset(kRouteDbVersion)) bytes, `size` the file's.
Status ParseRouteDbHeader(std::span<const std::uint8_t> head, std::size_t size,
                          RouteDbLoadReport* r) {
  const std::uint8_t* b = head.data();
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
    // Version 6 names its encoding; the versions before it had 0 there (a byte a column).
    const std::uint32_t bits =
        version >= 6 ? LoadBytes<std::uint32_t>(strip_record + kStripBitsOffset) : 8;
    if (bits != RouteDbStripBits(version)) {
      return Status::Error(StatusCode::kDataLoss,
                           "strip record: %u bits a strip column, version %u stores %u: the "
                           "file is corrupt",
                           bits, version, RouteDbStripBits(version));
    }
    r->strip_bits = s.strip.columns != 0 ? bits : 0;
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

// A frames chunk's `count` records at `payload` appended to `out` (its strips, packed,
// when `keep_strips`); kResourceExhausted when `out` is full (`chunk` names the chunk).
// `codes`: room for a version-5 or 6 record's dim codes.
Status AppendRecords(const std::uint8_t* payload, std::uint32_t count, std::size_t record_bytes,
                     std::uint32_t version, std::uint32_t dim, bool keep_strips, std::size_t chunk,
                     std::span<std::uint16_t> codes, RouteFrames* out) {
  const std::size_t strip_columns = out->strip_columns();
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
    if (keep_strips && RouteDbStripBits(version) == 8) {
      // A byte a column (versions 4, 5): packed as this skyloc keeps every strip, with the
      // loss the heading experiment measured for it (docs/ROUTE_DB.md, version 6).
      (void)dsp::PackStrip(std::span<const std::uint8_t>(rec + strip_at, strip_columns),
                           slot.strip);  // slot.strip is PackedStripBytes(strip_columns)
    } else if (keep_strips) {
      std::memcpy(slot.strip.data(), rec + strip_at, slot.strip.size());
    }
    if (Status added = out->Complete(slot); !added.ok()) {
      return Status::Error(added.code(), "route frame %zu: %s", out->size() - 1, added.message());
    }
  }
  return Status::Ok();
}

// The first offset at or after `from` where an intact chunk header starts, 0 when there
// is none. Searched at every byte: a version-5 record (34 + 2 dim + columns bytes) leaves
// chunks at any alignment. Read in windows of kRouteDbScanWindowBytes, each starting a
// chunk header less a byte before the end of the last, so every offset is tested once
// with a whole header's bytes; the window is allocated only here, after damage.
Status FindIntactChunkHeader(RouteDbSource& source, std::size_t size, std::size_t from,
                             std::size_t* found) {
  *found = 0;
  if (from > size || size - from < kRouteDbChunkHeaderBytes)
    return Status::Ok();
  FixedArray<std::uint8_t> window;
  SKYLOC_TRY(window.Allocate(std::min(kRouteDbScanWindowBytes, size - from)));
  for (std::size_t o = from; size - o >= kRouteDbChunkHeaderBytes;) {
    const std::size_t n = std::min(window.size(), size - o);  // >= a chunk header
    if (Status read = source.Read(o, {window.data(), n}); !read.ok())
      return read.AddContext("searching for intact data after damage");
    for (std::size_t i = 0; i + kRouteDbChunkHeaderBytes <= n; ++i) {
      if (ChunkHeaderIntact(window.data() + i)) {
        *found = o + i;
        return Status::Ok();
      }
    }
    o += n - (kRouteDbChunkHeaderBytes - 1);
  }
  return Status::Ok();
}

// After the chunks: what `policy` makes of damage (`problem`, found at `offset`), of bytes
// after the commit record and of a missing commit record; damage kept is counted in `r`.
Status CheckEndOfChunks(RouteDbSource& source, std::size_t size, const Status& problem,
                        std::size_t offset, RouteDbLoadPolicy policy, RouteDbLoadReport* r) {
  if (!problem.ok()) {
    // Damage followed by an intact chunk header is in the middle of the route: dropping
    // the tail would hide the frames after it, so only --salvage does that.
    std::size_t intact_after = 0;
    SKYLOC_TRY(FindIntactChunkHeader(source, size, offset + 1, &intact_after));
    if (intact_after != 0 && policy != RouteDbLoadPolicy::kSalvage) {
      // Short: the Status holds 240 characters and the caller puts the path in front.
      return Status::Error(StatusCode::kDataLoss,
                           "%s; intact data follows at offset %zu: damaged mid-file, not cut "
                           "short; 'route recover --salvage' keeps the %zu frames before it",
                           problem.message(), intact_after, r->frames);
    }
    if (policy == RouteDbLoadPolicy::kStrict)
      return problem;
    r->dropped_bytes = size - r->valid_bytes;
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

// Bytes in memory as a source (the fuzz target and the tests parse them).
class SpanSource final : public RouteDbSource {
 public:
  explicit SpanSource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint64_t size() const override { return bytes_.size(); }
  Status Read(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > bytes_.size() || bytes_.size() - offset < out.size()) {
      return Status::Error(StatusCode::kInternal, "read of %zu bytes at offset %llu past the end",
                           out.size(), static_cast<unsigned long long>(offset));
    }
    // An empty read may come with null pointers (an empty file's span), which memcpy must
    // not be given even for no bytes.
    if (!out.empty())
      std::memcpy(out.data(), bytes_.data() + offset, out.size());
    return Status::Ok();
  }

 private:
  std::span<const std::uint8_t> bytes_;
};

}  // namespace

Status ParseRouteDb(RouteDbSource& source, const RouteDbSettings* expected,
                    RouteDbLoadPolicy policy, RouteFrames* out, RouteDbLoadReport* report) {
  // Offsets and the report count in size_t: a file larger than this build addresses (4 GiB
  // on 32 bits) is refused here, so no offset is narrowed below.
  if (source.size() > std::numeric_limits<std::size_t>::max()) {
    return Status::Error(StatusCode::kResourceExhausted,
                         "%llu bytes, more than this build can address: load it on a 64-bit "
                         "build",
                         static_cast<unsigned long long>(source.size()));
  }
  const auto size = static_cast<std::size_t>(source.size());
  RouteDbLoadReport r;
  std::array<std::uint8_t, RouteDbDataOffset(kRouteDbVersion)> head{};
  const std::span<std::uint8_t> head_bytes(head.data(), std::min(size, head.size()));
  if (Status read = source.Read(0, head_bytes); !read.ok())
    return read.AddContext("header");
  SKYLOC_TRY(ParseRouteDbHeader(head_bytes, size, &r));
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
  // One chunk's payload at a time, in a buffer that grows to the largest chunk: the peak
  // memory of a load (docs/ROUTE_DB.md, "A chunk at a time").
  FixedArray<std::uint8_t> payload;

  std::size_t offset = data_offset;
  std::size_t chunk = 0;  // 1-based number of the chunk being read, for messages
  Status problem;
  while (offset < size) {
    ++chunk;
    const std::size_t left = size - offset;
    if (left < kRouteDbChunkHeaderBytes) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: truncated header "
                              "(%zu of %zu bytes)",
                              chunk, offset, left, kRouteDbChunkHeaderBytes);
      break;
    }
    std::uint8_t h[kRouteDbChunkHeaderBytes];
    if (Status read = source.Read(offset, h); !read.ok())
      return read.AddContext("chunk %zu at offset %zu", chunk, offset);
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
    // Before anything is allocated for it: a damaged header (in the fuzzing build, one
    // whose checksum is not compared) must not make the loader allocate more than the
    // file holds.
    if (left - kRouteDbChunkHeaderBytes < payload_bytes) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: truncated (%zu of "
                              "%u payload bytes)",
                              chunk, offset, left - kRouteDbChunkHeaderBytes, payload_bytes);
      break;
    }
    if (payload.size() < payload_bytes) {
      if (Status grown = payload.Allocate(payload_bytes); !grown.ok())
        return grown.AddContext("chunk %zu at offset %zu", chunk, offset);
    }
    if (Status read =
            source.Read(offset + kRouteDbChunkHeaderBytes, {payload.data(), payload_bytes});
        !read.ok())
      return read.AddContext("chunk %zu at offset %zu", chunk, offset);
    if (!CrcMatches(payload_crc, payload.data(), payload_bytes)) {
      problem = Status::Error(StatusCode::kDataLoss,
                              "chunk %zu at offset %zu: checksum mismatch "
                              "(frames %zu..%zu)",
                              chunk, offset, r.frames, r.frames + count - 1);
      break;
    }
    if (out != nullptr)
      SKYLOC_TRY(AppendRecords(payload.data(), count, record_bytes, version, s.dim, keep_strips,
                               chunk, codes, out));
    r.frames += count;
    ++r.chunks;
    offset += kRouteDbChunkHeaderBytes + payload_bytes;
    r.valid_bytes = offset;
  }
  if (r.valid_bytes == 0)
    r.valid_bytes = data_offset;

  SKYLOC_TRY(CheckEndOfChunks(source, size, problem, offset, policy, &r));
  if (report != nullptr)
    *report = r;
  return Status::Ok();
}

Status ParseRouteDb(std::span<const std::uint8_t> bytes, const RouteDbSettings* expected,
                    RouteDbLoadPolicy policy, RouteFrames* out, RouteDbLoadReport* report) {
  SpanSource source(bytes);
  return ParseRouteDb(source, expected, policy, out, report);
}

Status RouteDbFile::Open(const char* path) {
  UniqueFd fd;
  SKYLOC_TRY(OpenRegularFile(path, O_RDONLY, "route database", &fd));
  return Attach(std::move(fd), path);
}

Status RouteDbFile::Attach(UniqueFd fd, const char* path) {
  fd_ = std::move(fd);
  struct stat st {};
  if (::fstat(fd_.get(), &st) != 0) {
    const int e = errno;
    return Status::FromErrno(e, "cannot stat %s", path);
  }
  size_ = static_cast<std::uint64_t>(st.st_size);  // a regular file's: >= 0
  return Status::Ok();
}

Status RouteDbFile::Read(std::uint64_t offset, std::span<std::uint8_t> out) {
  std::size_t done = 0;
  while (done < out.size()) {
    // Within size_, which came from an off_t: the offset fits one.
    const auto at = static_cast<off_t>(offset + done);
    const ssize_t n = ::pread(fd_.get(), out.data() + done, out.size() - done, at);
    if (n < 0) {
      const int e = errno;
      if (e == EINTR)
        continue;
      return Status::FromErrno(e, "cannot read %zu bytes at offset %llu", out.size() - done,
                               static_cast<unsigned long long>(offset + done));
    }
    if (n == 0) {
      return Status::Error(StatusCode::kDataLoss,
                           "the file ends at offset %llu but had %llu bytes when opened: it was "
                           "cut while being read; load it again once nothing writes it",
                           static_cast<unsigned long long>(offset + done),
                           static_cast<unsigned long long>(size_));
    }
    done += static_cast<std::size_t>(n);
  }
  return Status::Ok();
}

Status LoadRouteDb(const char* path, const RouteDbSettings* expected, RouteDbLoadPolicy policy,
                   RouteFrames* out, RouteDbLoadReport* report) {
  RouteDbFile file;
  SKYLOC_TRY(file.Open(path));
  Status s = ParseRouteDb(file, expected, policy, out, report);
  if (!s.ok())
    s.AddContext("route database %s", path);
  return s;
}

namespace {

// The whole of `source` into fd, a window at a time (salvage's copy of the damaged
// original: as the load, without a buffer as large as the file).
Status CopyAll(RouteDbSource& source, int fd) {
  FixedArray<std::uint8_t> window;
  SKYLOC_TRY(window.Allocate(kRouteDbScanWindowBytes));
  for (std::uint64_t o = 0; o < source.size();) {
    const std::uint64_t left = source.size() - o;
    const std::size_t n =
        left < window.size() ? static_cast<std::size_t>(left) : window.size();  // fits: < window
    if (Status read = source.Read(o, {window.data(), n}); !read.ok())
      return read;
    SKYLOC_TRY(WriteAll(fd, window.data(), n));
    o += n;
  }
  return Status::Ok();
}

}  // namespace

Status RecoverRouteDb(const char* path, RouteDbLoadReport* report, bool salvage) {
  UniqueFd locked;
  SKYLOC_TRY(OpenRegularFile(path, O_RDWR, "route database", &locked));
  // A running teach holds this lock while it writes: recovering under it would cut the
  // chunk it is appending.
  if (::flock(locked.get(), LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    if (e == EWOULDBLOCK)
      return Status::Error(StatusCode::kUnavailable,
                           "%s is being written by a running teach (it holds the file's lock): "
                           "stop that teach (SIGINT commits it) instead of recovering",
                           path);
    return Status::FromErrno(e, "cannot lock %s", path);
  }
  RouteDbFile file;
  SKYLOC_TRY(file.Attach(std::move(locked), path));
  const int fd = file.fd();
  RouteDbLoadReport r;
  Status s = ParseRouteDb(
      file, nullptr, salvage ? RouteDbLoadPolicy::kSalvage : RouteDbLoadPolicy::kRecoverInterrupted,
      nullptr, &r);
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
    if (!out.is_valid()) {
      const int e = errno;
      return Status::FromErrno(e, "cannot keep the damaged original as %s (remove or move it)",
                               copy);
    }
    if (Status w = CopyAll(file, out.get()); !w.ok())
      return w.AddContext("copying %s to %s", path, copy);
    if (::fsync(out.get()) != 0) {
      const int e = errno;
      return Status::FromErrno(e, "cannot sync %s", copy);
    }
  }
  if (!r.committed || r.trailing_bytes > 0) {
    if (::ftruncate(fd, static_cast<off_t>(r.valid_bytes)) != 0 || ::lseek(fd, 0, SEEK_END) < 0)
      return Status::FromErrno(errno, "cannot cut the torn tail of %s", path);
  }
  if (!r.committed) {
    std::uint8_t commit[kRouteDbChunkHeaderBytes];
    EncodeChunkHeader(kChunkCommit, r.frames, 0, 0, Crc32({}), commit);
    // Not SKYLOC_TRY(x.AddContext()): that binds a reference to a destroyed temporary.
    if (Status w = WriteAll(fd, commit, sizeof commit); !w.ok())
      return w.AddContext("%s", path);
  }
  if ((!r.committed || r.trailing_bytes > 0) && ::fdatasync(fd) != 0)
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
  RouteDbFile file;
  if (!file.Open(tmp).ok())
    return r;
  RouteDbLoadReport parsed;
  r.loads =
      ParseRouteDb(file, nullptr, RouteDbLoadPolicy::kRecoverInterrupted, nullptr, &parsed).ok();
  r.frames = r.loads ? parsed.frames : 0;
  return r;
}

}  // namespace skyloc::firmware
