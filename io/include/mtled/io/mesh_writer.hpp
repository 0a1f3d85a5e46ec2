#pragma once
// Writes a TetMesh as an Abaqus input file that the abaqus_file reader reads back to the same mesh: the nodes with
// every digit (%.17g), the tets in their order (one *ELEMENT block per run of tets of one region, ELSET = the region),
// every node set as an *NSET. For machines without Gmsh (a GPU node of a cluster: docs/gpu.md), a scene's generated
// mesh is written once with `mtled mesh` and read there.
#include <filesystem>

#include "mtled/mesh.hpp"

namespace mtled {

// Throws InputError naming the file when it cannot be written, or a set name Abaqus cannot hold (a comma).
void write_abaqus_mesh(const TetMesh& mesh, const std::filesystem::path& file);

}  // namespace mtled
