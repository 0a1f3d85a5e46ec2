// `mmls`: modified moving least squares (Joldes, Chowdhury, Wittek, Doyle, Miller, "Modified moving least
// squares with polynomial bases for scattered data approximation", Appl. Math. Comput. 2015). A quadratic
// basis whose quadratic coefficients carry a small penalty: where the nodes determine a quadratic fit the
// penalty changes it by O(m^2); where they do not (few nodes, nearly flat supports at boundaries) the
// quadratic coefficients go to zero and the fit degrades to linear MLS instead of failing.
#include "moving_least_squares.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class MmlsShapeFunctions final : public ShapeFunctions {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("Modified moving least squares (Joldes et al. 2015): quadratic basis with a penalty on the quadratic "
              "coefficients, well posed with as few as 4 non-coplanar nodes; exact gradients.");
    shapefunctions::declare_support_dilatation(
        d, kDefaultDilatation,
        "The default is larger than the 1.6 usual for linear MLS because a quadratic fit needs about twice its 10 "
        "terms in nodes: on a Gmsh mesh of the paper's 30 x 17 mm cylinder (8,263 nodes) d_c = 1.8 gives at "
        "least 19 nodes per integration point and |N_I| < 0.7 everywhere, while 1.6 leaves 14-node boundary "
        "supports with |N_I| up to 1.2.");
    d.number("penalty")
        .unit("1")
        .between(1e-3, 1.0)
        .defaults(kDefaultPenalty)
        .doc(
            "m: m^2 times the sum of the node weights is added to the quadratic diagonal of the moment matrix, "
            "in coordinates scaled by the mean support radius (so m does not depend on units, mesh size or "
            "support size). Where the nodes determine a quadratic fit, it is changed by O(m^2); where they "
            "do not, the quadratic terms vanish and the fit is linear MLS. Below 1e-3 the regularisation is "
            "too weak to keep sparse supports well conditioned in double precision; near 1 the fit is close to "
            "linear MLS everywhere")
        .to<&Penalty::penalty>();
    d.example({{"support_dilatation", kDefaultDilatation}, {"penalty", kDefaultPenalty}});
  }

  explicit MmlsShapeFunctions(const Parameters& p) : dilatation_(p.read<shapefunctions::Support>().dilatation) {
    settings_.basis = shapefunctions::PolynomialBasis::quadratic;
    settings_.quadratic_penalty = p.read<Penalty>().penalty;
  }

  double support_dilatation() const override { return dilatation_; }
  // The penalty keeps the quadratic part well posed, so only the linear part needs its 4 non-coplanar nodes.
  int minimum_support_size() const override { return 4; }

  ShapeFunctionFit evaluate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                            std::span<double> values, std::span<Vec3> gradients) const override {
    return shapefunctions::evaluate_moving_least_squares(settings_, x, nodes, radii, values, gradients);
  }

  ShapeFunctionFit interpolate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                               std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) const override {
    return shapefunctions::interpolate_moving_least_squares(settings_, x, nodes, radii, node_values, value, gradient);
  }

 private:
  struct Penalty {
    double penalty = 0.0;
  };
  static constexpr double kDefaultDilatation = 1.8;
  static constexpr double kDefaultPenalty = 1e-2;
  double dilatation_;
  shapefunctions::MovingLeastSquaresSettings settings_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::ShapeFunctions, mtled::MmlsShapeFunctions)
