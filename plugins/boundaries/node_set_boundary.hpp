#pragma once
// A boundary condition that prescribes the interpolated displacement of a node set, for chosen components,
// as load_fraction x (d + G X): `fixed` has d = 0 and G = 0; `prescribed_displacement` takes d and G. With
// `platen`, the set is a flat face bonded to a rigid platen that moves with it, and the rest of the surface may not
// pass through the platen's plane (plane_contact.hpp).
#include <optional>

#include "mtled/interfaces/driver.hpp"
#include "mtled/node_selector.hpp"
#include "plane_contact.hpp"

namespace mtled {

class NodeSetBoundary : public BoundaryCondition {
 public:
  // Declares "nodes", "components", "name" and "platen" (shared by both plugins); "nodes" is read by
  // NodeSelector::from, the others into Selection.
  static void declare_selection(ComponentDeclaration& d);
  struct Selection {
    std::vector<std::string> components;
    std::optional<std::string> name;
    std::string platen;
  };
  NodeSetBoundary(const Parameters& parameters, Vec3 final_displacement, Mat3 final_gradient = Mat3::Zero());

  void setup(const Discretisation& model) override;
  void update(const LoadState& load, const Discretisation& model, std::span<const double> u) override;
  // Reads no displacement, except with a platen, whose contact looks at the whole surface (false: all of it).
  bool nodes_read(const LoadState&, const Discretisation&, std::vector<Index>&) const override { return !contact_; }
  std::vector<NodalConstraints*> constraints() override;

 private:
  void set_up_platen(const Discretisation& model, const std::vector<Index>& face);

  Parameters parameters_;
  NodeSelector selector_;
  Vec3 final_displacement_;
  Mat3 final_gradient_;
  std::vector<Vec3> positions_;
  NodalConstraints set_;
  std::string platen_;                   // "none", "frictionless" or "stick"
  std::optional<PlaneContact> contact_;  // with a platen: the rest of the surface against its plane
};

}  // namespace mtled
