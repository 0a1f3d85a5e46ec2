#include "mtled/constraints.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <set>

#include "factor_solve.hpp"
#include "mtled/log.hpp"

namespace mtled {
namespace {
// Rows (or nodes) of Phi, about 30 entries each, below which a loop runs on one thread: on the default needle
// scene (694 rows) splitting still paid; on the small cube's few dozen rows per set it did not.
constexpr std::int64_t kRowsWorthAThread = 256;
}  // namespace

void ConstraintSystem::update(const std::vector<NodalConstraints*>& sets, std::span<const double> mass,
                              bool mass_changed) {
  bool changed = mass_changed || sets.size() != sets_.size();
  for (std::size_t s = 0; s < sets.size() && !changed; ++s)
    changed = sets[s] != sets_[s] || sets[s]->revision() != revisions_[s];
  if (!changed) return;
  sets_ = sets;
  revisions_.clear();
  for (const auto* set : sets_) revisions_.push_back(set->revision());
  rebuild(mass, !mass_changed);
}

void ConstraintSystem::rebuild(std::span<const double> mass, bool reuse_factors) {
  ++factorisations_;
  std::vector<std::unique_ptr<Part>> reusable;
  if (reuse_factors)
    for (Block& block : blocks_)
      for (auto& part : block.parts) reusable.push_back(std::move(part));
  for (NodalConstraints* set : sets_) {
    set->reactions.assign(set->size(), Vec3::Zero());
    if (set->values.size() != set->size() || (!set->points().empty() && !set->nodes().empty()))
      throw std::logic_error(fmt::format("constraint set \"{}\": {} values for {} nodes and {} points", set->name,
                                         set->values.size(), set->nodes().size(), set->points().size()));
  }
  blocks_.clear();
  for (int c = 0; c < 3; ++c) {
    std::vector<Row> rows;
    std::set<Index> claimed;
    for (std::size_t s = 0; s < sets_.size(); ++s) {
      const NodalConstraints& set = *sets_[s];
      if (!set.components()[c]) continue;
      // Material points never coincide with one another's rows by construction; nodes may be claimed twice.
      for (std::size_t k = 0; k < set.size(); ++k)
        if (!set.points().empty() || claimed.insert(set.nodes()[k]).second) rows.push_back({s, k});
    }
    if (rows.empty()) continue;
    const auto same = std::find_if(blocks_.begin(), blocks_.end(), [&](const Block& b) {
      return std::equal(b.rows.begin(), b.rows.end(), rows.begin(), rows.end(),
                        [](const Row& x, const Row& y) { return x.set == y.set && x.entry == y.entry; });
    });
    if (same != blocks_.end()) {
      same->phi.components.push_back(c);
      continue;
    }
    blocks_.emplace_back();
    blocks_.back().phi.components = {c};
    blocks_.back().rows = std::move(rows);
  }
  for (Block& block : blocks_) build_block(block, mass, reusable);
}

void ConstraintSystem::build_block(Block& block, std::span<const double> mass,
                                   std::vector<std::unique_ptr<Part>>& reusable) {
  fill_phi(block, mass);
  find_parts(block);
  std::size_t factorised = 0;
  for (auto& part : block.parts) {
    const auto same =
        std::find_if(reusable.begin(), reusable.end(), [&](const auto& old) { return old && old->keys == part->keys; });
    if (same != reusable.end()) {
      (*same)->rows = std::move(part->rows);
      part = std::move(*same);
      continue;
    }
    factorise(*part, block.phi, mass);
    ++factorised;
    ++parts_factorised_;
  }
  std::size_t entries = 0;
  for (const auto& part : block.parts)
    entries += static_cast<std::size_t>(part->factor.matrixL().nestedExpression().nonZeros());
  log().debug(
      "constraints: components {} share {} rows in {} independent part(s), {} factorised again; Phi {} "
      "entries, the factors {} entries",
      block.phi.components, block.rows.size(), block.parts.size(), factorised, block.phi.row_nodes.size(), entries);
  block.y.assign(block.rows.size() * block.phi.components.size(), 0.0);
}

// Phi's rows for the block's rows, by row and by node (scaled by 1 / m there).
void ConstraintSystem::fill_phi(Block& block, std::span<const double> mass) const {
  const SupportRows& psi = discretisation_.basis()->interpolation;
  ConstraintBlock& phi_block = block.phi;
  const auto m = static_cast<Eigen::Index>(block.rows.size());
  phi_block.rows = m;
  phi_block.revision = factorisations_;
  std::vector<Index> support;
  std::vector<double> values;
  phi_block.row_offsets.assign(1, 0);
  phi_block.row_nodes.clear();
  phi_block.row_values.clear();
  for (Eigen::Index r = 0; r < m; ++r) {
    const NodalConstraints& set = *sets_[block.rows[r].set];
    if (!set.points().empty()) {
      const Vec3& x = set.points()[block.rows[r].entry];
      if (!discretisation_.shape_functions_at(x, support, values))
        throw std::logic_error(fmt::format("constraint set \"{}\": no shape functions at ({:g}, {:g}, {:g})", set.name,
                                           x[0], x[1], x[2]));
    } else {
      const Index node = set.nodes()[block.rows[r].entry];
      support.assign(psi.nodes.begin() + psi.offsets[node], psi.nodes.begin() + psi.offsets[node + 1]);
      values.assign(psi.values.begin() + psi.offsets[node], psi.values.begin() + psi.offsets[node + 1]);
    }
    phi_block.row_nodes.insert(phi_block.row_nodes.end(), support.begin(), support.end());
    phi_block.row_values.insert(phi_block.row_values.end(), values.begin(), values.end());
    phi_block.row_offsets.push_back(static_cast<std::int64_t>(phi_block.row_nodes.size()));
  }

  // Phi by node, scaled by 1 / m: entries in row order within each node.
  std::vector<std::size_t> order(phi_block.row_nodes.size());
  for (std::size_t e = 0; e < order.size(); ++e) order[e] = e;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return phi_block.row_nodes[a] < phi_block.row_nodes[b]; });
  std::vector<Index> entry_row(phi_block.row_nodes.size());
  for (Eigen::Index r = 0; r < m; ++r)
    for (std::int64_t e = phi_block.row_offsets[r]; e < phi_block.row_offsets[r + 1]; ++e)
      entry_row[e] = static_cast<Index>(r);
  phi_block.nodes.clear();
  phi_block.node_offsets.assign(1, 0);
  phi_block.node_rows.resize(order.size());
  phi_block.node_values.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t e = order[k];
    const Index node = phi_block.row_nodes[e];
    if (phi_block.nodes.empty() || phi_block.nodes.back() != node) {
      if (!phi_block.nodes.empty()) phi_block.node_offsets.push_back(static_cast<std::int64_t>(k));
      phi_block.nodes.push_back(node);
    }
    phi_block.node_rows[k] = entry_row[e];
    phi_block.node_values[k] = phi_block.row_values[e] / mass[node];
  }
  phi_block.node_offsets.push_back(static_cast<std::int64_t>(order.size()));
}

