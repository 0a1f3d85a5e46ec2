#pragma once
// Reading and labelling the current Gmsh model: measures of the geometry for the node-count model, faces
// found by where they lie, named physical groups, and the generated mesh as an mtled TetMesh.
#include <string>
#include <vector>

#include "mtled/mesh.hpp"

namespace mtled {

// Volume and surface area of a geometry. The area counts internal interfaces too: their nodes count.
struct GeometryMeasure {
  double volume = 0.0;        // m^3
  double surface_area = 0.0;  // m^2
};

// Sum of OpenCASCADE masses over all volumes and all surfaces of the current model.
GeometryMeasure occ_geometry_measure();

// Tags of the surfaces whose centre of mass lies on the plane x[axis] = coordinate (axis 0, 1, 2 for x, y,
// z), within `tolerance` (m). For boxes and stacked cylinders only the flat faces in that plane qualify (a
// side face's centre lies halfway between its ends), and centres are exact where OCC bounding boxes carry
// the modeller's tolerance (1e-7 m and more), too coarse for thin layers.
std::vector<int> surfaces_in_plane(int axis, double coordinate, double tolerance);

// Tags of all entities of dimension `dim`.
std::vector<int> entity_tags(int dim);

// A physical group named `name` over the entities `tags` of dimension `dim` (3: a region, 2: a node set).
void add_named_group(int dim, const std::vector<int>& tags, const std::string& name);

// Tags of the entities of dimension `dim` in the physical group named `name` (empty when there is none).
std::vector<int> named_group_entities(int dim, const std::string& name);

// The current model's mesh: every node; the linear tets of each physical volume group, one region per
// group in tag order; the nodes of each physical surface group as a node set of the same name.
TetMesh extract_tet_mesh();

// Nodes that at least one tet uses (the node count the size calibration aims at).
Index used_node_count(const TetMesh& mesh);

}  // namespace mtled
