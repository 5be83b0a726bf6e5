#include "skyloc/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "skyloc/drivers/dsp_status.h"
#include "skyloc/dsp/angles.h"
#include "skyloc/sim/random.h"

namespace skyloc::sim {
namespace {

constexpr float kFar = 20000.0f;  // metres: beyond any world

struct Rgb {
  float r = 0, g = 0, b = 0;
};
Rgb operator*(Rgb a, float s) {
  return {a.r * s, a.g * s, a.b * s};
}
Rgb operator+(Rgb a, Rgb b) {
  return {a.r + b.r, a.g + b.g, a.b + b.b};
}
Rgb Mix(Rgb a, Rgb b, float t) {
  return a * (1 - t) + b * t;
}

float Smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// The lattice index of a floored coordinate, defined for every float: converting one
// outside int32's range is undefined (x86-64 gives INT32_MIN, ARM saturates), and a ray
// grazing the ground plane hits it arbitrarily far away. Beyond +-2^30 (where the haze has
// long replaced the texture) every coordinate shares one lattice cell; NaN takes the lower.
std::int32_t LatticeIndex(float floored) {
  constexpr float kLimit = 1073741824.0f;  // 2^30: index + 1 cannot overflow
  if (!(floored > -kLimit))
    return -(1 << 30);
  if (!(floored < kLimit))
    return 1 << 30;
  return static_cast<std::int32_t>(floored);
}

// Value noise on an integer lattice, smoothly interpolated: clouds and surface textures.
float ValueNoise2(float x, float y, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const std::int32_t ix = LatticeIndex(fx), iy = LatticeIndex(fy);
  float tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const float a = HashToUnit(ix, iy, 0, seed), b = HashToUnit(ix + 1, iy, 0, seed);
  const float c = HashToUnit(ix, iy + 1, 0, seed), d = HashToUnit(ix + 1, iy + 1, 0, seed);
  return (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty;
}

float ValueNoise3(Vec3 p, std::uint32_t seed) {
  const float fz = std::floor(p.z);
  const std::int32_t iz = LatticeIndex(fz);
  const float tz = p.z - fz;
  const float lo = ValueNoise2(p.x, p.y, seed + static_cast<std::uint32_t>(iz) * 7919u);
  const float hi = ValueNoise2(p.x, p.y, seed + static_cast<std::uint32_t>(iz + 1) * 7919u);
  return lo + (hi - lo) * tz * tz * (3 - 2 * tz);
}

float Fract(float x) {
  return x - std::floor(x);
}

// Brightness multiplier of a surface pattern at world point p (normal n).
float TextureAt(Texture t, Vec3 p, Vec3 n) {
  switch (t) {
    case Texture::kPlain:
      return 1.0f;
    case Texture::kFoliage:
      return 0.55f + 0.8f * ValueNoise3(p * 3.0f, 11) * ValueNoise3(p * 0.7f, 12);
    case Texture::kBark:
      return 0.7f + 0.5f * ValueNoise2(std::atan2(n.y, n.x) * 6.0f, p.z * 0.8f, 13);
    case Texture::kFacade: {
      if (std::fabs(n.z) > 0.7f)
        return 0.8f + 0.2f * ValueNoise2(p.x, p.y, 14);  // flat roof
      const float along = Fract((p.x + p.y) / 3.2f);
      const float up = Fract(p.z / 3.0f);
      const bool window = along > 0.3f && along < 0.7f && up > 0.35f && up < 0.8f && p.z > 2.5f;
      return window ? 0.35f : 0.9f + 0.2f * ValueNoise3(p * 0.5f, 15);
    }
    case Texture::kConcrete:
      return 0.75f + 0.5f * ValueNoise3(p * 1.5f, 16) * ValueNoise3(p * 0.1f, 17);
    case Texture::kGrass:
      return 0.6f + 0.7f * ValueNoise2(p.x * 0.8f, p.y * 0.8f, 18) *
                        ValueNoise2(p.x * 0.07f, p.y * 0.07f, 19);
  }
  return 1.0f;
}

// Everything the shading needs that is fixed for one frame.
struct FrameLight {
  Vec3 sun;             // unit direction to the sun (world)
  bool sun_up = false;  // above the horizon and not hidden by overcast
  float cloud = 0;
  float sky = 1;   // sky brightness
  float gain = 1;  // exposure
  std::uint32_t cloud_seed = 0;
  // Flare, in pixels: sun position, image circle radius, ghost centres.
  bool flare_on = false;
  float flare = 0;
  float su = 0, sv = 0, radius = 1, axis_x = 1, axis_y = 0;
  float gx[3] = {}, gy[3] = {};
};

constexpr float kGhostRadius[3] = {0.05f, 0.1f, 0.16f};
constexpr float kGhostGain[3] = {0.5f, 0.3f, 0.25f};
constexpr float kGhostPosition[3] = {0.35f, 0.75f, 1.3f};  // along sun -> centre -> beyond

// Cloud density 0..1 in direction d (clouds on a layer 1 km up).
float CloudDensity(const FrameLight& fl, Vec3 d) {
  if (fl.cloud <= 0)
    return 0;
  const float z = std::max(d.z, 0.03f);
  const float x = d.x / z * 1000.0f, y = d.y / z * 1000.0f;
  const float n = 0.65f * ValueNoise2(x / 400.0f, y / 400.0f, fl.cloud_seed) +
                  0.35f * ValueNoise2(x / 120.0f, y / 120.0f, fl.cloud_seed + 1);
  const float edge = 1.0f - fl.cloud;
  return Smoothstep(edge - 0.12f, edge + 0.12f, n);
}

// Angle-based circumsolar brightening.
float SunGlow(const FrameLight& fl, Vec3 d, float width) {
  if (!fl.sun_up)
    return 0;
  const float c = std::clamp(Dot(d, fl.sun), -1.0f, 1.0f);
  return std::exp(-(1.0f - c) / width);
}

float UvSky(const FrameLight& fl, Vec3 d) {
  // UV skylight is nearly uniform (Rayleigh scattering ~ lambda^-4), slightly brighter
  // toward the horizon and the sun; clouds change it little, which is why UV segments well.
  const float clear = 0.7f * fl.sky * (0.88f + 0.12f * (1.0f - std::max(d.z, 0.0f))) +
                      0.3f * fl.sky * (1 - fl.cloud) * SunGlow(fl, d, 0.04f);
  const float density = CloudDensity(fl, d);
  return clear + (0.6f * fl.sky - clear) * density * 0.6f;
}

Rgb VisibleSky(const FrameLight& fl, Vec3 d) {
  const float up = std::max(d.z, 0.0f);
  const float t = (1 - up) * (1 - up) * (1 - up);
  Rgb sky = Mix(Rgb{0.16f, 0.32f, 0.75f}, Rgb{0.7f, 0.78f, 0.88f}, t) * fl.sky;
  sky = sky + Rgb{1.0f, 0.9f, 0.7f} * (0.5f * fl.sky * (1 - fl.cloud) * SunGlow(fl, d, 0.02f));
  const float density = CloudDensity(fl, d);
  if (density > 0) {
    const float n = ValueNoise2(d.x / std::max(d.z, 0.03f) * 12.0f,
                                d.y / std::max(d.z, 0.03f) * 12.0f, fl.cloud_seed + 2);
    const Rgb cloud = Rgb{0.85f, 0.85f, 0.88f} * (fl.sky * (0.7f + 0.4f * n));
    sky = Mix(sky, cloud, density);
  }
  if (fl.sun_up && Dot(d, fl.sun) > 0.99996f && density < 0.7f)  // the disc, 0.5 degrees
    sky = Rgb{30, 30, 28};
  return sky;
}

// Lens flare in the image around the sun: core bloom, halo, six streaks and ghost discs on
// the line through the image centre (Stone et al.'s failure case: it brightens ground).
float FlareAt(const FrameLight& fl, float u, float v) {
  const float dx = (u - fl.su) / fl.radius, dy = (v - fl.sv) / fl.radius;
  const float d2 = dx * dx + dy * dy;
  const float d = std::sqrt(d2);
  float f = 1.5f * std::exp(-d2 / 0.003f) + 0.45f * std::exp(-d / 0.1f);
  if (d > 1e-6f) {
    const float c = (dx * fl.axis_x + dy * fl.axis_y) / d;
    float s = std::fabs(4 * c * c * c - 3 * c);  // |cos 3a|: six spokes
    s *= s;
    s *= s;
    s *= s;
    s *= s;
    s *= s;  // ^32
    f += 0.5f * s * std::exp(-d / 0.35f);
  }
  for (int k = 0; k < 3; ++k) {
    const float gx = (u - fl.gx[k]) / fl.radius, gy = (v - fl.gy[k]) / fl.radius;
    const float r = std::sqrt(gx * gx + gy * gy);
    f += kGhostGain[k] * (1 - Smoothstep(kGhostRadius[k] * 0.7f, kGhostRadius[k], r));
  }
  return fl.flare * f;
}

std::uint8_t ToByte(float linear, float noise) {
  const float v = 255.0f * std::pow(std::max(linear, 0.0f), 1.0f / 2.2f) + noise;
  return static_cast<std::uint8_t>(std::clamp(v + 0.5f, 0.0f, 255.0f));
}

}  // namespace

const char* SpectrumName(Spectrum s) {
  return s == Spectrum::kUv ? "uv" : "visible";
}

dsp::LensParams DefaultSimLens(int width, int height) {
  dsp::LensParams p;
  p.model = dsp::LensModel::kEquidistant;
  p.width = width;
  p.height = height;
  p.fov_deg = 185.0;
  // The camera on the robot: camera x = body +y, camera y = body -x (image rows run
  // backwards), camera z = body +z. With the mount in the lens, the lens's body frame is the
  // robot's: the sky descriptor and an IMU share it (dsp/imu.h).
  p.yaw_deg = 90.0;
  return p;
}

bool LightingPreset(const char* name, std::uint64_t seed, Lighting* lighting) {
  Lighting l;
  l.seed = seed;
  if (std::strcmp(name, "noon") == 0) {
    l.sun_azimuth_deg = 160;
    l.sun_elevation_deg = 60;
    l.cloud_cover = 0.15;
    l.flare = 0.6;  // high sun: the flare sits mostly on sky
  } else if (std::strcmp(name, "dawn") == 0) {
    // Low sun in the field of view: the strongest flare, a dimmer sky.
    l.sun_azimuth_deg = 75;
    l.sun_elevation_deg = 8;
    l.cloud_cover = 0.25;
    l.sky_brightness = 0.6;
    l.exposure_ev = 0.5;
  } else if (std::strcmp(name, "overcast") == 0) {
    l.sun_azimuth_deg = 200;
    l.sun_elevation_deg = 35;
    l.cloud_cover = 1.0;
    l.sky_brightness = 0.55;
    l.exposure_ev = 0.6;
    l.noise_sigma = 3.0;
  } else {
    return false;
  }
  *lighting = l;
  return true;
}

Rotation BodyToWorld(const drivers::Pose& pose) {
  const double cy = std::cos(pose.yaw_deg * dsp::kDegToRad),
               sy = std::sin(pose.yaw_deg * dsp::kDegToRad);
  // Ry(-pitch): positive pitch lifts the nose.
  const double cp = std::cos(-pose.pitch_deg * dsp::kDegToRad);
  const double sp = std::sin(-pose.pitch_deg * dsp::kDegToRad);
  const double cr = std::cos(pose.roll_deg * dsp::kDegToRad),
               sr = std::sin(pose.roll_deg * dsp::kDegToRad);
  // Rz(yaw) * Ry(p) * Rx(roll)
  const double m[3][3] = {
      {cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
      {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
      {-sp, cp * sr, cp * cr},
  };
  Rotation r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      r.m[i][j] = static_cast<float>(m[i][j]);
  }
  return r;
}

Status Renderer::Init(const World* world, const dsp::LensParams& lens) {
  if (world == nullptr || world->bvh().node_count() == 0)
    return Status::Error(StatusCode::kFailedPrecondition, "renderer: the world is not built");
  if (lens.width < 8 || lens.height < 8 || lens.width > 8192 || lens.height > 8192) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "renderer: image size %dx%d is outside 8..8192 pixels a side", lens.width,
                         lens.height);
  }
  const dsp::LensError error = lens_.Init(lens);
  if (error != dsp::LensError::kOk)
    return drivers::DspStatus(error, "renderer");
  world_ = world;
  width_ = lens.width;
  height_ = lens.height;
  const auto n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  SKYLOC_TRY(rays_.Allocate(n));
  SKYLOC_TRY(inside_.Allocate(n));
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      const auto i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                     static_cast<std::size_t>(x);
      Eigen::Vector3d d;
      inside_[i] = lens_.PixelToRay(x, y, &d) ? 1 : 0;
      rays_[i] = inside_[i] ? Vec3{static_cast<float>(d.x()), static_cast<float>(d.y()),
                                   static_cast<float>(d.z())}
                            : Vec3{};
    }
  }
  return Status::Ok();
}

