// The route database file's records and durable writes, shared by its reader and
// recovery (route_db.cpp) and its writer (route_db_writer.cpp): the constants and
// the encoders and decoders of the header, lens, strip and chunk-header records with their
// CRC32 checks, a frame record's pose, and writing bytes durably (docs/ROUTE_DB.md).
// Private to app/firmware/: the file's layout is route_db.h's RouteDb* sizes and these.
#pragma once

#include <cstddef>
#include <cstdint>

#include "firmware/route_db.h"
#include "skyloc/platform/bytes.h"
#include "skyloc/platform/status.h"

namespace skyloc::firmware::route_file {

// The file is little-endian (StoreBytes/LoadBytes, platform/bytes.h).

inline constexpr char kMagic[8] = {'S', 'K', 'Y', 'L', 'O', 'C', 'R', 'T'};
inline constexpr std::uint32_t kChunkMagic = 0x4B4E4843u;  // "CHNK"
inline constexpr std::uint32_t kChunkFrames = 1;
inline constexpr std::uint32_t kChunkCommit = 2;
inline constexpr std::uint32_t kMaxDim = 1u << 16;
inline constexpr std::uint32_t kHasPose = 1u;  // a frame record's flags: it holds a pose

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

// Version 5: the pose as six floats at p.
void StorePoseFloats(const drivers::Pose& pose, std::uint8_t* p);

std::uint32_t CrcOf(const std::uint8_t* p, std::size_t n);
// Whether `stored` is the CRC32 of the n bytes at p (always true in the fuzz build).
bool CrcMatches(std::uint32_t stored, const std::uint8_t* p, std::size_t n);

// Lens record flags (offset 12 of the record).
inline constexpr std::uint32_t kLensKnown = 1u;  // the record describes the lens
inline constexpr std::uint32_t kLensOcamHash =
    2u;  // ocam_hash holds the OCamCalib polynomials' hash
inline constexpr std::size_t kLensCrcOffset = kRouteDbLensRecordBytes - 4;
inline constexpr std::size_t kStripCrcOffset = kRouteDbStripRecordBytes - 4;
// The strip record's bits a column (version 6; reserved and 0 before, a byte a column).
inline constexpr std::size_t kStripBitsOffset = 16;

// The lens record (docs/ROUTE_DB.md): h points just after the 64-byte header.
void EncodeLensRecord(const RouteDbLens& l, std::uint8_t* h);
RouteDbLens DecodeLensRecord(const std::uint8_t* h);
// The strip record (version 4; version 6 adds the bits a column): h points just after the
// lens record.
void EncodeStripRecord(const RouteDbStrip& strip, std::uint8_t* h);
RouteDbStrip DecodeStripRecord(const std::uint8_t* h);
// The header of the current version with its lens and strip records:
// RouteDbDataOffset(kRouteDbVersion) bytes at h.
void EncodeHeader(const RouteDbSettings& s, std::uint8_t* h);
// A chunk's 32-byte header at h: its magic, type, first frame, count, payload size and
// CRC, and its own CRC.
void EncodeChunkHeader(std::uint32_t type, std::uint64_t first, std::uint32_t count,
                       std::uint32_t payload_bytes, std::uint32_t payload_crc, std::uint8_t* h);
bool ChunkHeaderIntact(const std::uint8_t* h);

// All n bytes at p written to fd (retried on EINTR).
Status WriteAll(int fd, const std::uint8_t* p, std::size_t n);
// fsync of the folder that holds `path`, so a rename or a new file in it is durable.
Status SyncDirectoryOf(const char* path);

}  // namespace skyloc::firmware::route_file
