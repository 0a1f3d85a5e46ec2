#pragma once
// A circular cylinder along +z made of stacked layers, shared by the "cylinder" (one layer) and
// "layered_cylinder" generators.
#include <string>
#include <vector>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/mesh.hpp"
#include "mtled/parameters.hpp"
#include "support/gmsh_model.hpp"

namespace mtled {

struct CylinderStack {
  Vec3 base_center = Vec3::Zero();       // centre of the bottom face (m)
  double radius = 0.0;                   // m
  std::vector<double> layer_heights;     // bottom to top (m)
  std::vector<std::string> layer_names;  // one region per layer
};

// Declares "radius" and "base_center", bound to CylinderStack's (Parameters::read<CylinderStack>).
void declare_cylinder_axis(ComponentDeclaration& declaration);

// Builds one OCC cylinder per layer and fragments them into one conformal body (shared nodes across the
// interfaces). Physical groups: one region per layer; node sets "bottom", "top", "side" and, between layer
// k and k + 1, "interface<k>".
GeometryMeasure build_cylinder_stack(const CylinderStack& stack);

// Tags of the curves bounding the "bottom" and "top" faces that build_cylinder_stack named: the two rims where
// they meet the side.
std::vector<int> cylinder_rim_curves();

// "radius 0.015 m, layers [0.018, 0.009, 0.007] m, base centre [0, 0, 0] m".
std::string describe(const CylinderStack& stack);

// The stack meshed by Gmsh with the generator's parameters (target_nodes, ...), its elements no larger than the radius
// and its rims kept sharp: the mesh of the `component` ("cylinder", "layered_cylinder") described as `title`.
TetMesh mesh_cylinder_stack(const Parameters& parameters, const CylinderStack& stack, const std::string& component,
                            const std::string& title, const MeshContext& context);

}  // namespace mtled
