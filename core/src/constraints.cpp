#include "mtled/constraints.hpp"

#include <fmt/format.h>

#include <set>

namespace mtled {

void ConstraintSystem::update(const std::vector<NodalConstraints*>& sets, std::span<const double> mass,
                              bool mass_changed) {
  bool changed = mass_changed || sets.size() != sets_.size();
  for (std::size_t s = 0; s < sets.size() && !changed; ++s)
    changed = sets[s] != sets_[s] || sets[s]->revision() != revisions_[s];
  if (!changed) return;
  sets_ = sets;
  revisions_.clear();
  for (const auto* set : sets_) revisions_.push_back(set->revision());
  rebuild(mass);
}

void ConstraintSystem::rebuild(std::span<const double> mass) {
  ++factorisations_;
  inverse_mass_.resize(mass.size());
  for (std::size_t i = 0; i < mass.size(); ++i) inverse_mass_[i] = 1.0 / mass[i];
  const SupportRows& psi = model_.node_interpolation();
  const auto n = static_cast<Eigen::Index>(model_.node_count());

  for (int c = 0; c < 3; ++c) {
    Component& comp = components_[c];
    comp.rows.clear();
    std::set<Index> claimed;
    for (std::size_t s = 0; s < sets_.size(); ++s) {
      NodalConstraints& set = *sets_[s];
      set.reactions.assign(set.size(), Vec3::Zero());
      if (set.values.size() != set.size() || (!set.points().empty() && !set.nodes().empty()))
        throw std::logic_error(fmt::format("constraint set \"{}\": {} values for {} nodes and {} points", set.name,
                                           set.values.size(), set.nodes().size(), set.points().size()));
      if (!set.components()[c]) continue;
      // Material points never coincide with one another's rows by construction; nodes may be claimed twice.
      for (std::size_t k = 0; k < set.size(); ++k)
        if (!set.points().empty() || claimed.insert(set.nodes()[k]).second) comp.rows.push_back({s, k});
    }
    const auto m = static_cast<Eigen::Index>(comp.rows.size());
    std::vector<Eigen::Triplet<double>> triplets;
    std::vector<Index> support;
    std::vector<double> values;
    for (Eigen::Index r = 0; r < m; ++r) {
      const NodalConstraints& set = *sets_[comp.rows[r].set];
      if (!set.points().empty()) {
        const Vec3& x = set.points()[comp.rows[r].entry];
        if (!model_.shape_functions_at(x, support, values))
          throw std::logic_error(fmt::format("constraint set \"{}\": no shape functions at ({:g}, {:g}, {:g})",
                                             set.name, x[0], x[1], x[2]));
        for (std::size_t k = 0; k < support.size(); ++k) triplets.emplace_back(r, support[k], values[k]);
        continue;
      }
      const Index node = set.nodes()[comp.rows[r].entry];
      for (std::int64_t k = psi.offsets[node]; k < psi.offsets[node + 1]; ++k)
        triplets.emplace_back(r, psi.nodes[k], psi.values[k]);
    }
    comp.phi.resize(m, n);
    comp.phi.setFromTriplets(triplets.begin(), triplets.end());
    comp.residual.resize(m);
    comp.y.resize(m);
    comp.lambda = Eigen::VectorXd::Zero(m);
    if (m == 0) continue;
    Eigen::SparseMatrix<double> phi_m = comp.phi;  // column-major copy, scaled by M^-1 column-wise
    for (Eigen::Index j = 0; j < phi_m.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(phi_m, j); it; ++it) it.valueRef() *= inverse_mass_[j];
    const Eigen::SparseMatrix<double> phi_t = Eigen::SparseMatrix<double>(comp.phi).transpose();
    const Eigen::SparseMatrix<double> a = phi_m * phi_t;
    comp.factor.compute(a);
    if (comp.factor.info() != Eigen::Success)
      throw InputError("/boundaries",
                       fmt::format("the constrained nodes of component {} cannot all be prescribed independently "
                                   "(the constraint matrix is singular): are two constraint sets prescribing "
                                   "coincident nodes?",
                                   "xyz"[c]));
  }
}

void ConstraintSystem::constrained_values(const Component& comp, int c, std::span<const double> v,
                                          Eigen::VectorXd& out) {
  for (Eigen::Index r = 0; r < out.size(); ++r) {
    double sum = 0.0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(comp.phi, r); it; ++it)
      sum += it.value() * v[3 * static_cast<std::size_t>(it.col()) + c];
    out[r] = sum;
  }
}

void ConstraintSystem::add_correction(const Component& comp, int c, const Eigen::VectorXd& y,
                                      std::span<double> v) const {
  for (Eigen::Index r = 0; r < y.size(); ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(comp.phi, r); it; ++it)
      v[3 * static_cast<std::size_t>(it.col()) + c] += inverse_mass_[it.col()] * it.value() * y[r];
}

void ConstraintSystem::enforce(std::span<double> u, double alpha) {
  for (int c = 0; c < 3; ++c) {
    Component& comp = components_[c];
    if (comp.rows.empty()) continue;
    constrained_values(comp, c, u, comp.residual);  // in place: no allocation in the time step
    for (Eigen::Index r = 0; r < comp.residual.size(); ++r) {
      const auto& row = comp.rows[r];
      comp.residual[r] = sets_[row.set]->values[row.entry][c] - comp.residual[r];
    }
    comp.y = comp.factor.solve(comp.residual);
    add_correction(comp, c, comp.y, u);
    for (Eigen::Index r = 0; r < comp.y.size(); ++r) {
      const auto& row = comp.rows[r];
      comp.lambda[r] = comp.y[r] / alpha;
      sets_[row.set]->reactions[row.entry][c] = comp.lambda[r];
    }
  }
}

void ConstraintSystem::project_out(std::span<double> v) const {
  for (int c = 0; c < 3; ++c) {
    const Component& comp = components_[c];
    if (comp.rows.empty()) continue;
    Eigen::VectorXd phi_v(comp.residual.size());
    constrained_values(comp, c, v, phi_v);
    const Eigen::VectorXd y = comp.factor.solve(-phi_v);
    add_correction(comp, c, y, v);
  }
}

void ConstraintSystem::add_constraint_forces(std::span<double> f) const {
  for (int c = 0; c < 3; ++c) {
    const Component& comp = components_[c];
    for (Eigen::Index r = 0; r < static_cast<Eigen::Index>(comp.rows.size()); ++r)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(comp.phi, r); it; ++it)
        f[3 * static_cast<std::size_t>(it.col()) + c] += it.value() * comp.lambda[r];
  }
}

Index ConstraintSystem::constrained_count() const {
  std::size_t count = 0;
  for (const auto& comp : components_) count += comp.rows.size();
  return static_cast<Index>(count);
}

}  // namespace mtled
