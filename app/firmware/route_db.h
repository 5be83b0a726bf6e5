// The route database file: what `skyloc teach` records and `skyloc repeat` loads.
// Format and crash guarantees: docs/ROUTE_DB.md. In short: a versioned header with the
// descriptor settings, then chunks of frame records, each with a CRC32, then a commit
// record. Teach creates the file atomically (temp file + fsync + rename) and appends one
// chunk per flush followed by fdatasync, so a crash loses at most the frames since the
// last flush, and the loader finds every flushed frame intact.
//
// It lives in app/ beside the pipeline and the frame loop that teach and load it, and
// stores the camera's drivers::Pose as the camera reports it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "skyloc/drivers/camera.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/status.h"
#include "skyloc/platform/unique_fd.h"

namespace skyloc::firmware {

// The lens a route was taught with (version 3: the lens record after the header). Effective
// values: the centre and radius are what the lens used, never "unset". Numbers only; app/
// fills it from dsp::LensParams and dsp::Lens.
struct RouteDbLens {
  bool known = false;       // false: a version-1/2 file (only lens_hash), or not filled in
  std::uint32_t model = 0;  // dsp::LensModel's number (RouteDbLensModelName spells it)
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  double centre_x = 0, centre_y = 0, radius_px = 0;  // pixels
  double fov_deg = 0;
  double fx = 0, fy = 0;      // Kannala-Brandt focal lengths, pixels (0 for other models)
  std::array<double, 4> k{};  // Kannala-Brandt k1..k4
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0;  // camera-to-body mount
  // OCamCalib only: its polynomials (up to 2 x 32 terms), centre and affine part do not fit
  // a fixed record, so a hash of them is stored instead (0 for the other models).
  std::uint64_t ocam_hash = 0;

  bool operator==(const RouteDbLens&) const = default;
};

// Tolerances of CheckRouteDbLens: a lens written out to a camera file and read back
// compares equal to the one in memory.
inline constexpr double kRouteDbLensPixelTolerance = 0.01;     // centre, radius
inline constexpr double kRouteDbLensDegreeTolerance = 0.01;    // fov, mount angles
inline constexpr double kRouteDbLensRelativeTolerance = 1e-6;  // fx, fy, k1..k4

// "equidistant", "equisolid", "kannala_brandt", "ocamcalib", "equirectangular" (the
// camera-file spelling of dsp::LensModel), "unknown" otherwise.
const char* RouteDbLensModelName(std::uint32_t model);
// Compares the taught lens with the running one within the tolerances above. The error
// says in words what differs ("image size 320x240 vs 160x120", taught value first) and
// the fix.
Status CheckRouteDbLens(const RouteDbLens& taught, const RouteDbLens& now);
// One line for `route info`: "equidistant 320x240, centre 159.50 119.50 px, ...".
void FormatRouteDbLens(const RouteDbLens& lens, char* out, std::size_t size);

// The horizon strip stored with every frame (version 4) for the heading of a recognised
// place (docs/SURF1D.md): the band mean of each azimuth column rounded to 0..255, stored
// as a byte a column in versions 4 and 5 and at 4 bits a column from version 6
// (dsp::PackStrip; RouteDbStripBytes). columns = 0: no strips (every file before version
// 4, or a route taught with [heading] strip_columns = 0). Numbers only; app/ fills it from
// dsp::HorizonStripOptions. What the strip samples, not how it is stored: a route taught
// with 8-bit strips loads into any skyloc with the same band.
struct RouteDbStrip {
  std::uint32_t columns = 0;  // azimuth columns over 360 degrees; 0: none stored
  std::uint32_t band_rows = 0;
  std::int32_t elevation_min_cdeg = 0;  // band, hundredths of a degree above the horizon
  std::int32_t elevation_max_cdeg = 0;

