// `mls`: moving least squares with the quartic spline weight and a linear or quadratic basis (Lancaster and
// Salkauskas, Math. Comp. 1981; moving_least_squares.hpp); the MTLED papers use the linear basis.
#include <fmt/format.h>

#include "moving_least_squares.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class MlsShapeFunctions final : public ShapeFunctions {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("Moving least squares shape functions: quartic spline weight, linear or quadratic basis in local "
              "scaled coordinates, exact gradients.");
    shapefunctions::declare_support_dilatation(
        d, 1.6,
        "1.5 to 1.6 is usual with the linear basis (Horton, Wittek, Joldes, Miller, Commun. Numer. Methods Eng. 2010). The quadratic basis needs at least 10 well-spread "
        "nodes in every support: use 1.8 to 2.0 with it (at 1.6, boundary supports of a Gmsh mesh have as few as "
        "14 nodes and |N_I| up to 1.7), or use mmls.");
    d.string("basis")
        .defaults("linear")
        .choices({"linear", "quadratic"})
        .doc(
            "polynomial basis: linear (1, x, y, z) reproduces linear fields exactly and needs 4 non-coplanar nodes "
            "per support; quadratic (10 terms) reproduces quadratic fields and needs at least 10 nodes that do "
            "not lie on one quadric surface, which fails near boundaries of coarse meshes")
        .to<&Basis::basis>();
    d.example({{"support_dilatation", 1.6}, {"basis", "linear"}});
  }

  explicit MlsShapeFunctions(const Parameters& p) : dilatation_(p.read<shapefunctions::Support>().dilatation) {
    const std::string basis = p.read<Basis>().basis;
    if (basis == "linear") {
      settings_.basis = shapefunctions::PolynomialBasis::linear;
    } else if (basis == "quadratic") {
      settings_.basis = shapefunctions::PolynomialBasis::quadratic;
    } else {  // validation rejects this first; kept so a hand-built Parameters cannot slip through
      throw InputError(p.pointer("basis"),
                       fmt::format("unknown basis \"{}\"; allowed: \"linear\" or \"quadratic\" (use \"linear\" for "
                                   "MTLED as in the paper)",
                                   basis));
    }
  }

  double support_dilatation() const override { return dilatation_; }
  int minimum_support_size() const override { return shapefunctions::basis_size(settings_.basis); }

  ShapeFunctionFit evaluate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                            std::span<double> values, std::span<Vec3> gradients) const override {
    return shapefunctions::evaluate_moving_least_squares(settings_, x, nodes, radii, values, gradients);
  }

  ShapeFunctionFit interpolate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                               std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) const override {
    return shapefunctions::interpolate_moving_least_squares(settings_, x, nodes, radii, node_values, value, gradient);
  }

 private:
  struct Basis {
    std::string basis;
  };
  double dilatation_;
  shapefunctions::MovingLeastSquaresSettings settings_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::ShapeFunctions, mtled::MlsShapeFunctions)
