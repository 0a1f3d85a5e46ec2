#include "mtled/point_search.hpp"

#include <nanoflann.hpp>

namespace mtled {

// The nanoflann adaptor and tree as members of the pimpl, not in an anonymous namespace: a type with internal
// linkage as a member's type is what GCC warns of (-Wsubobject-linkage) when the file is compiled in a unity batch.
struct PointSearch::Tree {
  struct Cloud {
    std::span<const Vec3> points;
    std::size_t kdtree_get_point_count() const { return points.size(); }
    double kdtree_get_pt(std::size_t i, std::size_t d) const { return points[i][static_cast<Eigen::Index>(d)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using KdTree =
      nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, std::uint32_t>;

  Cloud cloud;
  KdTree index;
  explicit Tree(std::span<const Vec3> points)
      : cloud{points}, index(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    index.buildIndex();
  }
};

PointSearch::PointSearch(std::span<const Vec3> points) : tree_(std::make_unique<Tree>(points)) {}
PointSearch::~PointSearch() = default;

void PointSearch::within(const Vec3& x, double radius, std::vector<Index>& out) const {
  // One buffer per thread, kept between calls: setup asks once per integration point and node, and a fresh vector
  // grew by reallocation to each support's size every time.
  thread_local std::vector<std::pair<std::uint32_t, double>> matches;
  tree_->index.radiusSearch(x.data(), radius * radius, matches, nanoflann::SearchParams(32, 0.0f, false));
  out.clear();
  out.reserve(matches.size());
  for (const auto& m : matches) out.push_back(static_cast<Index>(m.first));
}

void PointSearch::nearest(const Vec3& x, std::size_t k, std::vector<Index>& out) const {
  k = std::min(k, tree_->cloud.points.size());
  std::vector<std::uint32_t> indices(k);
  std::vector<double> distances(k);
  const std::size_t found = tree_->index.knnSearch(x.data(), k, indices.data(), distances.data());
  out.assign(indices.begin(), indices.begin() + static_cast<std::ptrdiff_t>(found));
}

}  // namespace mtled