// The parts: rows joined when their supports share a node (then A couples them), by union-find over the rows; each
// part's rows ascending, with their keys.
void ConstraintSystem::find_parts(Block& block) const {
  const ConstraintBlock& phi_block = block.phi;
  std::vector<std::size_t> root(block.rows.size());
  for (std::size_t r = 0; r < root.size(); ++r) root[r] = r;
  const auto find = [&](std::size_t r) {
    while (root[r] != r) r = root[r] = root[root[r]];
    return r;
  };
  std::vector<std::int64_t> row_of_node(static_cast<std::size_t>(discretisation_.node_count()), -1);
  for (std::size_t r = 0; r < root.size(); ++r)
    for (std::int64_t e = phi_block.row_offsets[r]; e < phi_block.row_offsets[r + 1]; ++e) {
      std::int64_t& seen = row_of_node[static_cast<std::size_t>(phi_block.row_nodes[e])];
      if (seen < 0) {
        seen = static_cast<std::int64_t>(r);
        continue;
      }
      const std::size_t a = find(r), b = find(static_cast<std::size_t>(seen));
      if (a != b) root[std::max(a, b)] = std::min(a, b);  // each part's root is its first row
    }
  std::vector<std::size_t> part_of_root(root.size(), 0);
  block.parts.clear();
  for (std::size_t r = 0; r < root.size(); ++r) {
    const std::size_t first = find(r);
    if (first == r) {
      part_of_root[r] = block.parts.size();
      block.parts.push_back(std::make_unique<Part>());
    }
    Part& part = *block.parts[part_of_root[first]];
    part.rows.push_back(r);
    const NodalConstraints& set = *sets_[block.rows[r].set];
    part.keys.push_back(set.points().empty() ? RowKey{&set, set.nodes()[block.rows[r].entry], Vec3::Zero()}
                                             : RowKey{&set, -1, set.points()[block.rows[r].entry]});
  }
}