  bool operator==(const RouteDbStrip&) const = default;
};

// What produced the descriptors; a route loads only into a pipeline with equal settings.
struct RouteDbSettings {
  std::uint32_t descriptor_kind = 0;
  std::uint32_t bands = 0;
  std::uint32_t rings = 0;
  std::uint32_t longitudes = 0;
  std::uint32_t dim = 0;  // floats per descriptor
  std::uint32_t normalisation = 0;
  // A hash of the lens parameters as configured (firmware::LensHash). Compared only when the
  // file is version 1 or 2 (no lens record); version 3 compares `lens` instead.
  std::uint64_t lens_hash = 0;
  RouteDbLens lens;  // version 3; when both sides know it, it replaces the hash check
  // The gravity-aligned cap the descriptors were computed with (version 2): its lower edge
  // and taper in hundredths of a degree, or kNoGravityCap (every version-1 file).
  std::uint32_t gravity_cap_cdeg = 0xffffffffu;
  std::uint32_t gravity_cap_taper_cdeg = 0;
  // Version 4. A file without strips loads into any configuration (heading is then off);
  // a file with strips must match the configuration's strip unless that has none.
  RouteDbStrip strip;

  bool operator==(const RouteDbSettings&) const = default;
};

struct RouteFrameMeta {
  std::uint64_t timestamp_ns = 0;
  std::optional<drivers::Pose> pose;  // when the camera knew it
};

// The pose as a version-5 route file and RouteFrames keep it: each value rounded to a
// float (a coordinate within 0.5 mm up to 8 km from the origin, an angle within 4e-6
// degree).
drivers::Pose RoutePoseFloats(const drivers::Pose& pose);

inline constexpr std::uint32_t kNoGravityCap = 0xffffffffu;
// Version 2 added the gravity cap (header offsets 52, 56, reserved and 0 in version 1).
// Version 3 added the lens record after the header. Version 4 added the strip record after
// the lens record and a horizon strip at the end of every frame record. Version 5 made the
// frame record compact: the descriptor as 16-bit codes with a power-of-two scale
// (dsp::EncodeCodes), the pose as floats. Version 6 stores the strip at 4 bits a column
// (dsp::PackStrip), its bits in the strip record. This version reads 1 to 6, writes 6.
inline constexpr std::uint32_t kRouteDbVersion = 6;
inline constexpr std::size_t kRouteDbHeaderBytes = 64;
inline constexpr std::size_t kRouteDbLensRecordBytes = 144;  // version 3, after the header
inline constexpr std::size_t kRouteDbStripRecordBytes = 32;  // version 4, after the lens
// Where the first chunk starts: after the header (versions 1, 2), the lens record (3) and
// the strip record (4 to 6).
constexpr std::size_t RouteDbDataOffset(std::uint32_t version) {
  return kRouteDbHeaderBytes + (version >= 3 ? kRouteDbLensRecordBytes : 0) +
         (version >= 4 ? kRouteDbStripRecordBytes : 0);
}
inline constexpr std::size_t kRouteDbChunkHeaderBytes = 32;
// The frame record's part before the descriptor: versions 1 to 4 a u64 timestamp, u32
// flags, u32 reserved and six f64 pose values; version 5 a u64 timestamp, u8 flags, the
// descriptor's i8 scale exponent and six f32 pose values (and version 6).
constexpr std::size_t RouteDbRecordFixedBytes(std::uint32_t version) {
  return version >= 5 ? 34 : 64;
}
// Bytes per descriptor value: f32 before version 5, a 16-bit code from version 5 (8-bit
// codes lost accuracy: docs/ROUTE_DB.md).
constexpr std::size_t RouteDbDescriptorValueBytes(std::uint32_t version) {
  return version >= 5 ? 2 : 4;
}
// Bits a strip column takes in a frame record: a byte in versions 4 and 5, 4 bits from
// version 6 (the heading experiment lost nothing: docs/RESULTS.md, "Heading").
constexpr std::uint32_t RouteDbStripBits(std::uint32_t version) {
  return version >= 6 ? 4 : 8;
}
// A frame record's strip: strip_columns bytes in versions 4 and 5, from version 6
// dsp::PackedStripBytes(strip_columns) (a byte minimum, a byte range, then 4 bits a
// column); nothing without strips.
constexpr std::size_t RouteDbStripBytes(std::uint32_t version, std::size_t strip_columns) {
  if (strip_columns == 0 || RouteDbStripBits(version) == 8)
    return strip_columns;
  return dsp::PackedStripBytes(strip_columns);
}
// A frame record: the fixed part, the descriptor, then the strip (version 4+).
constexpr std::size_t RouteDbRecordBytes(std::uint32_t version, std::size_t dim,
                                         std::size_t strip_columns) {
  return RouteDbRecordFixedBytes(version) + RouteDbDescriptorValueBytes(version) * dim +
         RouteDbStripBytes(version, strip_columns);
}

// Where a route's descriptors and strips go when RouteFrames does not keep them: the
// firmware's pipeline (its matcher and its heading), so the route is in memory once, the
// descriptors at the matcher's configured storage type (float32 or bfloat16), not also
// as floats here. RouteFrames then keeps only each frame's time and pose.
class RouteSink {
 public:
  virtual void BeginRoute() = 0;  // a route starts: forget the frames added before
  // strip: packed (dsp::PackStrip, as RouteFrames keeps it), empty when the route has none.
  virtual Status AddFrame(std::span<const float> descriptor,
                          std::span<const std::uint8_t> strip) = 0;

