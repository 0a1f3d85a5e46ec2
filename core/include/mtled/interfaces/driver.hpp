#pragma once
// Drivers move or push the body as the load proceeds: boundary conditions and needle models.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

class Discretisation;

// Displacements a driver prescribes: the *interpolated* displacement u(X_K) = sum_I N_I(X_K) u_I at each
// listed node K, or at each listed material point X_K (reference coordinates inside the body), for the
// constrained components. A set lists nodes or points, not both. The kernel enforces them after every step
// (the simplified essential-boundary-condition imposition of Joldes, Chowdhury, Wittek and Miller, EABE 2017)
// and writes back the reaction, the force the constraint exerts on the body at each entry.
//
// The entries and components change only through the members below, each of which advances revision():
// the kernel rebuilds and refactorises its constraint matrices exactly when the revision moved.
class NodalConstraints {
 public:
  std::string name;             // the "set" column of reactions.csv
  std::vector<Vec3> values;     // one per entry, set by the driver at every update
  std::vector<Vec3> reactions;  // one per entry, written by the kernel (N)

  const std::vector<Index>& nodes() const { return nodes_; }
  const std::vector<Vec3>& points() const { return points_; }
  const std::array<bool, 3>& components() const { return components_; }
  std::uint64_t revision() const { return revision_; }
  std::size_t size() const { return points_.empty() ? nodes_.size() : points_.size(); }
  Vec3 total_reaction() const;

  void set_components(const std::array<bool, 3>& components);
  // Replaces the entries by `nodes`, each prescribed `value`.
  void assign_nodes(std::vector<Index> nodes, const Vec3& value);
  void add_node(Index node, const Vec3& value);
  void add_point(const Vec3& point, const Vec3& value);
  // Keeps entry k (with its value and reaction) where keep[k] is true.
  void keep_entries(const std::vector<char>& keep);
  void clear();

 private:
  std::vector<Index> nodes_;
  std::vector<Vec3> points_;  // used instead of nodes_ when not empty
  std::array<bool, 3> components_{true, true, true};
  std::uint64_t revision_ = 0;
};

// Forces a driver applies (N), one per listed node, added to the external force vector at every step.
struct NodalForces {
  std::string name;
  std::vector<Index> nodes;
  std::vector<Vec3> values;  // set by the driver at every update
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
  virtual void setup(const Discretisation& model) = 0;
  // Sets the prescribed values (and, for drivers whose node sets change, the sets) for `load`, given the
  // current nodal parameters `u` (3 per node).
  virtual void update(const LoadState& load, const Discretisation& model, std::span<const double> u) = 0;
  // For a driver that reads only some of u: appends to `nodes` every node whose u_I the coming update(load, ...)
  // reads (the supports of what it interpolates included) and returns true. An engine that spreads the nodes over
  // processes then brings only those to every process before the update. False (the default): it may read any
  // node, and the whole displacement is gathered before each update.
  virtual bool nodes_read(const LoadState& load, const Discretisation& model, std::vector<Index>& nodes) const;
  // What this driver imposes: the constraint sets it prescribes and the force sets it applies, both filled
  // by update(). Pointers stay valid for the driver's lifetime; the lists are read once, after setup().
  virtual std::vector<NodalConstraints*> constraints() = 0;
  virtual std::vector<NodalForces*> forces() { return {}; }
};

class BoundaryCondition : public Driver {
 public:
  static constexpr Category category = Category::boundary;
  ~BoundaryCondition() override;
};

// The paper's two phases of an insertion (section 2.2.1): the tip indents the surface until it punctures it,
// then penetrates the tissue.
enum class NeedlePhase { indentation, penetration };
std::string_view to_string(NeedlePhase phase);

struct NeedleStatus {
  double depth = 0.0;             // m, tip advance along the needle direction
  double force = 0.0;             // N, force needed to impose the needle's effect, along the axis
  NeedlePhase phase = NeedlePhase::indentation;
  double puncture_depth = -1.0;   // m, negative until the needle punctures
  Index driven_nodes = 0;
  // The shaft in the reference configuration: from `entry` along `direction` (unit) to the tip at `depth`, `radius`
  // across: what the needle has swept through (the inversion monitor tells the tets it cut from folds elsewhere).
  Vec3 entry = Vec3::Zero();
  Vec3 direction = -Vec3::UnitZ();
  double radius = 0.0;  // m
};

class NeedleModel : public Driver {
 public:
  static constexpr Category category = Category::needle;
  ~NeedleModel() override;
  virtual NeedleStatus status() const = 0;
  // The path it will sweep, from its parameters alone (before setup): what a mesh refines along. None by default.
  virtual std::optional<PlannedPath> planned_path() const { return std::nullopt; }
};

}  // namespace mtled