std::size_t ConstraintSystem::parts() const {
  std::size_t count = 0;
  for (const Block& block : blocks_) count += block.parts.size();
  return count;
}

// A = Phi M^-1 Phi^T over the part's rows, factorised.
void ConstraintSystem::factorise(Part& part, const ConstraintBlock& phi_block, std::span<const double> mass) const {
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::size_t i = 0; i < part.rows.size(); ++i)
    for (std::int64_t e = phi_block.row_offsets[part.rows[i]]; e < phi_block.row_offsets[part.rows[i] + 1]; ++e)
      triplets.emplace_back(static_cast<Eigen::Index>(i), phi_block.row_nodes[e], phi_block.row_values[e]);
  Eigen::SparseMatrix<double> phi(static_cast<Eigen::Index>(part.rows.size()),
                                  static_cast<Eigen::Index>(discretisation_.node_count()));
  phi.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SparseMatrix<double> phi_m = phi;  // scaled by M^-1 column-wise
  for (Eigen::Index j = 0; j < phi_m.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(phi_m, j); it; ++it) it.valueRef() /= mass[j];
  const Eigen::SparseMatrix<double> a = phi_m * Eigen::SparseMatrix<double>(phi.transpose());
  part.factor.compute(a);
  if (part.factor.info() != Eigen::Success) {
    std::string names;
    for (int c : phi_block.components) names += "xyz"[c];
    throw InputError("/boundaries",
                     fmt::format("the constrained nodes of component(s) {} cannot all be prescribed independently (the "
                                 "constraint matrix is singular): are two constraint sets prescribing coincident nodes?",
                                 names));
  }
  // factor_solve takes every stored entry of L as below the diagonal (Eigen's LDLT stores no unit diagonal).
  const auto& L = part.factor.matrixL().nestedExpression();
  for (Eigen::Index col = 0; col < L.outerSize(); ++col)
    if (L.outerIndexPtr()[col] < L.outerIndexPtr()[col + 1] && L.innerIndexPtr()[L.outerIndexPtr()[col]] <= col)
      throw std::logic_error("ConstraintSystem: the factor stores entries on or above its diagonal");
  const Eigen::VectorXd D = part.factor.vectorD();
  part.inverse_diagonal.resize(static_cast<std::size_t>(D.size()));
  for (Eigen::Index i = 0; i < D.size(); ++i) part.inverse_diagonal[static_cast<std::size_t>(i)] = 1.0 / D[i];
}

namespace {

// The two products below for a block of K components, K fixed at compile time: the loops over the components
// unroll, and a pass over Phi's entries serves all of them (with the block's component count read at run time the
// compiler kept an indexed inner loop per entry, two to three times slower on the default needle scene's rows):
// body(component) gets the block's components in a std::array of their count.
template <class Body>
void with_components(const ConstraintBlock& block, Body&& body) {
  const auto call = [&]<std::size_t K>(std::array<int, K> component) {
    for (std::size_t j = 0; j < K; ++j) component[j] = block.components[j];
    body(component);
  };
  switch (block.components.size()) {
    case 1:
      return call(std::array<int, 1>{});
    case 2:
      return call(std::array<int, 2>{});
    default:
      return call(std::array<int, 3>{});
  }
}

}  // namespace

void constrained_values(const ConstraintBlock& block, std::span<const double> v, std::vector<double>& out,
                        ThreadTeam& team) {
  with_components(block, [&]<std::size_t K>(const std::array<int, K>& component) {
    team.for_each_share(
        block.rows,
        [&](std::int64_t begin, std::int64_t end) {
          for (auto r = static_cast<std::size_t>(begin); r < static_cast<std::size_t>(end); ++r) {
            double sum[K] = {};
            for (std::int64_t e = block.row_offsets[r]; e < block.row_offsets[r + 1]; ++e) {
              const double* vi = &v[3 * static_cast<std::size_t>(block.row_nodes[e])];
              for (std::size_t j = 0; j < K; ++j) sum[j] += block.row_values[e] * vi[component[j]];
            }
            for (std::size_t j = 0; j < K; ++j) out[K * r + j] = sum[j];
          }
        },
        kRowsWorthAThread);
  });
}