 protected:
  ~RouteSink() = default;
};

// The frames of a route in memory, at a capacity fixed at start-up. strip_columns: room
// for a horizon strip per frame (0: none), kept packed at 4 bits a column
// (dsp::PackStrip: dsp::PackedStripBytes(strip_columns) bytes a frame, whatever the file's
// version); has_strips() says whether the loaded route filled them (a file before version
// 4, or taught without strips, does not). With a sink, descriptors and strips are handed
// to it as they arrive and not kept: descriptor(i) and strip(i) are then empty.
class RouteFrames {
 public:
  Status Allocate(std::size_t capacity, std::size_t dim, std::size_t strip_columns = 0,
                  RouteSink* sink = nullptr);
  void Clear() {
    size_ = 0;
    has_strips_ = false;
    if (sink_ != nullptr)
      sink_->BeginRoute();
  }
  // False when full, or when `strip` (a byte a column, as dsp::StripToBytes gives it; kept
  // packed) is neither empty nor strip_columns() long. Every frame of a route has a strip
  // or none does: the first Append decides.
  [[nodiscard]] bool Append(const RouteFrameMeta& meta, std::span<const float> descriptor,
                            std::span<const std::uint8_t> strip = {});

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return timestamps_.size(); }
  std::size_t dim() const { return dim_; }
  std::size_t strip_columns() const { return strip_columns_; }
  bool has_strips() const { return has_strips_; }
  // The sink the descriptors went to; nullptr: they are kept here.
  const RouteSink* sink() const { return sink_; }
  std::span<const float> descriptor(std::size_t i) const {
    if (sink_ != nullptr)
      return {};
    return {descriptors_.data() + i * dim_, dim_};
  }
  // Frame i's horizon strip, packed (dsp::UnpackStrip reads it); empty when the route has
  // none.
  std::span<const std::uint8_t> strip(std::size_t i) const {
    if (!has_strips_ || sink_ != nullptr)
      return {};
    return {strips_.data() + i * strip_bytes_, strip_bytes_};
  }
  // Frame i's time and pose; the pose as the route file keeps it since version 5, in
  // floats (RoutePoseFloats).
  RouteFrameMeta meta(std::size_t i) const;

  // Adds a frame and returns its storage to fill in (the loader copies straight into it):
  // the descriptor, and the packed strip when `with_strip` (which the first frame decides
  // for the route). Empty spans when full or when with_strip disagrees with the route. Once
  // filled, Complete(slot) hands the descriptor to the sink, if there is one.
  struct Slot {
    std::span<float> descriptor;
    std::span<std::uint8_t> strip;
  };
  [[nodiscard]] Slot Emplace(const RouteFrameMeta& meta, bool with_strip);
  [[nodiscard]] Status Complete(const Slot& slot);

