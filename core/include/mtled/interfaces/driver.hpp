#pragma once
// Drivers move or push the body as the load proceeds: boundary conditions and needle models.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

class Model;

// Displacements a driver prescribes: the *interpolated* displacement u(X_K) = sum_I N_I(X_K) u_I at each
// listed node K, or at each listed material point X_K (reference coordinates inside the body), for the
// constrained components. A set lists nodes or points, not both. The kernel enforces them after every step
// (simplified EBCIEM) and writes back the reaction, the force the constraint exerts on the body at each entry.
struct NodalConstraints {
  std::string name;  // the "set" column of reactions.csv
  std::vector<Index> nodes;
  std::vector<Vec3> points;  // used instead of `nodes` when not empty
  std::array<bool, 3> components{true, true, true};
  std::vector<Vec3> values;     // one per entry
  std::vector<Vec3> reactions;  // one per entry, written by the kernel (N)
  std::uint64_t revision = 0;   // bump when `nodes`, `points` or `components` change

  std::size_t size() const { return points.empty() ? nodes.size() : points.size(); }
  Vec3 total_reaction() const;
};

struct LoadState {
  double time = 0.0;           // s (pseudo-time for dynamic relaxation)
  double load_fraction = 0.0;  // 0 at the start, 1 when the full load is applied
  long step = 0;
};

class Driver {
 public:
  virtual ~Driver();
  // Chooses nodes; throws InputError naming the scene pointer when the scene cannot be honoured.
  virtual void setup(const Model& model) = 0;
  // Sets the prescribed values (and, for drivers whose node sets change, the sets) for `load`, given the
  // current nodal parameters `u` (3 per node).
  virtual void update(const LoadState& load, const Model& model, std::span<const double> u) = 0;
  // The constraint sets this driver owns; pointers stay valid for the driver's lifetime.
  virtual std::vector<NodalConstraints*> constraints() = 0;
  // Drivers that push instead of prescribing (contact) add nodal forces here.
  virtual bool applies_forces() const { return false; }
  virtual void add_forces(const LoadState& load, const Model& model, std::span<const double> u,
                          std::span<double> f_ext);
};

class BoundaryCondition : public Driver {
 public:
  static constexpr Category category = Category::boundary;
  ~BoundaryCondition() override;
};

struct NeedleStatus {
  double depth = 0.0;             // m, tip advance along the needle direction
  double force = 0.0;             // N, force needed to impose the needle's effect, along the axis
  std::string phase = "indentation";  // "indentation" or "penetration"
  double puncture_depth = -1.0;   // m, negative until the needle punctures
  Index driven_nodes = 0;
};

class NeedleModel : public Driver {
 public:
  static constexpr Category category = Category::needle;
  ~NeedleModel() override;
  virtual NeedleStatus status() const = 0;
};

}  // namespace mtled
