// Same bits on every target (docs/ARCHITECTURE.md, "Same numbers on every machine"): a
// procedural world, a rendered frame and its sky descriptor hash to CRCs computed once on
// x86-64 and written here. The aarch64 and armhf builds run this same test under
// qemu-user, so a target that builds another world, renders another pixel or rounds
// another amplitude fails it.
//
// It caught three causes: rng draws passed as the arguments of one call (evaluated right
// to left on x86-64, left to right on ARM: other worlds from one seed, an eighth of a frame's
// pixels different), Eigen's vectorised float sum in the amplitude spectrum (SSE on x86-64,
// scalar on armhf: amplitudes a bit apart) and the street's noise hash multiplying in
// armhf's 32-bit size_t.
//
// A deliberate change to the worlds, the renderer or the descriptor changes these values:
// print them on x86-64 (the failure message has them), paste them here, and see that the
// aarch64 and armhf runs pass with them.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "skyloc/dsp/imu.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/platform/bytes.h"
#include "skyloc/platform/crc32.h"
#include "skyloc/sim/renderer.h"
#include "skyloc/sim/street_source.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {
namespace {

// CRC of values' bit patterns, little-endian (no struct padding enters it).
class BitsCrc {
 public:
  void Add(float v) { Add(std::bit_cast<std::uint32_t>(v)); }
  void Add(std::uint32_t v) {
    std::uint8_t bytes[4];
    StoreBytes(bytes, v);
    crc_ = Crc32(bytes, crc_);
  }
  void Add(Vec3 v) {
    Add(v.x);
    Add(v.y);
    Add(v.z);
  }
  void Add(std::span<const std::uint8_t> bytes) { crc_ = Crc32(bytes, crc_); }
  std::uint32_t value() const { return crc_; }

