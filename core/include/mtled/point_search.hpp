#pragma once
// Nearest-neighbour and radius queries over a fixed point cloud (a k-d tree, nanoflann).
#include <memory>
#include <span>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

class PointSearch {
 public:
  explicit PointSearch(std::span<const Vec3> points);
  ~PointSearch();
  PointSearch(const PointSearch&) = delete;
  PointSearch& operator=(const PointSearch&) = delete;

  // Indices of the points within `radius` of x (|p - x| <= radius), unsorted. Thread-safe.
  void within(const Vec3& x, double radius, std::vector<Index>& out) const;
  // The k nearest points, closest first. Thread-safe.
  void nearest(const Vec3& x, std::size_t k, std::vector<Index>& out) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace mtled
