// `prescribed_displacement`: a node set moved by load_fraction x (displacement + gradient X): a rigid
// translation, or an affine field (patch tests, simple shear, a rotated face to first order).
#include "mtled/plugin.hpp"
#include "node_set_boundary.hpp"

namespace mtled {

class PrescribedDisplacementBoundary final : public NodeSetBoundary {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Moves a node set by a displacement that grows with the integrator's load curve from 0 to `displacement`; "
        "components not listed stay free.");
    declare_selection(d);
    d.vector3("displacement")
        .unit("m")
        .doc("displacement of the node set at full load (plus gradient X)")
        .to<&Settings::displacement>();
    d.number_list("gradient")
        .unit("1")
        .optional()
        .doc("displacement gradient G (9 numbers, row by row) of an affine field d + G X at full load; default 0")
        .to<&Settings::gradient>();
    d.example({{"nodes", {{"group", "top"}}}, {"displacement", {0.0, 0.0, -0.002}}, {"components", {"z"}}});
  }
  explicit PrescribedDisplacementBoundary(const Parameters& parameters)
      : NodeSetBoundary(parameters, parameters.read<Settings>().displacement, read_gradient(parameters)) {}

 private:
  struct Settings {
    Vec3 displacement = Vec3::Zero();
    std::optional<std::vector<double>> gradient;
  };

  static Mat3 read_gradient(const Parameters& parameters) {
    const auto given = parameters.read<Settings>().gradient;
    if (!given) return Mat3::Zero();
    const std::vector<double>& g = *given;
    if (g.size() != 9)
      throw InputError(parameters.pointer("gradient"),
                       "expected 9 numbers, the gradient's rows one after another: [Gxx, Gxy, Gxz, Gyx, ...]");
    Mat3 G;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) G(i, j) = g[static_cast<std::size_t>(3 * i + j)];
    return G;
  }
};

}  // namespace mtled

MTLED_PLUGIN(mtled::BoundaryCondition, mtled::PrescribedDisplacementBoundary)
