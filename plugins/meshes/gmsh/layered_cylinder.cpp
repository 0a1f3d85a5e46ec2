// A cylinder of stacked layers with a conformal mesh across the interfaces: the paper's large sample
// (radius 32.5 mm; layers 18, 9 and 7 mm from the bottom; Table 2).
#include <fmt/format.h>

#include <set>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/plugin.hpp"
#include "support/cylinder_stack.hpp"
#include "support/generator.hpp"

namespace mtled {

class GmshLayeredCylinder final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Cylinder along +z of stacked layers (one region each), tet-meshed by Gmsh with shared nodes on "
        "the interfaces; node sets bottom, top, side, interface1 .. interface<N-1> (interface k lies "
        "between layer k and k + 1). The paper's large sample: radius 32.5 mm, layers 18, 9, 7 mm, "
        "32,276 nodes");
    declare_cylinder_axis(d);
    d.number_list("layer_heights")
        .at_least(kMinLength)
        .unit("m")
        .doc("thickness of each layer, bottom to top (at least one)")
        .to<&CylinderStack::layer_heights>();
    d.string_list("layer_names")
        .optional()
        .unit("1")
        .doc("region name of each layer, bottom to top, one per layer, distinct; default layer1 .. layerN")
        .to<&Settings::layer_names>();
    declare_mesh_size(d, 32276);
    declare_rim_refinement(d);
    d.example({{"radius", 0.0325}, {"layer_heights", {0.018, 0.009, 0.007}}, {"target_nodes", 2500}});
  }

  explicit GmshLayeredCylinder(const Parameters& p) : parameters_(p), stack_(p.read<CylinderStack>()) {
    const std::size_t layers = stack_.layer_heights.size();
    if (layers == 0)
      throw InputError(p.pointer("layer_heights"),
                       "no layers given: list the thickness of each layer from the bottom, e.g. [0.018, 0.009, 0.007]");
    if (const auto names = p.read<Settings>().layer_names) {
      stack_.layer_names = *names;
      check_names(p);
    } else {
      for (std::size_t k = 1; k <= layers; ++k) stack_.layer_names.push_back(fmt::format("layer{}", k));
    }
  }

  TetMesh load(const MeshContext& context) override {
    return mesh_cylinder_stack(parameters_, stack_, "layered_cylinder", "Gmsh layered cylinder", context);
  }

 private:
  void check_names(const Parameters& p) const {
    const auto& names = stack_.layer_names;
    if (names.size() != stack_.layer_heights.size())
      throw InputError(p.pointer("layer_names"),
                       fmt::format("{} names for {} layers: give one name per entry of layer_heights, bottom to top",
                                   names.size(), stack_.layer_heights.size()));
    std::set<std::string> seen;
    for (std::size_t k = 0; k < names.size(); ++k) {
      const std::string where = fmt::format("{}/{}", p.pointer("layer_names"), k);
      if (names[k].empty()) throw InputError(where, "a layer name is empty: name each layer (e.g. \"white_matter\")");
      if (!seen.insert(names[k]).second)
        throw InputError(where, fmt::format("layer name \"{}\" is used twice: each layer is its own region and "
                                            "needs its own name",
                                            names[k]));
    }
  }

  struct Settings {
    std::optional<std::vector<std::string>> layer_names;
  };
  Parameters parameters_;
  CylinderStack stack_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::GmshLayeredCylinder)
