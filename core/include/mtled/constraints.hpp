#pragma once
// Essential boundary conditions for non-interpolating shape functions (simplified EBCIEM, Joldes,
// Chowdhury, Wittek, Miller, EABE 2017). After each unconstrained update u_pred the kernel applies
//   u = u_pred + M^-1 Phi^T y,   y = (Phi M^-1 Phi^T)^-1 (u_bar - Phi u_pred),
// per displacement component, where row K of Phi holds the shape functions at constrained node (or material
// point) K. Then the interpolated displacement there equals the prescribed one to round-off, and the
// reaction at K is lambda_K = y_K / alpha (alpha: the integrator's factor on M^-1 f in its update).
// The matrices are factorised when the constrained sets change, each independent part of them (rows coupled to no
// row outside it) on its own, so that a needle capturing nodes far from a fixed boundary leaves the boundary's
// factor as it was. Components with the same constrained rows (a fixed boundary, a needle held in every direction)
// share one matrix and are solved together, one pass over the factor for all of them.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <deque>
#include <memory>
#include <span>
#include <vector>

#include "mtled/discretisation.hpp"
#include "mtled/interfaces/driver.hpp"

namespace mtled {

class ThreadTeam;

// Phi for the constrained rows that some components share, in both orientations: by row for Phi v, by node for
// Phi^T y (so that threads, or a device's threads, take disjoint nodes). Vectors over the rows hold one value per
// component of the block, interleaved. `revision` changes whenever the blocks are rebuilt (a driver changed its
// sets, or the masses changed): a backend that holds copies re-reads them then.
struct ConstraintBlock {
  std::vector<int> components;
  std::int64_t rows = 0;
  std::vector<std::int64_t> row_offsets;  // Phi by row: entries row_offsets[r] .. row_offsets[r+1] - 1
  std::vector<Index> row_nodes;
  std::vector<double> row_values;
  std::vector<Index> nodes;                // the nodes Phi touches, each once
  std::vector<std::int64_t> node_offsets;  // Phi by node: entries node_offsets[k] .. node_offsets[k+1] - 1
  std::vector<Index> node_rows;
  std::vector<double> node_values;  // Phi(r, node) / m_node
  long revision = 0;
};

// The two products of the projection on a vector v of 3 unknowns per node, on the host (parallel on `team` when the
// block is large): out = Phi v (rows x components), and v += M^-1 Phi^T y.
void constrained_values(const ConstraintBlock& block, std::span<const double> v, std::vector<double>& out,
                        ThreadTeam& team);
void add_correction(const ConstraintBlock& block, const std::vector<double>& y, std::span<double> v, ThreadTeam& team);

// The vector a projection corrects, wherever it lives (host memory, or a device's: StepEngine).
class ConstrainedVector {
 public:
  virtual ~ConstrainedVector();
  virtual void values(const ConstraintBlock& block, std::vector<double>& out) = 0;      // out = Phi v
  virtual void correct(const ConstraintBlock& block, const std::vector<double>& y) = 0;  // v += M^-1 Phi^T y
};

class ConstraintSystem {
 public:
  explicit ConstraintSystem(const Discretisation& discretisation) : discretisation_(discretisation) {}

  // Rebuilds and refactorises when the sets, their revisions or the masses changed. A (node, component)
  // pair claimed by several sets is enforced by the first set only (boundaries come before the needle);
  // the later sets get a zero reaction there.
  void update(const std::vector<NodalConstraints*>& sets, std::span<const double> mass, bool mass_changed);
  void enforce(ConstrainedVector& u, double alpha);
  void enforce(std::span<double> u, double alpha);
  // f += Phi^T lambda: the nodal forces the constraints exerted in the last enforce().
  void add_constraint_forces(std::span<double> f) const;
  // v -= M^-1 Phi^T (Phi M^-1 Phi^T)^-1 Phi v: the M-orthogonal projection onto the increments that leave every
  // constrained value unchanged (the correction enforce() applies, for prescribed values held fixed). The
  // constrained dynamics live in that subspace; the stable-step monitor iterates in it.
  void project_out(std::span<double> v) const;
  long factorisations() const { return factorisations_; }      // rebuilds of the blocks
  long parts_factorised() const { return parts_factorised_; }  // parts' factors computed (the others were kept)
  std::size_t parts() const;                                   // independent parts now, over every block

 private:
  struct Row {
    std::size_t set;
    std::size_t entry;
  };
  // What a row constrains: its set and node, or its set and material point. Equal keys give equal rows of Phi
  // (for the same masses), so a part whose keys all reappear after a rebuild keeps its factor.
  struct RowKey {
    const NodalConstraints* set;
    Index node;  // -1 for a material point
    Vec3 point;
    bool operator==(const RowKey&) const = default;
  };
  // An independent diagonal block of A = Phi M^-1 Phi^T: rows whose supports share no node with any row outside it
  // (a fixed boundary far from the needle's captured nodes). Each part has its own factor, and a rebuild factorises
  // again only the parts whose rows changed.
  struct Part {
    std::vector<std::size_t> rows;  // into the block's rows, ascending
    std::vector<RowKey> keys;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor;
    std::vector<double> inverse_diagonal;  // of the factor's D
  };
  // A block with the rows it stands for and the factors of Phi M^-1 Phi^T's parts.
  struct Block {
    ConstraintBlock phi;
    std::vector<Row> rows;
    std::vector<std::unique_ptr<Part>> parts;
    std::vector<double> y, work;  // y: rows x components, the residual, then the multipliers; work: solve()'s scratch
  };
  void rebuild(std::span<const double> mass, bool reuse_factors);
  void build_block(Block& block, std::span<const double> mass, std::vector<std::unique_ptr<Part>>& reusable);
  void fill_phi(Block& block, std::span<const double> mass) const;
  void find_parts(Block& block) const;
  void factorise(Part& part, const ConstraintBlock& phi, std::span<const double> mass) const;
  // y = (Phi M^-1 Phi^T)^-1 y in place, for every component of the block at once (work: scratch).
  void solve(const Block& block, std::vector<double>& y, std::vector<double>& work) const;

  const Discretisation& discretisation_;
  std::vector<NodalConstraints*> sets_;
  std::vector<std::uint64_t> revisions_;
  std::deque<Block> blocks_;
  long factorisations_ = 0;
  long parts_factorised_ = 0;
};

}  // namespace mtled
