#pragma once
// A field known at the nodes of a cloud, evaluated anywhere with MLS (linear basis; the catalog's "mls" shape
// functions): how `mtled compare` carries one run onto another cloud, the fit's markers read a run, and the
// displacement is sampled on an image grid. Each node's support radius is 1.3 times the distance to its 10th nearest
// neighbour (about 20 nodes per support); a point that too few supports cover takes its 20 nearest nodes. The
// supports are found through a grid of bins, each listing the nodes whose support sphere reaches it: one bin and a
// distance test per node listed, instead of a tree search as wide as the largest support.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/io/large_buffer.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/point_search.hpp"

namespace mtled {

class MlsTransfer {
 public:
  MlsTransfer(const std::vector<Vec3>& nodes, PluginCatalog& catalog);
  // sum_I N_I(x) values_I; std::runtime_error when the neighbourhood of x is degenerate. Thread-safe.
  Vec3 at(const Vec3& x, const std::vector<Vec3>& values) const;
  // The same, and its gradient d/dx (sum_I N_I(x) values_I) (rows: components).
  Vec3 at(const Vec3& x, const std::vector<Vec3>& values, Mat3& gradient) const;

 private:
  // The nodes whose supports reach bin b: bin_nodes_[bin_start_[b] .. bin_start_[b + 1]).
  std::int64_t bin_of(const Vec3& x) const;  // -1 outside the bins
  Vec3 evaluate(const Vec3& x, const std::vector<Vec3>& values, Mat3* gradient) const;
  void fill_bins();
  void pack_nodes();

  const std::vector<Vec3>& nodes_;
  std::shared_ptr<ShapeFunctions> mls_;
  PointSearch search_;
  std::vector<double> radius_;
  Vec3 bins_origin_ = Vec3::Zero();
  double bin_size_ = 1.0;
  std::array<std::int64_t, 3> bins_{0, 0, 0};
  std::vector<std::int64_t> bin_start_;
  LargeVector<std::uint32_t> bin_nodes_;  // positions in packed_ (a cloud has fewer than 2^32 nodes)
  std::vector<Eigen::Vector4d> packed_;   // a node's position and support radius, in bin order
  std::vector<Index> packed_node_;       // the node each packed_ entry is
};

}  // namespace mtled
