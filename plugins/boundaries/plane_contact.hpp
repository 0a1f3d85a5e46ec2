#pragma once
// Contact of the body's surface with a rigid plane (a platen, a table), enforced kinematically as the boundary
// conditions are (no penalty stiffness, so the explicit time step is untouched). A candidate node that has crossed
// the plane joins the contact: its interpolated displacement is prescribed so that it lies on the plane, along the
// normal only (frictionless) or in every direction (sticking: held where it touched). It leaves when the plane has
// had to pull it (its reaction along the normal tensile) for `release_steps` steps in a row: a node that merely
// touches the plane would otherwise leave and come back every other step, and each change refactorises the
// constraints. Used by `platen_contact` (a plane given in the scene) and by the node-set boundaries' `platen`
// option (the plane of the face they hold).
#include <string>
#include <vector>

#include "mtled/interfaces/driver.hpp"

namespace mtled {

// The release_steps of a platen whose face is bonded (the node-set boundaries' `platen`), and platen_contact's default.
inline constexpr long kPlatenReleaseSteps = 20;

class PlaneContact {
 public:
  struct Plane {
    Vec3 point = Vec3::Zero();         // in the reference configuration
    Vec3 normal = Vec3::UnitZ();       // unit, pointing into the body
    Vec3 displacement = Vec3::Zero();  // at full load; the plane moves by load_fraction x this
  };
  // `pointer`: the scene key an unusable normal is reported at. Frictionless needs a normal along x, y or z (the
  // kernel constrains whole Cartesian components).
  PlaneContact(std::string name, const Plane& plane, bool stick, long release_steps, const std::string& pointer);

  // The nodes that may touch the plane: `candidates` that lie on the body's side of it (farther than 1e-6 of the
  // body's size: those on it are held by another condition). Returns how many.
  std::size_t setup(const Discretisation& model, const std::vector<Index>& candidates);
  void update(const LoadState& load, const Discretisation& model, std::span<const double> u);
  NodalConstraints& constraints() { return set_; }
  bool sticks() const { return stick_; }

 private:
  // What a node in contact keeps: its tangential displacement (zero when frictionless), and for how many steps in a
  // row the plane has pulled on it.
  struct Entry {
    Vec3 tangential;
    long tensile_steps;
  };
  Vec3 on_plane(const Discretisation& model, Index node, const Vec3& tangential, const Vec3& point) const;
  void release_pulled_nodes();

  Plane plane_;
  bool stick_;
  long release_steps_;
  std::vector<Index> candidates_;
  std::vector<char> in_contact_;
  std::vector<Entry> entries_;  // one per entry of set_
  NodalConstraints set_;
};

// The nodes of the body's surface.
std::vector<Index> surface_node_list(const Discretisation& model);

}  // namespace mtled
