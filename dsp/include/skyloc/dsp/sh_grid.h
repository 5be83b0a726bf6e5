// The sampling grid for the spherical-harmonic transform: iso-latitude rings on the
// Gauss–Legendre nodes of the full sphere, equispaced longitudes on every ring.
//
// Rings on Gauss–Legendre nodes make the latitude integral of the transform exact for
// band-limited functions, and equispaced longitudes turn the longitude integral into one
// real FFT per ring (see spherical_harmonics.h). The camera sees the upper hemisphere only:
// the lower hemisphere is ground (value 0), contributes nothing, and is not sampled, so an
// upper-hemisphere grid holds only the rings with cos θ > 0 of a 2·rings-node rule.
//
// Coordinates (body frame): z is the zenith, θ the angle from the zenith (0..π), φ the
// longitude measured from the body x axis towards y, direction = (sinθ cosφ, sinθ sinφ, cosθ).
// Samples are ring-major: sample s = ring · longitudes + j, ring 0 nearest the zenith,
// φ_j = 2π j / longitudes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace skyloc::dsp {

// Errors of the SH configuration and calls (dsp/ has no Status; app/ turns these into one
// with ShErrorMessage()).
enum class ShError : std::uint8_t {
  kOk,
  kRingsOutOfRange,          // ShGridConfig::rings outside [1, kMaxShRings]
  kLongitudesOutOfRange,     // ShGridConfig::longitudes outside [4, kMaxShLongitudes]
  kLongitudesNotPowerOfTwo,  // the ring FFT needs a power of two (64, 128, 256, ...)
  kBandsOutOfRange,          // bands outside [1, kMaxShBands]
  kTableTooLarge,            // the naive projector's Y table would exceed its memory cap
  kNotInitialised,           // Init() was not called or failed
  kSizeMismatch,             // a span's size does not match the grid or the band count
};

// A fixed English sentence naming the problem and the fix, e.g. for a Status message.
const char* ShErrorMessage(ShError error);

inline constexpr int kMaxShRings = 1024;
inline constexpr int kMaxShLongitudes = 8192;
inline constexpr int kMaxShBands = 512;

enum class ShCoverage : std::uint8_t {
  kUpperHemisphere,  // the camera's view: rings with cos θ > 0 of a 2·rings-node rule
  kFullSphere,       // all nodes of a rings-node rule (tests, full-sphere references)
};

struct ShGridConfig {
  int rings = 60;        // rings sampled (upper hemisphere: half the Gauss–Legendre nodes)
  int longitudes = 256;  // per ring; a power of two (the ring FFT's length)
  ShCoverage coverage = ShCoverage::kUpperHemisphere;
};

ShError ValidateShGridConfig(const ShGridConfig& config);

// The default grid for `bands` bands (l = 0..bands-1) that does not alias: an exact
// quadrature of Y_lm·Y_l'm' for l, l' < bands needs ≥ bands full-sphere Gauss–Legendre nodes,
// i.e. ≥ ceil(bands/2) upper-hemisphere rings, and ≥ 2·bands - 1 longitudes (rounded up to a
// power of two for the FFT). bands = 120 gives 60 rings × 256 longitudes (15 360 samples).
// `bands` is clamped to [1, kMaxShBands].
ShGridConfig DefaultShGridConfig(int bands);

// The firmware's grid for `bands` bands: the unaliased grid for ceil(1.5 bands) bands (64
// bands: 48 rings x 256 longitudes; 120 bands: 90 x 512). Why more than the minimum: a sky mask
// has hard edges, so it is not band-limited, and on the minimal grid everything above the
// grid's limit folds back into the bands the descriptor keeps. The folded part depends on
// where the edges fall between samples, so it changes with a tilt, a yaw or a metre
// sideways when the place has not (test OversampledGridMovesLessWithAYawThanTheMinimalGrid).
// Measured (docs/SKY_DESCRIPTOR.md, "Grid"): on runs repeated with bumps, lateral wander and
// another speed, at 160x120, 320x240 and 640x480, 64 and 120 bands on this grid localised
// more frames, and more of their confident ones right, than on the minimal grid.
// `bands` is clamped to [1, kMaxShBands].
ShGridConfig OversampledShGridConfig(int bands);

// The paper's sampling density (Stone et al. 2016: 2000 points on the upper hemisphere, 120
// bands), laid out on our rings: 16 upper rings of a 32-node rule × 128 longitudes = 2048
// samples (ring spacing ~5.6°, 2.8° along the horizon). It resolves bands up to 32 only
// (exact for l + l' < 64 and m + m' < 128); with 120 bands everything above ~band 32-40
// aliases (the paper's own 2000 points cannot resolve more than ~band 40 however they are
// laid out: a band-L function has L² degrees of freedom). Kept to compare against the
// paper, never the default.
ShGridConfig PaperShGridConfig();

// True when the grid integrates Y_lm·Y_l'm' exactly for all l, l' < bands (no aliasing).
bool ShGridResolvesBands(const ShGridConfig& config, int bands);

// Gauss–Legendre nodes and weights on [-1, 1] for an n-point rule, nodes in descending
// order (x[0] nearest +1). Newton iteration on P_n from the Tricomi initial guess; nodes are
// accurate to ~1e-15 for n up to several thousand. Both spans must hold n values; returns
// false (and writes nothing) otherwise or when n < 1.
bool GaussLegendreNodes(int n, std::span<double> nodes, std::span<double> weights);

struct ShRing {
  double theta = 0;      // angle from the zenith, radians
  double cos_theta = 0;  // the Gauss–Legendre node
  double sin_theta = 0;
  // Quadrature weight of each sample on this ring: Gauss–Legendre weight × 2π/longitudes,
  // so that Σ over a full-sphere grid of all sample weights is 4π.
  double weight = 0;
};

struct ShDirection {
  double theta = 0;
  double phi = 0;
  double x = 0, y = 0, z = 0;  // unit vector, z = zenith
};

class ShGrid {
 public:
  // Computes the nodes and weights (allocates; call at start-up).
  ShError Init(const ShGridConfig& config);

  bool initialised() const { return !rings_.empty(); }
  const ShGridConfig& config() const { return config_; }
  int ring_count() const { return config_.rings; }
  int longitudes() const { return config_.longitudes; }
  std::size_t sample_count() const {
    return static_cast<std::size_t>(config_.rings) * static_cast<std::size_t>(config_.longitudes);
  }
  std::span<const ShRing> rings() const { return rings_; }
  const ShRing& ring(int i) const { return rings_[static_cast<std::size_t>(i)]; }
  // φ_j = 2π j / longitudes.
  double phi(int j) const;
  // The direction of sample s = ring · longitudes + j (for building a pixel lookup table).
  ShDirection direction(std::size_t sample) const;

 private:
  ShGridConfig config_;
  std::vector<ShRing> rings_;
};

}  // namespace skyloc::dsp