Status Renderer::CheckOutput(const dsp::MutableImageView& out, dsp::PixelFormat format) const {
  if (world_ == nullptr)
    return Status::Error(StatusCode::kFailedPrecondition, "renderer: Init() was not called");
  if (out.data == nullptr || out.width != width_ || out.height != height_ || out.format != format ||
      out.stride < static_cast<std::size_t>(out.width) *
                       static_cast<std::size_t>(dsp::BytesPerPixelTimes2(format) / 2)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "renderer: output must be a %dx%d %s image, got %dx%d %s", width_, height_,
                         dsp::PixelFormatName(format), out.width, out.height,
                         dsp::PixelFormatName(out.format));
  }
  return Status::Ok();
}

Status Renderer::Render(const drivers::Pose& pose, const Lighting& lighting, Spectrum spectrum,
                        std::uint64_t frame_seed, const dsp::MutableImageView& out) const {
  const bool uv = spectrum == Spectrum::kUv;
  SKYLOC_TRY(CheckOutput(out, uv ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24));
  const Rotation to_world = BodyToWorld(pose);  // the lens's rays are in the body frame
  const Vec3 origin{static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
                    static_cast<float>(pose.z_m)};
  const Bvh& bvh = world_->bvh();
  const auto triangles = world_->triangles();
  const auto materials = world_->materials();

  FrameLight fl;
  const double az = lighting.sun_azimuth_deg * dsp::kDegToRad;
  const double el = lighting.sun_elevation_deg * dsp::kDegToRad;
  fl.sun = Vec3{static_cast<float>(std::cos(el) * std::cos(az)),
                static_cast<float>(std::cos(el) * std::sin(az)), static_cast<float>(std::sin(el))};
  fl.cloud = static_cast<float>(std::clamp(lighting.cloud_cover, 0.0, 1.0));
  fl.sun_up = lighting.sun_elevation_deg > 0 && fl.cloud < 0.9f;
  fl.sky = static_cast<float>(lighting.sky_brightness);
  fl.gain = static_cast<float>(std::exp2(lighting.exposure_ev));
  fl.cloud_seed = static_cast<std::uint32_t>(lighting.seed * 2654435761u);
  // Flare only when the sun is in the field of view and nothing blocks it.
  if (fl.sun_up && lighting.flare > 0) {
    // body = to_world^T * world
    Vec3 cam;
    for (int i = 0; i < 3; ++i)
      cam[i] =
          to_world.m[0][i] * fl.sun.x + to_world.m[1][i] * fl.sun.y + to_world.m[2][i] * fl.sun.z;
    double su, sv;
    if (lens_.RayToPixel(Eigen::Vector3d(double{cam.x}, double{cam.y}, double{cam.z}), &su, &sv) &&
        !bvh.AnyHit({origin, fl.sun}, 1e-4f, kFar) && CloudDensity(fl, fl.sun) < 0.7f) {
      fl.flare_on = true;
      fl.flare = static_cast<float>(lighting.flare) * (1 - fl.cloud) * fl.sky * (uv ? 1.0f : 0.6f);
      fl.su = static_cast<float>(su);
      fl.sv = static_cast<float>(sv);
      fl.radius = static_cast<float>(lens_.radius_px());
      const float ax = fl.su - static_cast<float>(lens_.centre_x());
      const float ay = fl.sv - static_cast<float>(lens_.centre_y());
      const float an = std::sqrt(ax * ax + ay * ay);
      fl.axis_x = an > 1e-3f ? ax / an : 1.0f;
      fl.axis_y = an > 1e-3f ? ay / an : 0.0f;
      for (int k = 0; k < 3; ++k) {
        fl.gx[k] = static_cast<float>(lens_.centre_x()) - kGhostPosition[k] * ax;
        fl.gy[k] = static_cast<float>(lens_.centre_y()) - kGhostPosition[k] * ay;
      }
    }
  }
  const float direct = fl.sun_up ? (1 - 0.8f * fl.cloud) : 0.0f;
  const float noise_sigma = static_cast<float>(std::max(lighting.noise_sigma, 0.0));
  Rng noise(lighting.seed * 0xD1B54A32D192ED03ull ^ (frame_seed + 1) * 0x9E3779B97F4A7C15ull ^
            static_cast<std::uint64_t>(spectrum));
  auto next_noise = [&] {
    return noise_sigma > 0 ? noise_sigma * static_cast<float>(noise.Normal()) : 0.0f;
  };

  const Rgb horizon_haze = Rgb{0.7f, 0.78f, 0.88f} * fl.sky;
  for (int y = 0; y < height_; ++y) {
    std::uint8_t* row = out.Row(y);
    for (int x = 0; x < width_; ++x) {
      const auto i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                     static_cast<std::size_t>(x);
      if (inside_[i] == 0) {
        if (uv) {
          row[x] = 0;
        } else {
          std::memset(row + 3 * x, 0, 3);
        }
        continue;
      }
      const Vec3 d = to_world.Apply(rays_[i]);
      const Hit hit = bvh.ClosestHit({origin, d}, 1e-4f, kFar);
      // Surface hit: a triangle, else the ground plane for downward rays.
      bool surface = hit.hit();
      float t = hit.t;
      Vec3 normal{0, 0, 1};
      Material m = world_->ground;
      if (surface) {
        const Triangle& tri = triangles[hit.triangle];
        normal = Normalized(Cross(tri.b - tri.a, tri.c - tri.a));
        if (Dot(normal, d) > 0)
          normal = normal * -1.0f;
        m = materials[hit.triangle];
      } else if (d.z < 0) {
        surface = true;
        t = origin.z > 0 ? -origin.z / d.z : 1e-3f;
      }
      float value = 0;
      Rgb colour;
      if (surface) {
        const Vec3 p = origin + d * t;
        const float tex = TextureAt(m.texture, p, normal);
        const float sun_cos = std::max(Dot(normal, fl.sun), 0.0f);
        float sunlit = 0;
        if (direct > 0 && sun_cos > 0 && !uv &&
            !bvh.AnyHit({p + normal * 1e-3f, fl.sun}, 1e-4f, kFar))
          sunlit = direct * sun_cos;
        // Distance haze: far surfaces fade toward the horizon sky (stronger in the UV).
        if (uv) {
          const float ambient = 0.8f * fl.sky;
          value = m.uv * tex * (ambient + 0.6f * direct * sun_cos);
          const float haze = 1.0f - std::exp(-t / 600.0f);
          value += (0.7f * fl.sky - value) * haze;
        } else {
          const float light = 0.3f * fl.sky + 1.1f * sunlit;
          colour = Rgb{m.r, m.g, m.b} * (tex * light);
          colour = Mix(colour, horizon_haze, 1.0f - std::exp(-t / 1500.0f));
        }
      } else if (uv) {
        value = UvSky(fl, d);
      } else {
        colour = VisibleSky(fl, d);
      }
      if (fl.flare_on) {
        const float f = FlareAt(fl, static_cast<float>(x), static_cast<float>(y));
        value += f;
        colour = colour + Rgb{1.0f, 0.92f, 0.8f} * f;
      }
      if (uv) {
        row[x] = ToByte(value * fl.gain, next_noise());
      } else {
        std::uint8_t* px = row + 3 * x;
        px[0] = ToByte(colour.r * fl.gain, next_noise());
        px[1] = ToByte(colour.g * fl.gain, next_noise());
        px[2] = ToByte(colour.b * fl.gain, next_noise());
      }
    }
  }
  return Status::Ok();
}

Status Renderer::RenderSkyMask(const drivers::Pose& pose, const dsp::MutableImageView& out) const {
  SKYLOC_TRY(CheckOutput(out, dsp::PixelFormat::kGrey8));
  const Rotation to_world = BodyToWorld(pose);  // the lens's rays are in the body frame
  const Vec3 origin{static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
                    static_cast<float>(pose.z_m)};
  for (int y = 0; y < height_; ++y) {
    std::uint8_t* row = out.Row(y);
    for (int x = 0; x < width_; ++x) {
      const auto i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                     static_cast<std::size_t>(x);
      if (inside_[i] == 0) {
        row[x] = 0;
        continue;
      }
      const Vec3 d = to_world.Apply(rays_[i]);
      const bool ground = d.z < 0;  // the ground plane hides everything below the horizon
      row[x] = ground || world_->bvh().AnyHit({origin, d}, 1e-4f, kFar) ? 0 : 255;
    }
  }
  return Status::Ok();
}

}  // namespace skyloc::sim
