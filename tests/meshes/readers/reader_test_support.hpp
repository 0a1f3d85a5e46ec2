#pragma once
// Helpers of the mesh-reader tests: reading a file through the real plugin, catching the InputError a bad
// file must give, and a form of a TetMesh that does not depend on the order of nodes and tets, so that one
// mesh read from different formats can be compared.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/mesh.hpp"
#include "test_support.hpp"

namespace mtled::test {

// tests/data/meshes in the source tree.
std::filesystem::path fixtures();

// Builds `reader` from `block` and loads the mesh with `directory` as the scene's folder.
TetMesh read_mesh(const std::string& reader, const json& block, const std::filesystem::path& directory = fixtures());

// The InputError loading must throw (a test failure, and an empty error, when it throws nothing).
InputError read_error(const std::string& reader, const json& block,
                      const std::filesystem::path& directory = fixtures());

// A scratch folder `folder` (under the tests' scratch root) holding one file `name` with `text`; returns the folder.
std::filesystem::path folder_with_file(const std::string& folder, const std::string& name, const std::string& text);

// The first problem's "where" and message.
std::string where_of(const InputError& error);
std::string message_of(const InputError& error);

// A mesh up to the numbering of its nodes and tets: points as coordinates, tets as sets of corners, regions
// by (renamed) name, node sets as sets of coordinates.
using Point = std::array<double, 3>;
struct CanonicalMesh {
  std::vector<Point> points;                                      // sorted
  std::map<std::string, std::multiset<std::set<Point>>> regions;  // region -> its tets
  std::map<std::string, std::set<Point>> node_sets;
  bool operator==(const CanonicalMesh&) const = default;
};
// `rename` maps region names (such as the numbers of a VTK region array) to the names to compare; a
// `quantum` > 0 rounds coordinates to its multiples (for writers that print fewer digits than others).
CanonicalMesh canonical(const TetMesh& mesh, const std::map<std::string, std::string>& rename = {},
                        double quantum = 0.0);
std::ostream& operator<<(std::ostream& out, const CanonicalMesh& mesh);

// The reference two-box cube of tests/data/meshes (README.md there): 12 nodes, 12 tets, regions "left"
// and "right", node sets "bottom" and "top", built here from its definition, not read from a file.
CanonicalMesh reference_cube();

// Sum of |tet volume|.
double total_volume(const TetMesh& mesh);

}  // namespace mtled::test
