#include "support/cylinder_stack.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gmsh.h>

#include <algorithm>
#include <cmath>

#include "support/generator.hpp"
#include "support/gmsh_session.hpp"

namespace mtled {

void declare_cylinder_axis(ComponentDeclaration& declaration) {
  declaration.number("radius")
      .at_least(kMinLength)
      .unit("m")
      .doc("radius of the cylinder")
      .to<&CylinderStack::radius>();
  declaration.vector3("base_center")
      .defaults({0.0, 0.0, 0.0})
      .unit("m")
      .doc("centre of the bottom face; the axis runs along +z from it")
      .to<&CylinderStack::base_center>();
}

GeometryMeasure build_cylinder_stack(const CylinderStack& stack) {
  const Vec3& c = stack.base_center;
  std::vector<double> levels{c[2]};  // z of the bottom, the interfaces and the top
  for (const double height : stack.layer_heights) levels.push_back(levels.back() + height);
  gmsh_checked([&] {
    gmsh::vectorpair layers;
    for (std::size_t k = 0; k < stack.layer_heights.size(); ++k)
      layers.emplace_back(
          3, gmsh::model::occ::addCylinder(c[0], c[1], levels[k], 0.0, 0.0, stack.layer_heights[k], stack.radius));
    if (layers.size() > 1) {
      // Fragmenting makes the layers share their interface faces, so the mesh is conformal across them.
      gmsh::vectorpair fragments;
      std::vector<gmsh::vectorpair> origin;
      gmsh::model::occ::fragment({layers.front()}, gmsh::vectorpair(layers.begin() + 1, layers.end()), fragments,
                                 origin);
    }
    gmsh::model::occ::synchronize();
  });

  // Each volume goes to the layer that holds its centre of mass.
  std::vector<std::vector<int>> layer_volumes(stack.layer_heights.size());
  for (const int volume : entity_tags(3)) {
    double x = 0.0, y = 0.0, z = 0.0;
    gmsh_checked([&] { gmsh::model::occ::getCenterOfMass(3, volume, x, y, z); });
    const auto above = std::upper_bound(levels.begin(), levels.end(), z);
    if (above == levels.begin() || above == levels.end()) throw GmshError("a layer volume lies outside the stack");
    layer_volumes[static_cast<std::size_t>(above - levels.begin() - 1)].push_back(volume);
  }
  for (std::size_t k = 0; k < layer_volumes.size(); ++k) add_named_group(3, layer_volumes[k], stack.layer_names[k]);

  // Faces found by where they lie: a side face's centre is half a layer away from the planes.
  const double thinnest = *std::min_element(stack.layer_heights.begin(), stack.layer_heights.end());
  const double tolerance = 1e-6 * thinnest;
  std::vector<int> flat;
  for (std::size_t k = 0; k < levels.size(); ++k) {
    const std::vector<int> disks = surfaces_in_plane(2, levels[k], tolerance);
    flat.insert(flat.end(), disks.begin(), disks.end());
    const std::string name = k == 0 ? "bottom" : k + 1 == levels.size() ? "top" : fmt::format("interface{}", k);
    add_named_group(2, disks, name);
  }
  std::vector<int> side;
  for (const int surface : entity_tags(2))
    if (std::find(flat.begin(), flat.end(), surface) == flat.end()) side.push_back(surface);
  add_named_group(2, side, "side");
  return occ_geometry_measure();
}

std::vector<int> cylinder_rim_curves() {
  std::vector<int> curves;
  for (const char* face : {"bottom", "top"})
    for (const int disk : named_group_entities(2, face)) {
      gmsh::vectorpair boundary;
      gmsh_checked([&] { gmsh::model::getBoundary({{2, disk}}, boundary, false, false, false); });
      for (const auto& [dim, tag] : boundary) curves.push_back(std::abs(tag));
    }
  return curves;
}

std::string describe(const CylinderStack& stack) {
  return fmt::format("radius {:.6g} m, layer heights [{:.6g}] m, base centre {} m", stack.radius,
                     fmt::join(stack.layer_heights, ", "), format_vector(stack.base_center));
}

TetMesh mesh_cylinder_stack(const Parameters& parameters, const CylinderStack& stack, const std::string& component,
                            const std::string& title, const MeshContext& context) {
  GeneratorRequest request;
  request.context = context;
  request.component = component;
  request.description = fmt::format("{}, {}", title, describe(stack));
  request.build_geometry = [&stack] { return build_cylinder_stack(stack); };
  request.max_mesh_size = GeneratorRequest::SizeLimit{stack.radius, "the radius"};
  request.rim_curves = cylinder_rim_curves;
  return generate_tet_mesh(parameters, request);
}

}  // namespace mtled
