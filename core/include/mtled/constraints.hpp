#pragma once
// Essential boundary conditions for non-interpolating shape functions (simplified EBCIEM, Joldes,
// Chowdhury, Wittek, Miller, EABE 2017). After each unconstrained update u_pred the kernel applies
//   u = u_pred + M^-1 Phi^T y,   y = (Phi M^-1 Phi^T)^-1 (u_bar - Phi u_pred),
// per displacement component, where row K of Phi holds the shape functions at constrained node (or material
// point) K. Then the interpolated displacement there equals the prescribed one to round-off, and the
// reaction at K is lambda_K = y_K / alpha (alpha: the integrator's factor on M^-1 f in its update).
// The matrices are factorised once per change of the constrained sets.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <span>
#include <vector>

#include "mtled/interfaces/driver.hpp"
#include "mtled/model.hpp"

namespace mtled {

class ConstraintSystem {
 public:
  explicit ConstraintSystem(const Model& model) : model_(model) {}

  // Rebuilds and refactorises when the sets, their revisions or the masses changed. A (node, component)
  // pair claimed by several sets is enforced by the first set only (boundaries come before the needle);
  // the later sets get a zero reaction there.
  void update(const std::vector<NodalConstraints*>& sets, std::span<const double> mass, bool mass_changed);
  void enforce(std::span<double> u, double alpha);
  // f += Phi^T lambda: the nodal forces the constraints exerted in the last enforce().
  void add_constraint_forces(std::span<double> f) const;
  // v -= M^-1 Phi^T (Phi M^-1 Phi^T)^-1 Phi v: the M-orthogonal projection onto the increments that leave every
  // constrained value unchanged (the correction enforce() applies, for prescribed values held fixed). The
  // constrained dynamics live in that subspace; the stable-step monitor iterates in it.
  void project_out(std::span<double> v) const;
  Index constrained_count() const;
  long factorisations() const { return factorisations_; }

 private:
  struct Row {
    std::size_t set;
    std::size_t entry;
  };
  struct Component {
    std::vector<Row> rows;
    Eigen::SparseMatrix<double, Eigen::RowMajor> phi;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor;
    Eigen::VectorXd residual, y, lambda;
  };
  void rebuild(std::span<const double> mass);
  // out = Phi_c v (one entry per row of component c; out is sized already) and v += M^-1 Phi_c^T y.
  static void constrained_values(const Component& comp, int c, std::span<const double> v, Eigen::VectorXd& out);
  void add_correction(const Component& comp, int c, const Eigen::VectorXd& y, std::span<double> v) const;

  const Model& model_;
  std::vector<NodalConstraints*> sets_;
  std::vector<std::uint64_t> revisions_;
  std::vector<double> inverse_mass_;
  Component components_[3];
  long factorisations_ = 0;
};

}  // namespace mtled
