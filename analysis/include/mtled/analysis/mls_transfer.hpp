#pragma once
// A field known at the nodes of a cloud, evaluated anywhere with MLS (linear basis; the catalog's "mls" shape
// functions): how `mtled compare` carries one run onto another cloud, the fit's markers read a run, and the
// displacement is sampled on an image grid. Each node's support radius is 1.3 times the distance to its 10th nearest
// neighbour (about 20 nodes per support); a point that too few supports cover takes its 20 nearest nodes.
#include <memory>
#include <vector>

#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/point_search.hpp"

namespace mtled {

class MlsTransfer {
 public:
  MlsTransfer(const std::vector<Vec3>& nodes, PluginCatalog& catalog);
  // sum_I N_I(x) values_I; std::runtime_error when the neighbourhood of x is degenerate. Thread-safe.
  Vec3 at(const Vec3& x, const std::vector<Vec3>& values) const;

 private:
  const std::vector<Vec3>& nodes_;
  std::shared_ptr<ShapeFunctions> mls_;
  PointSearch search_;
  std::vector<double> radius_;
  double max_radius_ = 0.0;
};

}  // namespace mtled
