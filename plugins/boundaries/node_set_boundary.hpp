#pragma once
// A boundary condition that prescribes the interpolated displacement of a node set, for chosen components,
// as load_fraction x (d + G X): `fixed` has d = 0 and G = 0; `prescribed_displacement` takes d and G.
#include "mtled/interfaces/driver.hpp"
#include "mtled/node_selector.hpp"

namespace mtled {

class NodeSetBoundary : public BoundaryCondition {
 public:
  // Declares "nodes", "components" and "name" (shared by both plugins); "nodes" is read by NodeSelector::from, the
  // others into Selection.
  static void declare_selection(ComponentDeclaration& d);
  struct Selection {
    std::vector<std::string> components;
    std::optional<std::string> name;
  };
  NodeSetBoundary(const Parameters& parameters, Vec3 final_displacement, Mat3 final_gradient = Mat3::Zero());

  void setup(const Discretisation& model) override;
  void update(const LoadState& load, const Discretisation& model, std::span<const double> u) override;
  bool nodes_read(const LoadState&, const Discretisation&, std::vector<Index>&) const override { return true; }  // none
  std::vector<NodalConstraints*> constraints() override { return {&set_}; }

 private:
  Parameters parameters_;
  NodeSelector selector_;
  Vec3 final_displacement_;
  Mat3 final_gradient_;
  std::vector<Vec3> positions_;
  NodalConstraints set_;
};

}  // namespace mtled