 private:
  std::uint32_t crc_ = 0;
};

// Compared as text, so a failure prints the value in the form written here.
std::string Hex(std::uint32_t v) {
  char text[11];
  std::snprintf(text, sizeof text, "0x%08x", v);
  return text;
}

std::uint32_t WorldCrc(const World& world) {
  BitsCrc crc;
  for (const Triangle& t : world.triangles()) {
    crc.Add(t.a);
    crc.Add(t.b);
    crc.Add(t.c);
  }
  for (const Material& m : world.materials()) {
    crc.Add(m.r);
    crc.Add(m.g);
    crc.Add(m.b);
    crc.Add(m.uv);
    crc.Add(static_cast<std::uint32_t>(m.texture));
  }
  return crc.value();
}

TEST(SameBits, ProceduralWorlds) {
  struct Case {
    WorldKind kind;
    std::uint32_t crc;
  };
  const Case cases[] = {{WorldKind::kCity, 0xc4838d40u},
                        {WorldKind::kForest, 0x67093f75u},
                        {WorldKind::kRepetitive, 0x35f4e477u}};
  for (const Case& c : cases) {
    World world;
    ASSERT_TRUE(MakeProceduralWorld(c.kind, 1, &world).ok());
    EXPECT_EQ(Hex(WorldCrc(world)), Hex(c.crc))
        << WorldKindName(c.kind) << " seed 1: " << world.triangles().size()
        << " triangles; the value is x86-64's";
  }
}

// A 64x64 frame of the city at dawn (low sun in view: flare, clouds, sensor noise), tilted,
// in both spectra, and the 24- and 120-band descriptors of the UV frame, the last also with
// the gravity-aligned cap.
TEST(SameBits, RenderedFrameAndDescriptor) {
  World world;
  ASSERT_TRUE(MakeProceduralWorld(WorldKind::kCity, 1, &world).ok());
  const dsp::LensParams lens_params = DefaultSimLens(64, 64);
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, lens_params).ok());
  drivers::Pose pose;
  pose.x_m = -40;
  pose.y_m = -50;
  pose.z_m = 1;
  pose.yaw_deg = 10;
  pose.pitch_deg = 5;
  pose.roll_deg = -3;
  Lighting lighting;
  ASSERT_TRUE(LightingPreset("dawn", 1, &lighting));

  std::vector<std::uint8_t> uv(64 * 64);
  ASSERT_TRUE(renderer
                  .Render(pose, lighting, Spectrum::kUv, 7,
                          {uv.data(), 64, 64, 64, dsp::PixelFormat::kGrey8})
                  .ok());
  std::vector<std::uint8_t> visible(64 * 64 * 3);
  ASSERT_TRUE(renderer
                  .Render(pose, lighting, Spectrum::kVisible, 7,
                          {visible.data(), 64, 64, 64 * 3, dsp::PixelFormat::kRgb24})
                  .ok());
  EXPECT_EQ(Hex(Crc32(uv)), Hex(0xaecb58abu)) << "UV frame; the value is x86-64's";
  EXPECT_EQ(Hex(Crc32(visible)), Hex(0x35115fb8u)) << "visible frame; the value is x86-64's";

  dsp::Lens lens;
  ASSERT_EQ(lens.Init(lens_params), dsp::LensError::kOk);
  struct Case {
    int bands;
    bool cap;
    std::uint32_t coefficients_crc, amplitudes_crc;
  };
  // The gravity-aligned cap (10 degrees) at a 20-degree tilt, past its 12.5-degree limit:
  // the world-aligned table, its rotation, the bilinear read and the skyline fill.
  dsp::Attitude tilted;
  tilted.up = dsp::UpFromRollPitch(12.0, -16.0);
  const Case cases[] = {{24, false, 0x45408548u, 0x4f39b86du},
                        {120, false, 0xb58718f5u, 0x7ee1a8b9u},
                        {120, true, 0x492507d9u, 0x165cad19u}};
  for (const Case& c : cases) {
    dsp::SkyDescriptor descriptor;
    dsp::SkyDescriptorOptions options;
    options.bands = c.bands;
    options.cap.enabled = c.cap;
    options.cap.elevation_deg = 10;
    ASSERT_TRUE(descriptor.Init(lens, options).ok());
    std::vector<float> amplitudes(static_cast<std::size_t>(c.bands));
    ASSERT_TRUE(descriptor
                    .Compute({uv.data(), 64, 64, 64, dsp::PixelFormat::kGrey8}, amplitudes, nullptr,
                             c.cap ? &tilted : nullptr)
                    .ok());
    BitsCrc coefficients, spectrum;
    for (float v : descriptor.coefficients())
      coefficients.Add(v);
    for (float a : amplitudes)
      spectrum.Add(a);
    EXPECT_EQ(Hex(coefficients.value()), Hex(c.coefficients_crc))
        << c.bands << " bands" << (c.cap ? " with the cap" : "")
        << ": SH coefficients; the value is x86-64's";
    EXPECT_EQ(Hex(spectrum.value()), Hex(c.amplitudes_crc))
        << c.bands << " bands" << (c.cap ? " with the cap" : "")
        << ": amplitudes; the value is x86-64's";
  }
}

// The built-in street at its default 640x480, tilted and zig-zagging: frame 9 after a
// jittered drive. 640x480 has pixel indices past 2^32 / 0x9e37, where the noise hash's
// product once wrapped in armhf's 32-bit size_t.
TEST(SameBits, StreetFrame) {
  StreetOptions options;
  options.run_seed = 3;
  options.speed_jitter = 0.2;
  options.tilt_deg = 6;
  options.zigzag_deg = 15;
  StreetSource street(options);
  ASSERT_TRUE(street.Prepare(options.width, options.height, dsp::PixelFormat::kGrey8).ok());
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(options.width * options.height));
  ASSERT_TRUE(street
                  .Render(9,
                          {frame.data(), options.width, options.height,
                           static_cast<std::size_t>(options.width), dsp::PixelFormat::kGrey8},
                          nullptr)
                  .ok());
  EXPECT_EQ(Hex(Crc32(frame)), Hex(0xc244074du)) << "street frame; the value is x86-64's";
}

}  // namespace
}  // namespace skyloc::sim
