// A boundary that pushes instead of prescribing, used only to exercise the kernel's force path
// (Driver::forces()): a total force, ramped with the load, split equally among the nodes of a group.
#include "mtled/discretisation.hpp"
#include "mtled/interfaces/driver.hpp"
#include "mtled/node_selector.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class TestNodalForce final : public BoundaryCondition {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("test only: a total force split equally among the nodes of a mesh group");
    d.string("group").doc("mesh node group").to<&Settings::group>();
    d.vector3("force").unit("N").doc("total force at the full load").to<&Settings::force>();
  }
  explicit TestNodalForce(const Parameters& p) : group_(p.read<Settings>().group), total_(p.read<Settings>().force) {
    forces_.name = "test_force";
  }
  void setup(const Discretisation& model) override {
    NodeSelector selector;
    selector.kind = NodeSelector::Kind::group;
    selector.group = group_;
    forces_.nodes = select_nodes(selector, model.mesh(), model.cloud().surface, "/boundaries");
    forces_.values.assign(forces_.nodes.size(), Vec3::Zero());
  }
  void update(const LoadState& load, const Discretisation&, std::span<const double>) override {
    for (Vec3& v : forces_.values) v = load.load_fraction * total_ / static_cast<double>(forces_.nodes.size());
  }
  std::vector<NodalConstraints*> constraints() override { return {}; }
  std::vector<NodalForces*> forces() override { return {&forces_}; }

 private:
  struct Settings {
    std::string group;
    Vec3 force = Vec3::Zero();
  };
  std::string group_;
  Vec3 total_;
  NodalForces forces_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::BoundaryCondition, mtled::TestNodalForce)