 private:
  RouteSink* sink_ = nullptr;
  FixedArray<float> descriptors_;    // capacity x dim; with a sink: one frame, to fill
  FixedArray<std::uint8_t> strips_;  // capacity x strip_bytes_; with a sink: one frame
  // Per frame 32 bytes, not a RouteFrameMeta's 64: the time, and the pose as six floats
  // (x NaN: no pose). A pose grades a repeat against the route and steers nothing.
  FixedArray<std::uint64_t> timestamps_;
  FixedArray<std::array<float, 6>> poses_;
  std::size_t dim_ = 0;
  std::size_t strip_columns_ = 0;
  std::size_t strip_bytes_ = 0;  // a packed strip's: dsp::PackedStripBytes(strip_columns_)
  std::size_t size_ = 0;
  bool has_strips_ = false;
};

enum class RouteDbLoadPolicy : std::uint8_t {
  // The file must end with its commit record and every chunk must verify.
  kStrict,
  // A file without a commit record (teach was interrupted) loads every intact chunk; a
  // damaged or incomplete tail is dropped and reported. Damage followed by an intact
  // chunk is still an error: that is corruption, not an interrupted write.
  kRecoverInterrupted,
  // Like kRecoverInterrupted, but damage in the middle of the file is accepted too: every
  // intact chunk before the first damage is kept, everything from the damage on is
  // dropped (`skyloc route recover --salvage`).
  kSalvage,
};

struct RouteDbLoadReport {
  RouteDbSettings settings;   // as stored in the file
  std::uint32_t version = 0;  // the file's format version
  // Bits a strip column takes in the file: 8 (versions 4, 5), 4 (version 6); 0: no strips.
  std::uint32_t strip_bits = 0;
  std::size_t frames = 0;
  std::size_t chunks = 0;  // intact frame chunks
  bool committed = false;
  std::size_t valid_bytes = 0;    // the intact prefix (header + chunks [+ commit])
  std::size_t dropped_bytes = 0;  // kRecoverInterrupted/kSalvage: bytes of the torn tail
  // kSalvage: the damage was in the middle (intact chunks followed it and were dropped).
  bool damaged_mid_file = false;
  // Bytes after a valid commit record (something appended to a complete route): the
  // route is committed; a strict load refuses the file, recovery cuts them off.
  std::size_t trailing_bytes = 0;
};

// Where ParseRouteDb reads a route's bytes: at any offset, so that loading a file needs
// no copy of it in memory (a 1,000,000-place route is 456 MB at the default settings;
// docs/ROUTE_DB.md, "A chunk at a time").
class RouteDbSource {
 public:
  virtual std::uint64_t size() const = 0;
  // Exactly out.size() bytes from `offset` (offset + out.size() <= size()), or an error
  // naming the offset: never fewer bytes.
  virtual Status Read(std::uint64_t offset, std::span<std::uint8_t> out) = 0;

 protected:
  ~RouteDbSource() = default;
};

// A route file read with pread. Its size is taken when it is opened: a file that ends
// before that size (cut while it was being read) and a read error are errors naming the
// offset (LoadRouteDb puts the path in front).
class RouteDbFile final : public RouteDbSource {
 public:
  // Opens `path` read-only; anything but a regular file is refused (OpenRegularFile).
  Status Open(const char* path);
  // Reads through `fd`, a regular file `path` names (recovery opens it read-write and
  // locks it first, so the size is taken under the lock).
  Status Attach(UniqueFd fd, const char* path);
  std::uint64_t size() const override { return size_; }
  Status Read(std::uint64_t offset, std::span<std::uint8_t> out) override;
  int fd() const { return fd_.get(); }

 private:
  UniqueFd fd_;
  std::uint64_t size_ = 0;
};

// The window in which the loader searches for an intact chunk header after damage
// (whether the damage is mid-file); windows overlap by a chunk header less a byte, so a
// header across an edge is found whole in the next one.
inline constexpr std::size_t kRouteDbScanWindowBytes = 16384;

