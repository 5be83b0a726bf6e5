// RouteDbWriter: teach's side of the route database (route_db.h, docs/ROUTE_DB.md).
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "firmware/route_db.h"
#include "firmware/route_db_records.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/platform/crc32.h"
#include "skyloc/platform/regular_file.h"

namespace skyloc::firmware {
using namespace route_file;

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
  if (!strip.empty()) {
    // 4 bits a column (version 6): the lengths were checked above.
    (void)dsp::PackStrip(strip, {rec + kFixed + 2 * descriptor.size(),
                                 RouteDbStripBytes(kRouteDbVersion, strip.size())});
  }
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
