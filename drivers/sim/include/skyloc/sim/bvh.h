// A bounding volume hierarchy over triangles: binned surface-area-heuristic build, nodes
// flattened depth-first (left child follows its parent), iterative traversal with a
// fixed stack. Closest hit shades a pixel; any hit answers "is the sky blocked" (the UV
// sky mask, sun visibility, shadows) and stops at the first blocker.
//
// Built once at start-up (allocates); queries are const, allocation-free and thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/platform/status.h"
#include "skyloc/sim/geometry.h"

namespace skyloc::sim {

struct Hit {
  float t = kInfinity;                  // distance along the ray, in units of its direction
  std::uint32_t triangle = UINT32_MAX;  // index into the triangles given to Build()
  bool hit() const { return triangle != UINT32_MAX; }
};

struct BvhNode {
  Aabb box;
  std::uint32_t offset = 0;  // leaf: first triangle; interior: index of the right child
  std::uint32_t count = 0;   // triangles in a leaf; 0 for an interior node
  std::uint32_t axis = 0;    // split axis of an interior node (orders the traversal)
};

class Bvh {
 public:
  static constexpr int kMaxDepth = 64;  // traversal stack size; Build() never goes deeper
  static constexpr int kMaxLeafSize = 4;

  // Copies the triangles (reordered for locality). Fails only on an empty input.
  Status Build(std::span<const Triangle> triangles);

  // Nearest hit with t in (t_min, t_max).
  Hit ClosestHit(const Ray& ray, float t_min, float t_max) const;
  // True if anything is hit with t in (t_min, t_max).
  bool AnyHit(const Ray& ray, float t_min, float t_max) const;

  const Aabb& bounds() const { return nodes_.front().box; }
  std::size_t node_count() const { return nodes_.size(); }
  std::size_t triangle_count() const { return triangles_.size(); }

 private:
  std::uint32_t BuildNode(std::uint32_t begin, std::uint32_t end, int depth,
                          std::vector<Vec3>& centroids, std::vector<Aabb>& boxes);

  std::vector<BvhNode> nodes_;
  std::vector<Triangle> triangles_;   // leaf order
  std::vector<std::uint32_t> order_;  // leaf order -> index given to Build()
};

// The reference the BVH is tested against: every triangle, one by one.
Hit ClosestHitBruteForce(std::span<const Triangle> triangles, const Ray& ray, float t_min,
                         float t_max);
bool AnyHitBruteForce(std::span<const Triangle> triangles, const Ray& ray, float t_min,
                      float t_max);

}  // namespace skyloc::sim
