// Small float 3-vectors, rays, boxes and triangles for the simulator. Floats, because a
// world is a few hundred thousand triangles traced a few hundred thousand times a frame:
// float is precise to well under a millimetre over the 1 km a world spans.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace skyloc::sim {

struct Vec3 {
  float x = 0, y = 0, z = 0;

  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

// A Vec3 from doubles: the worlds lay out their geometry in double and store it in float.
inline Vec3 Vec3Of(double x, double y, double z) {
  return {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
}

inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(Vec3 a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline Vec3 operator*(float s, Vec3 a) {
  return a * s;
}
inline float Dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float Length(Vec3 a) {
  return std::sqrt(Dot(a, a));
}
inline Vec3 Normalized(Vec3 a) {
  const float n = Length(a);
  return n > 0 ? a * (1.0f / n) : a;
}
inline Vec3 Min(Vec3 a, Vec3 b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 Max(Vec3 a, Vec3 b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Ray {
  Vec3 origin;
  Vec3 direction;  // need not be unit length; hit distances are in units of it
};

struct Aabb {
  Vec3 min{kInfinity, kInfinity, kInfinity};
  Vec3 max{-kInfinity, -kInfinity, -kInfinity};

  void Grow(Vec3 p) {
    min = Min(min, p);
    max = Max(max, p);
  }
  void Grow(const Aabb& b) {
    min = Min(min, b.min);
    max = Max(max, b.max);
  }
  float HalfArea() const {
    const Vec3 d = max - min;
    return d.x < 0 ? 0.0f : d.x * d.y + d.y * d.z + d.z * d.x;
  }
};

struct Triangle {
  Vec3 a, b, c;
};

// Möller–Trumbore: distance along the ray to the triangle, or +inf if missed (both faces
// count, rays from behind included). Hits at t <= t_min are ignored so a shadow ray that
// starts on a surface does not hit that surface.
inline float IntersectTriangle(const Ray& ray, const Triangle& tri, float t_min) {
  const Vec3 e1 = tri.b - tri.a;
  const Vec3 e2 = tri.c - tri.a;
  const Vec3 p = Cross(ray.direction, e2);
  const float det = Dot(e1, p);
  if (std::fabs(det) < 1e-12f)
    return kInfinity;
  const float inv = 1.0f / det;
  const Vec3 s = ray.origin - tri.a;
  const float u = Dot(s, p) * inv;
  if (u < 0.0f || u > 1.0f)
    return kInfinity;
  const Vec3 q = Cross(s, e1);
  const float v = Dot(ray.direction, q) * inv;
  if (v < 0.0f || u + v > 1.0f)
    return kInfinity;
  const float t = Dot(e2, q) * inv;
  return t > t_min ? t : kInfinity;
}

}  // namespace skyloc::sim