void add_correction(const ConstraintBlock& block, const std::vector<double>& y, std::span<double> v, ThreadTeam& team) {
  with_components(block, [&]<std::size_t K>(const std::array<int, K>& component) {
    team.for_each_share(
        static_cast<std::int64_t>(block.nodes.size()),
        [&](std::int64_t begin, std::int64_t end) {
          for (auto n = static_cast<std::size_t>(begin); n < static_cast<std::size_t>(end); ++n) {
            double sum[K] = {};
            for (std::int64_t e = block.node_offsets[n]; e < block.node_offsets[n + 1]; ++e) {
              const double* yr = &y[K * static_cast<std::size_t>(block.node_rows[e])];
              for (std::size_t j = 0; j < K; ++j) sum[j] += block.node_values[e] * yr[j];
            }
            double* vn = &v[3 * static_cast<std::size_t>(block.nodes[n])];
            for (std::size_t j = 0; j < K; ++j) vn[component[j]] += sum[j];
          }
        },
        kRowsWorthAThread);
  });
}

ConstrainedVector::~ConstrainedVector() = default;

// Each part in turn, every component of the block at once, on the calling thread: one pass over L serves all three
// for about 1.3 times the cost of one, less than a component per thread cost with its hand-over.
void ConstraintSystem::solve(const Block& block, std::vector<double>& y, std::vector<double>& work) const {
  const std::size_t k = block.phi.components.size();
  work.resize(factor_solve::record_width(k) * block.rows.size());
  for (const auto& part : block.parts) {
    const auto& L = part->factor.matrixL().nestedExpression();
    const factor_solve::LdltFactor factor{static_cast<std::size_t>(L.cols()),
                                          L.outerIndexPtr(),
                                          L.innerIndexPtr(),
                                          L.valuePtr(),
                                          part->factor.permutationP().indices().data(),
                                          part->inverse_diagonal.data()};
    factor_solve::solve(factor, part->rows.data(), k, y.data(), work.data());
  }
}

void ConstraintSystem::enforce(ConstrainedVector& u, double alpha) {
  for (Block& block : blocks_) {
    const std::size_t k = block.phi.components.size();
    u.values(block.phi, block.y);  // into the block's own vectors: no allocation in the time step
    for (std::size_t r = 0; r < block.rows.size(); ++r) {
      const Vec3& prescribed = sets_[block.rows[r].set]->values[block.rows[r].entry];
      for (std::size_t j = 0; j < k; ++j) block.y[k * r + j] = prescribed[block.phi.components[j]] - block.y[k * r + j];
    }
    solve(block, block.y, block.work);
    u.correct(block.phi, block.y);
    for (std::size_t r = 0; r < block.rows.size(); ++r) {
      Vec3& reaction = sets_[block.rows[r].set]->reactions[block.rows[r].entry];
      for (std::size_t j = 0; j < k; ++j) reaction[block.phi.components[j]] = block.y[k * r + j] / alpha;
    }
  }
}

namespace {
// A host vector as the projection's target.
class HostVector final : public ConstrainedVector {
 public:
  HostVector(std::span<double> v, ThreadTeam& team) : v_(v), team_(team) {}
  void values(const ConstraintBlock& block, std::vector<double>& out) override {
    constrained_values(block, v_, out, team_);
  }
  void correct(const ConstraintBlock& block, const std::vector<double>& y) override { add_correction(block, y, v_, team_); }

 private:
  std::span<double> v_;
  ThreadTeam& team_;
};
}  // namespace

void ConstraintSystem::enforce(std::span<double> u, double alpha) {
  HostVector vector(u, discretisation_.team());
  enforce(vector, alpha);
}

void ConstraintSystem::project_out(std::span<double> v) const {
  for (const Block& block : blocks_) {
    std::vector<double> y(block.y.size()), work;
    constrained_values(block.phi, v, y, discretisation_.team());
    for (double& value : y) value = -value;
    solve(block, y, work);
    add_correction(block.phi, y, v, discretisation_.team());
  }
}

void ConstraintSystem::add_constraint_forces(std::span<double> f) const {
  for (const Block& block : blocks_)
    for (std::size_t r = 0; r < block.rows.size(); ++r) {
      const Vec3& reaction = sets_[block.rows[r].set]->reactions[block.rows[r].entry];
      for (std::int64_t e = block.phi.row_offsets[r]; e < block.phi.row_offsets[r + 1]; ++e)
        for (int c : block.phi.components)
          f[3 * static_cast<std::size_t>(block.phi.row_nodes[e]) + c] += block.phi.row_values[e] * reaction[c];
    }
}

}  // namespace mtled
