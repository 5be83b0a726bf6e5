#include "skyloc/sim/bvh.h"

#include <algorithm>
#include <array>

namespace skyloc::sim {
namespace {

constexpr int kBins = 16;
// SAH costs relative to one ray–triangle test.
constexpr float kTraversalCost = 1.0f;
constexpr float kTriangleCost = 1.0f;

struct Bin {
  Aabb box;
  std::uint32_t count = 0;
};

// Slab test; returns the entry distance or +inf when the box is missed within (t_min, t_max).
inline float IntersectBox(const Aabb& box, const Vec3& origin, const Vec3& inv_dir, float t_min,
                          float t_max) {
  float lo = t_min, hi = t_max;
  for (int a = 0; a < 3; ++a) {
    float t0 = (box.min[a] - origin[a]) * inv_dir[a];
    float t1 = (box.max[a] - origin[a]) * inv_dir[a];
    if (t0 > t1)
      std::swap(t0, t1);
    // NaN (0 * inf: origin on a slab plane of a parallel ray) compares false: keep lo/hi.
    lo = t0 > lo ? t0 : lo;
    hi = t1 < hi ? t1 : hi;
    if (lo > hi)
      return kInfinity;
  }
  return lo;
}

inline Vec3 Inverse(const Vec3& d) {
  return {1.0f / d.x, 1.0f / d.y, 1.0f / d.z};
}

}  // namespace

Status Bvh::Build(std::span<const Triangle> triangles) {
  if (triangles.empty())
    return Status::Error(StatusCode::kInvalidArgument, "BVH: the world has no triangles");
  if (triangles.size() >= UINT32_MAX / 2)
    return Status::Error(StatusCode::kOutOfRange, "BVH: %zu triangles is too many",
                         triangles.size());
  const auto n = static_cast<std::uint32_t>(triangles.size());
  std::vector<Vec3> centroids(n);
  std::vector<Aabb> boxes(n);
  order_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const Triangle& t = triangles[i];
    boxes[i].Grow(t.a);
    boxes[i].Grow(t.b);
    boxes[i].Grow(t.c);
    centroids[i] = (t.a + t.b + t.c) * (1.0f / 3.0f);
    order_[i] = i;
  }
  nodes_.clear();
  nodes_.reserve(2 * static_cast<std::size_t>(n));
  BuildNode(0, n, 0, centroids, boxes);
  nodes_.shrink_to_fit();
  triangles_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i)
    triangles_[i] = triangles[order_[i]];
  return Status::Ok();
}

std::uint32_t Bvh::BuildNode(std::uint32_t begin, std::uint32_t end, int depth,
                             std::vector<Vec3>& centroids, std::vector<Aabb>& boxes) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Aabb box, centroid_box;
  for (std::uint32_t i = begin; i < end; ++i) {
    box.Grow(boxes[order_[i]]);
    centroid_box.Grow(centroids[order_[i]]);
  }
  nodes_[index].box = box;
  const std::uint32_t count = end - begin;
  auto make_leaf = [&] {
    nodes_[index].offset = begin;
    nodes_[index].count = count;
    return index;
  };
  // Depth is bounded so traversal's fixed stack cannot overflow; leaves at the limit (only
  // reachable with pathological inputs) may hold more triangles.
  if (count <= 1 || depth >= kMaxDepth - 2)
    return make_leaf();

  // Binned SAH over the widest centroid axis, falling back to the other axes when all
  // centroids coincide on it.
  int best_axis = -1;
  int best_split = 0;
  float best_cost = kInfinity;
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = centroid_box.min[axis], hi = centroid_box.max[axis];
    if (!(hi > lo))
      continue;
    const float scale = static_cast<float>(kBins) / (hi - lo);
    std::array<Bin, kBins> bins{};
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t t = order_[i];
      int b = static_cast<int>((centroids[t][axis] - lo) * scale);
      b = std::clamp(b, 0, kBins - 1);
      bins[static_cast<std::size_t>(b)].box.Grow(boxes[t]);
      ++bins[static_cast<std::size_t>(b)].count;
    }
    std::array<float, kBins> right_area{};
    std::array<std::uint32_t, kBins> right_count{};
    Aabb acc;
    std::uint32_t acc_count = 0;
    for (int b = kBins - 1; b > 0; --b) {
      acc.Grow(bins[static_cast<std::size_t>(b)].box);
      acc_count += bins[static_cast<std::size_t>(b)].count;
      right_area[static_cast<std::size_t>(b)] = acc.HalfArea();
      right_count[static_cast<std::size_t>(b)] = acc_count;
    }
    acc = Aabb{};
    acc_count = 0;
    for (int b = 0; b < kBins - 1; ++b) {
      acc.Grow(bins[static_cast<std::size_t>(b)].box);
      acc_count += bins[static_cast<std::size_t>(b)].count;
      const auto r = static_cast<std::size_t>(b + 1);
      if (acc_count == 0 || right_count[r] == 0)
        continue;
      const float cost = acc.HalfArea() * static_cast<float>(acc_count) +
                         right_area[r] * static_cast<float>(right_count[r]);
      if (cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_split = b + 1;
      }
    }
  }
  const float leaf_cost = static_cast<float>(count) * kTriangleCost;
  const float parent_area = box.HalfArea();
  const float split_cost = best_axis < 0 || parent_area <= 0
                               ? kInfinity
                               : kTraversalCost + kTriangleCost * best_cost / parent_area;
  const bool small = count <= static_cast<std::uint32_t>(kMaxLeafSize);
  if ((small && leaf_cost <= split_cost) ||
      (best_axis < 0 && count <= static_cast<std::uint32_t>(4 * kMaxLeafSize)))
    return make_leaf();

  std::uint32_t mid;
  if (best_axis >= 0) {
    const float lo = centroid_box.min[best_axis];
    const float scale = static_cast<float>(kBins) / (centroid_box.max[best_axis] - lo);
    auto* first = order_.data() + begin;
    auto* last = order_.data() + end;
    auto* split = std::partition(first, last, [&](std::uint32_t t) {
      const int b =
          std::clamp(static_cast<int>((centroids[t][best_axis] - lo) * scale), 0, kBins - 1);
      return b < best_split;
    });
    mid = begin + static_cast<std::uint32_t>(split - first);
  } else {
    // All centroids coincide and the node is too large for one leaf: split by count.
    best_axis = 0;
    mid = begin + count / 2;
  }
  if (mid == begin || mid == end)
    mid = begin + count / 2;
  nodes_[index].axis = static_cast<std::uint32_t>(best_axis);
  BuildNode(begin, mid, depth + 1, centroids, boxes);
  const std::uint32_t right = BuildNode(mid, end, depth + 1, centroids, boxes);
  nodes_[index].offset = right;
  nodes_[index].count = 0;
  return index;
}

