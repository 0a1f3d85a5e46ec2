// A circular cylinder meshed with Gmsh: the paper's small silicone-gel sample (radius 15 mm, height 17 mm).
#include <fmt/format.h>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/plugin.hpp"
#include "support/cylinder_stack.hpp"
#include "support/generator.hpp"

namespace mtled {

class GmshCylinder final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Circular cylinder along +z from base_center, tet-meshed by Gmsh; node sets bottom, top, side; "
        "region \"all\". The paper's small sample (r = 15 mm, h = 17 mm) used grids of 7,480 / 17,730 / "
        "30,294 nodes");
    declare_cylinder_axis(d);
    d.number("height").at_least(kMinLength).unit("m").doc("height along +z").to<&Settings::height>();
    declare_mesh_size(d, 7480);
    declare_rim_refinement(d);
    d.example({{"radius", 0.015}, {"height", 0.017}, {"target_nodes", 2000}});
  }

  explicit GmshCylinder(const Parameters& p) : parameters_(p), stack_(p.read<CylinderStack>()) {
    stack_.layer_heights = {p.read<Settings>().height};
    stack_.layer_names = {"all"};
  }

  TetMesh load(const MeshContext& context) override {
    return mesh_cylinder_stack(parameters_, stack_, "cylinder", "Gmsh cylinder", context);
  }

 private:
  struct Settings {
    double height = 0.0;
  };
  Parameters parameters_;
  CylinderStack stack_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::GmshCylinder)
