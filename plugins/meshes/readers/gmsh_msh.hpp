#pragma once
// What the two ways of reading a .msh file share: mtled's own parser of ASCII MSH 2.2 / 4.1 (gmsh_file.cpp,
// with "file:line" in every message) and Gmsh's reader through its API (gmsh_api.cpp: binary files, and any
// file when the scene asks for "reader": "gmsh"). Both build the same TetMesh from the same physical groups.
#include <functional>
#include <span>
#include <string>

#include "mtled/mesh.hpp"
#include "mtled/io/mesh_file.hpp"

namespace mtled::msh {

constexpr long long kTetType = 4;  // MSH element type of the 4-node tetrahedron

// The refusal of a volume element that is not a 4-node tet, with what to change in Gmsh.
std::string volume_element_advice(long long type);

// Regions from each tet's physical volume tag (0: in none): one per tag, in ascending order, named by
// `name_of(tag)`, then "unassigned" for the tets in none (with a warning naming `label`); no tags at all:
// no regions (finish_mesh makes "all").
void assign_physical_regions(TetMesh& mesh, std::span<const long long> tet_physical,
                             const std::function<std::string(long long)>& name_of, const std::string& label);

// Whether the file's $MeshFormat line says binary (file-type 1).
bool is_binary(std::string_view text);

// The mesh of `file` as Gmsh's own reader sees it (any MSH version Gmsh reads, ASCII or binary). Gmsh's
// complaints become InputErrors naming the file. Only in builds with Gmsh (MTLED_WITH_GMSH).
TetMesh read_with_gmsh(const mesh_readers::MeshFileText& file);

}  // namespace mtled::msh