// Parses a route file's bytes, the header and the lens and strip records once, then a
// chunk at a time into a buffer as large as the largest chunk (the loader, recovery and
// the fuzz target share this one parser). `expected` (may be null: accept what the file
// says) must equal the stored settings. On success `out` holds the frames; on error the
// Status names the chunk and its byte offset. A read error is returned as it is, whatever
// the policy: it is not damage to recover from.
Status ParseRouteDb(RouteDbSource& source, const RouteDbSettings* expected,
                    RouteDbLoadPolicy policy, RouteFrames* out, RouteDbLoadReport* report);
// The same on bytes in memory (the fuzz target and the tests).
Status ParseRouteDb(std::span<const std::uint8_t> bytes, const RouteDbSettings* expected,
                    RouteDbLoadPolicy policy, RouteFrames* out, RouteDbLoadReport* report);

// Reads and parses `path` chunk by chunk (RouteDbFile). Start-up only: it allocates a
// buffer as large as the file's largest chunk, not one as large as the file.
Status LoadRouteDb(const char* path, const RouteDbSettings* expected, RouteDbLoadPolicy policy,
                   RouteFrames* out, RouteDbLoadReport* report);

// Makes an interrupted file loadable strictly again: keeps the intact chunks, cuts the
// torn tail and appends the commit record; a committed file with trailing bytes loses
// them. Fails (changing nothing) if the file is corrupt in a way recovery must not hide
// (unless `salvage`: then the intact chunks before mid-file damage are kept, and the
// original is first copied to FILE.damaged), if no frame is intact, if the path is not a
// regular file, or if a running teach holds the file's lock.
Status RecoverRouteDb(const char* path, RouteDbLoadReport* report, bool salvage = false);

// The lock of the route at `route_path`: an OFD write lock (fcntl F_OFD_SETLK) on
// FILE.db.lock beside it. A teach takes it before it touches FILE.db or FILE.db.tmp and
// holds it until it has committed or closed them, so two teaches on one path never both
// write, and one that is refused has changed nothing. OFD locks belong to an open file
// description, so two writers in one process exclude each other as two processes do; the
// kernel drops the lock when its holder dies, so the lock file a killed teach leaves is
// taken over by the next one. The holder writes its process id into the file (for the
// refusal's message) and removes the file while it still holds the lock.
class RouteLock {
 public:
  static constexpr std::size_t kPathCapacity = 264;  // FILE.db.lock, its terminator included

  RouteLock() = default;
  ~RouteLock() { Release(); }
  RouteLock(const RouteLock&) = delete;
  RouteLock& operator=(const RouteLock&) = delete;

  // Without waiting: kUnavailable, naming the holder's process, when a teach holds it.
  Status Acquire(const char* route_path);
  void Release();
  bool held() const { return fd_.is_valid(); }

 private:
  UniqueFd fd_;
  char path_[kPathCapacity] = {};
};

// Whether a teach holds the lock of the route at `route_path` now, asked without taking
// it (F_OFD_GETLK). *pid: the holder's process id as it wrote it, 0 when unknown.
bool RouteBeingTaught(const char* route_path, long* pid);

// FILE.db.tmp: where `teach --force` writes until its commit renames it over FILE.db. One
// that exists while no teach holds the route's lock was left by a teach that was killed
// (its frames were never committed).
struct RouteTmpReport {
  bool exists = false;
  std::uint64_t bytes = 0;
  bool loads = false;      // its intact chunks parse (as `route recover` would keep them)
  std::size_t frames = 0;  // intact frames in it
};
// Reads FILE.db.tmp of the route at `route_path` (start-up only: as LoadRouteDb, a chunk at
// a time).
RouteTmpReport InspectRouteTmp(const char* route_path);