Hit Bvh::ClosestHit(const Ray& ray, float t_min, float t_max) const {
  Hit best;
  best.t = t_max;
  if (nodes_.empty())
    return Hit{};
  const Vec3 inv = Inverse(ray.direction);
  // Deferred subtrees with their entry distance, so a pop can skip one that now lies
  // behind the closest hit without testing its box again.
  struct Deferred {
    std::uint32_t node;
    float t_entry;
  };
  std::array<Deferred, kMaxDepth> stack;
  int top = 0;
  std::uint32_t node = 0;
  if (IntersectBox(nodes_[0].box, ray.origin, inv, t_min, best.t) == kInfinity)
    return Hit{};
  for (;;) {
    const BvhNode& n = nodes_[node];
    if (n.count > 0) {
      for (std::uint32_t i = n.offset; i < n.offset + n.count; ++i) {
        const float t = IntersectTriangle(ray, triangles_[i], t_min);
        if (t < best.t) {
          best.t = t;
          best.triangle = i;
        }
      }
    } else {
      std::uint32_t near = node + 1, far = n.offset;
      float t_near = IntersectBox(nodes_[near].box, ray.origin, inv, t_min, best.t);
      float t_far = IntersectBox(nodes_[far].box, ray.origin, inv, t_min, best.t);
      // Visit the child the ray enters first.
      if (t_far < t_near) {
        std::swap(near, far);
        std::swap(t_near, t_far);
      }
      if (t_near != kInfinity) {
        if (t_far != kInfinity)
          stack[static_cast<std::size_t>(top++)] = {far, t_far};
        node = near;
        continue;
      }
    }
    // Pop the next subtree still in front of the closest hit found so far.
    bool found = false;
    while (top > 0) {
      const Deferred d = stack[static_cast<std::size_t>(--top)];
      if (d.t_entry < best.t) {
        node = d.node;
        found = true;
        break;
      }
    }
    if (!found)
      break;
  }
  if (!best.hit())
    return Hit{};
  best.triangle = order_[best.triangle];
  return best;
}

bool Bvh::AnyHit(const Ray& ray, float t_min, float t_max) const {
  if (nodes_.empty())
    return false;
  const Vec3 inv = Inverse(ray.direction);
  std::array<std::uint32_t, kMaxDepth> stack;
  int top = 0;
  stack[static_cast<std::size_t>(top++)] = 0;
  while (top > 0) {
    const BvhNode& n = nodes_[stack[static_cast<std::size_t>(--top)]];
    if (IntersectBox(n.box, ray.origin, inv, t_min, t_max) == kInfinity)
      continue;
    if (n.count > 0) {
      for (std::uint32_t i = n.offset; i < n.offset + n.count; ++i) {
        if (IntersectTriangle(ray, triangles_[i], t_min) < t_max)
          return true;
      }
    } else {
      const auto self = static_cast<std::uint32_t>(&n - nodes_.data());
      stack[static_cast<std::size_t>(top++)] = n.offset;
      stack[static_cast<std::size_t>(top++)] = self + 1;
    }
  }
  return false;
}

Hit ClosestHitBruteForce(std::span<const Triangle> triangles, const Ray& ray, float t_min,
                         float t_max) {
  Hit best;
  best.t = t_max;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const float t = IntersectTriangle(ray, triangles[i], t_min);
    if (t < best.t) {
      best.t = t;
      best.triangle = static_cast<std::uint32_t>(i);
    }
  }
  return best.hit() ? best : Hit{};
}

bool AnyHitBruteForce(std::span<const Triangle> triangles, const Ray& ray, float t_min,
                      float t_max) {
  for (const Triangle& t : triangles) {
    if (IntersectTriangle(ray, t, t_min) < t_max)
      return true;
  }
  return false;
}

}  // namespace skyloc::sim
