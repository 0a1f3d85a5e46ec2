#pragma once
// Finding where a triangulated surface crosses itself, before Gmsh's 3D mesher fails on it with "PLC Error".
#include <array>
#include <optional>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

struct SurfaceCrossing {
  std::size_t first = 0, second = 0;  // facet indices
  Vec3 near = Vec3::Zero();           // a point of the first facet near the crossing
};

// The first pair of facets (in a deterministic order) that intersect other than along the edge or corner
// they share. Facets sharing an edge are not tested against each other (a fold there is not detected).
// Uses a uniform grid over the facets' bounding boxes: about linear in the facet count.
std::optional<SurfaceCrossing> find_self_intersection(const std::vector<Vec3>& vertices,
                                                      const std::vector<std::array<Index, 3>>& triangles);

}  // namespace mtled
