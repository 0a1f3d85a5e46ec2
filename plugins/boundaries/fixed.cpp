// `fixed`: zero displacement of a node set (all or some components).
#include "mtled/plugin.hpp"
#include "node_set_boundary.hpp"

namespace mtled {

class FixedBoundary final : public NodeSetBoundary {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("Holds the interpolated displacement of a node set at zero, in all or some components.");
    declare_selection(d);
    d.example({{"nodes", {{"group", "bottom"}}}});
  }
  explicit FixedBoundary(const Parameters& parameters) : NodeSetBoundary(parameters, Vec3::Zero()) {}
};

}  // namespace mtled

MTLED_PLUGIN(mtled::BoundaryCondition, mtled::FixedBoundary)
