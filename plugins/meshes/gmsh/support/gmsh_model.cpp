#include "support/gmsh_model.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <cmath>

#include "support/gmsh_session.hpp"

namespace mtled {

namespace {

constexpr int kTetrahedron = 4;  // Gmsh element type of a 4-node tetrahedron

}  // namespace

GeometryMeasure occ_geometry_measure() {
  GeometryMeasure measure;
  gmsh_checked([&] {
    for (const int tag : entity_tags(3)) {
      double mass = 0.0;
      gmsh::model::occ::getMass(3, tag, mass);
      measure.volume += mass;
    }
    for (const int tag : entity_tags(2)) {
      double mass = 0.0;
      gmsh::model::occ::getMass(2, tag, mass);
      measure.surface_area += mass;
    }
  });
  return measure;
}

std::vector<int> entity_tags(int dim) {
  gmsh::vectorpair dim_tags;
  gmsh_checked([&] { gmsh::model::getEntities(dim_tags, dim); });
  std::vector<int> tags;
  tags.reserve(dim_tags.size());
  for (const auto& [entity_dim, tag] : dim_tags) tags.push_back(tag);
  return tags;
}

std::vector<int> surfaces_in_plane(int axis, double coordinate, double tolerance) {
  std::vector<int> found;
  for (const int tag : entity_tags(2)) {
    double center[3];
    gmsh_checked([&] { gmsh::model::occ::getCenterOfMass(2, tag, center[0], center[1], center[2]); });
    if (std::abs(center[axis] - coordinate) <= tolerance) found.push_back(tag);
  }
  return found;
}

void add_named_group(int dim, const std::vector<int>& tags, const std::string& name) {
  if (tags.empty()) throw GmshError(fmt::format("the geometry has no entity for the group \"{}\"", name));
  gmsh_checked([&] {
    const int group = gmsh::model::addPhysicalGroup(dim, tags);
    gmsh::model::setPhysicalName(dim, group, name);
  });
}

std::vector<int> named_group_entities(int dim, const std::string& name) {
  std::vector<int> tags;
  gmsh_checked([&] {
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups, dim);
    for (const auto& [group_dim, group] : groups) {
      std::string group_name;
      gmsh::model::getPhysicalName(group_dim, group, group_name);
      if (group_name != name) continue;
      std::vector<int> entities;
      gmsh::model::getEntitiesForPhysicalGroup(group_dim, group, entities);
      tags.insert(tags.end(), entities.begin(), entities.end());
    }
  });
  return tags;
}

TetMesh extract_tet_mesh() {
  TetMesh mesh;
  gmsh_checked([&] {
    std::vector<std::size_t> node_tags;
    std::vector<double> coordinates, parametric;
    gmsh::model::mesh::getNodes(node_tags, coordinates, parametric, -1, -1, false, false);
    std::size_t max_tag = 0;
    for (const std::size_t tag : node_tags) max_tag = std::max(max_tag, tag);
    // Gmsh node tags are positive but not always contiguous: map them to 0-based indices.
    std::vector<Index> index_of(max_tag + 1, -1);
    mesh.points.resize(node_tags.size());
    for (std::size_t i = 0; i < node_tags.size(); ++i) {
      index_of[node_tags[i]] = static_cast<Index>(i);
      mesh.points[i] = Vec3(coordinates[3 * i], coordinates[3 * i + 1], coordinates[3 * i + 2]);
    }
    auto index = [&](std::size_t tag) {
      if (tag > max_tag || index_of[tag] < 0) throw GmshError("Gmsh returned an element with an unknown node");
      return index_of[tag];
    };

    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups, 3);
    for (const auto& [dim, group] : groups) {
      std::string name;
      gmsh::model::getPhysicalName(dim, group, name);
      const auto region = static_cast<Index>(mesh.region_names.size());
      mesh.region_names.push_back(name.empty() ? "region" + std::to_string(group) : name);
      std::vector<int> volumes;
      gmsh::model::getEntitiesForPhysicalGroup(dim, group, volumes);
      for (const int volume : volumes) {
        std::vector<std::size_t> element_tags, element_nodes;
        gmsh::model::mesh::getElementsByType(kTetrahedron, element_tags, element_nodes, volume);
        for (std::size_t e = 0; e < element_tags.size(); ++e) {
          mesh.tets.push_back({index(element_nodes[4 * e]), index(element_nodes[4 * e + 1]),
                               index(element_nodes[4 * e + 2]), index(element_nodes[4 * e + 3])});
          mesh.tet_region.push_back(region);
        }
      }
    }

    gmsh::model::getPhysicalGroups(groups, 2);
    for (const auto& [dim, group] : groups) {
      std::string name;
      gmsh::model::getPhysicalName(dim, group, name);
      std::vector<std::size_t> set_tags;
      std::vector<double> set_coordinates;
      gmsh::model::mesh::getNodesForPhysicalGroup(dim, group, set_tags, set_coordinates);
      std::vector<Index>& set = mesh.node_sets[name];
      for (const std::size_t tag : set_tags) set.push_back(index(tag));
      std::sort(set.begin(), set.end());
      set.erase(std::unique(set.begin(), set.end()), set.end());
    }
  });
  return mesh;
}

Index used_node_count(const TetMesh& mesh) {
  std::vector<char> used(mesh.points.size(), 0);
  for (const auto& tet : mesh.tets)
    for (const Index node : tet) used[static_cast<std::size_t>(node)] = 1;
  return static_cast<Index>(std::count(used.begin(), used.end(), 1));
}

}  // namespace mtled
