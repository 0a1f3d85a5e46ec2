#pragma once
// Which nodes a boundary condition (or anything else) acts on: a named group of the mesh (physical group,
// NSET) or a geometric test on reference coordinates. Scene syntax, one of:
//   {"group": "bottom"}
//   {"plane": {"point": [x,y,z], "normal": [x,y,z]}}            nodes on the plane
//   {"box": {"min": [x,y,z], "max": [x,y,z]}}                    nodes inside the box
//   {"cylinder": {"point": [..], "direction": [..], "radius": r}} nodes within r of the axis line
//   {"sphere": {"center": [..], "radius": r}}                    nodes within r of the centre
// with optional "tolerance" (m; default 1e-6 of the mesh's bounding-box diagonal) and "surface_only"
// (only nodes on the body's boundary; default false).
#include <optional>
#include <string>
#include <vector>

#include "mtled/errors.hpp"
#include "mtled/json.hpp"
#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

struct NodeSelector {
  enum class Kind { group, plane, box, cylinder, sphere };
  Kind kind = Kind::group;
  std::string group;
  Vec3 point = Vec3::Zero();      // plane point, cylinder axis point, sphere centre
  Vec3 direction = Vec3::UnitZ();  // plane normal, cylinder axis (unit)
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
  double radius = 0.0;
  std::optional<double> tolerance;
  bool surface_only = false;

  // Parses and checks a selector; problems get JSON pointers below `pointer`.
  static std::optional<NodeSelector> parse(const nlohmann::json& value, const std::string& pointer,
                                           std::vector<Problem>& problems);
  // The syntax a component declares a node-set parameter with (ComponentDeclaration::node_set), and the selector it
  // reads back from its validated parameters.
  static ValueSyntax syntax();
  static NodeSelector from(const Parameters& parameters, std::string_view name);
  // Geometric test (group selectors are resolved against the mesh's named node sets instead).
  bool contains(const Vec3& x, double tol) const;
  std::string describe() const;
  static nlohmann::json json_schema();
};

}  // namespace mtled