// Writes a route database during teach. Append() copies into a chunk buffer allocated by
// Create(); every `flush_every` frames the chunk is written with one write() and made
// durable with fdatasync(). Append() allocates nothing.
class RouteDbWriter {
 public:
  RouteDbWriter() = default;
  ~RouteDbWriter();  // Closes without committing: the file stays recoverable.
  RouteDbWriter(const RouteDbWriter&) = delete;
  RouteDbWriter& operator=(const RouteDbWriter&) = delete;

  // Takes the route's lock (RouteLock) before it touches any file: another teach of the
  // same path is refused with kUnavailable, changing nothing. Then creates `path`
  // atomically (path.tmp, fsync, rename, fsync of the directory). An existing file is kept
  // and reported unless `overwrite`; with it, the frames go to path.tmp and Commit()
  // renames that over the old route, so the old route stays whole until the new one is
  // committed. A path.tmp left by a killed teach is replaced, and replaced_tmp() says what
  // it held (the caller tells the user). A path that is a symlink, device node, FIFO or
  // directory is refused, `overwrite` or not. The open file also holds an exclusive
  // flock() until it is closed, so `route recover` refuses a file being taught.
  Status Create(const char* path, const RouteDbSettings& settings, std::size_t flush_every,
                bool overwrite);
  // `strip`: settings.strip.columns bytes (dsp::StripToBytes), empty when that is 0; stored
  // at 4 bits a column (dsp::PackStrip). The descriptor is stored as 16-bit codes
  // (dsp::EncodeCodes: values >= 0, each within max / 65535 of its code), the pose as
  // floats.
  Status Append(const RouteFrameMeta& meta, std::span<const float> descriptor,
                std::span<const std::uint8_t> strip = {});
  // Writes the buffered frames as one chunk and waits until they are on the disk.
  Status Flush();
  // Flush, append the commit record, sync, close. After this the writer is closed. When
  // the last chunk cannot be written (disk full), the commit record is still appended for
  // the frames already on the disk: the error is returned, committed() is true and
  // frames_lost() says how many frames did not fit. When even the commit record cannot
  // be written, committed() is false and `skyloc route recover` keeps frames_durable().
  // No frame on the disk (stopped before the first, or the disk full before the first
  // chunk): nothing is committed and the file this writer made is removed, so the path is
  // as it was: an old route stays, a new path stays free; discarded() is then true and the
  // error, if any, is why the frames did not reach the disk.
  Status Commit();
  bool committed() const { return committed_; }
  bool discarded() const { return discarded_; }
  // What Create() found at path.tmp and replaced (exists: false when there was none).
  const RouteTmpReport& replaced_tmp() const { return replaced_tmp_; }
  std::uint64_t frames_lost() const { return lost_; }

  bool is_open() const { return fd_.is_valid(); }
  // The file the frames go to: the route's path, or path.tmp while replacing a route.
  const char* write_path() const { return write_path_; }
  bool replacing() const { return replacing_; }
  std::uint64_t frames_appended() const { return appended_; }
  // Frames known to be on the disk.
  std::uint64_t frames_durable() const { return durable_; }

 private:
  Status WriteChunk(std::uint32_t type, std::uint64_t first, std::uint32_t count,
                    std::size_t payload_bytes);

  Status CreateLocked(const char* path, const RouteDbSettings& settings, std::size_t flush_every,
                      bool overwrite);

  RouteLock lock_;  // before fd_: released after the file is closed
  UniqueFd fd_;
  char path_[256] = {};
  char write_path_[264] = {};
  bool replacing_ = false;
  bool committed_ = false;
  bool discarded_ = false;
  RouteTmpReport replaced_tmp_;
  std::uint64_t lost_ = 0;
  RouteDbSettings settings_;
  FixedArray<std::uint8_t> chunk_;   // chunk header + flush_every records
  FixedArray<std::uint16_t> codes_;  // one descriptor's codes (format 5), before storing
  std::size_t flush_every_ = 0;
  std::size_t pending_ = 0;
  std::uint64_t appended_ = 0;
  std::uint64_t durable_ = 0;
};

}  // namespace skyloc::firmware
