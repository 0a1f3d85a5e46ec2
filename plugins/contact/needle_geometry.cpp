#include "mtled/needle/needle_geometry.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>

#include <algorithm>

#include "mtled/errors.hpp"
#include "mtled/json.hpp"
#include "mtled/log.hpp"
#include "mtled/markups.hpp"

namespace mtled {

void declare_needle_path(ComponentDeclaration& d) {
  d.number("diameter")
      .unit("m")
      .positive()
      .defaults(1.6e-3)
      .doc("needle shaft diameter (the paper: 1.6 mm)")
      .to<&NeedlePathSettings::diameter>();
  d.vector3("entry")
      .unit("m")
      .optional()
      .doc("point on the body surface where the tip enters (reference coordinates); give it or trajectory")
      .to<&NeedlePathSettings::entry>();
  d.vector3("direction")
      .unit("1")
      .nonzero()
      .optional()
      .doc("insertion direction (normalised internally); default (0, 0, -1), or from the trajectory")
      .to<&NeedlePathSettings::direction>();
  d.number("depth")
      .unit("m")
      .positive()
      .optional()
      .doc(
          "final insertion depth: the tip's advance from the entry point; needed with entry, with trajectory the "
          "distance from its entry to its target unless given")
      .to<&NeedlePathSettings::depth>();
  d.file("trajectory")
      .optional()
      .doc(
          "instead of entry and direction: a 3D Slicer markups file (.mrk.json) whose line (or first two points) runs "
          "from the entry to the target, in its coordinateSystem (LPS or RAS) and coordinateUnits (mm); placed in the "
          "mesh's frame when the mesh records one (a label map's)")
      .to<&NeedlePathSettings::trajectory>();
}

void declare_strain_radius(ComponentDeclaration& d) {
  d.number("strain_radius")
      .unit("m")
      .positive()
      .optional()
      .doc(
          "integration points within this distance of the tip are watched for the puncture strain; default: the "
          "larger of the needle diameter and the node spacing at the entry")
      .to<&TipStrainSettings::strain_radius>();
}

namespace {

// A needle's trajectory: the markup's first two placed points, the entry then the target.
MarkupsTrajectory trajectory_of(const MarkupsPoints& markups, const std::string& label) {
  const auto& points = markups.points;
  if (points.size() < 2)
    throw InputError(label + ": /markups/0/controlPoints",
                     fmt::format("the {} has {} placed control point{}; a needle trajectory needs two, the entry and "
                                 "then the target (a Line markup, or a point list's first two points)",
                                 markups.type.empty() ? "markup" : markups.type, points.size(),
                                 points.size() == 1 ? "" : "s"));
  if ((points[1].position - points[0].position).norm() == 0.0)
    throw InputError(label + ": /markups/0/controlPoints",
                     "the entry and the target are the same point: the trajectory has no direction");
  return {points[0].position, points[1].position, markups.frame};
}

}  // namespace

MarkupsTrajectory read_markups_trajectory(const std::filesystem::path& file) {
  return trajectory_of(read_markups(file), file.string());
}

MarkupsTrajectory parse_markups_trajectory(const std::string& text, const std::string& label) {
  return trajectory_of(parse_markups(text, label), label);
}

NeedlePath read_needle_path(const Parameters& p) {
  const auto given = p.read<NeedlePathSettings>();
  NeedlePath path;
  path.radius = 0.5 * given.diameter;
  if (given.trajectory) {
    for (const auto& [name, value] : {std::pair{"entry", given.entry}, std::pair{"direction", given.direction}})
      if (value)
        throw InputError(p.pointer(name), fmt::format("give either \"trajectory\" or \"entry\" and \"direction\", "
                                                      "not both: the trajectory's line sets the {}",
                                                      name));
    const MarkupsTrajectory trajectory = read_markups_trajectory(*given.trajectory);
    path.frame = trajectory.frame;
    path.trajectory = *given.trajectory;
    path.entry = trajectory.entry;
    path.direction = (trajectory.target - trajectory.entry).normalized();
    path.depth = given.depth.value_or((trajectory.target - trajectory.entry).norm());
    return path;
  }
  if (!given.entry)
    throw InputError(p.pointer("entry"), "missing: the needle needs \"entry\" (m, a point on the body's surface) or "
                                         "\"trajectory\" (a 3D Slicer markups file from the entry to the target)");
  if (!given.depth)
    throw InputError(p.pointer("depth"), "missing: how far the tip advances from the entry (m), e.g. 0.02");
  path.entry = *given.entry;
  path.direction = given.direction.value_or(-Vec3::UnitZ()).normalized();
  path.depth = *given.depth;
  return path;
}

std::vector<Index> footprint_nodes(const NeedlePath& path, const Discretisation& model, double spacing, double radius) {
  const auto& surface = model.cloud().surface;
  Index nearest = -1;
  double nearest_distance = INFINITY;
  std::vector<Index> footprint;
  for (Index i = 0; i < model.node_count(); ++i) {
    if (!surface[i]) continue;
    const Vec3& x = model.nodes()[i];
    const double distance = (x - path.entry).norm();
    if (distance < nearest_distance) {
      nearest_distance = distance;
      nearest = i;
    }
    if (std::abs(path.axial(x)) <= 0.5 * spacing && path.radial(x) <= radius) footprint.push_back(i);
  }
  if (footprint.empty()) footprint.push_back(nearest);
  return footprint;
}

double spacing_at_entry(const NeedlePath& path, const Discretisation& model) {
  std::vector<Index> nearest;
  model.cloud().search->nearest(path.entry, 8, nearest);
  double sum = 0.0;
  for (Index i : nearest) sum += model.cloud().spacing[i];
  return nearest.empty() ? 0.0 : sum / static_cast<double>(nearest.size());
}

void place_needle_path(NeedlePath& path, const Discretisation& model, const Parameters& p) {
  const std::string& mesh_frame = model.mesh().coordinate_system;
  if (frames_differ(path.frame, mesh_frame)) {
    path.entry = flip_lps_ras(path.entry);
    path.direction = flip_lps_ras(path.direction);
    path.frame = mesh_frame;
  }
  const bool from_markups = !path.frame.empty();
  const std::string frame_said = mesh_frame.empty() ? path.frame + " as given: the mesh records none" : mesh_frame;
  if (from_markups)  // say where the markups put it, in the mesh's coordinates
    log().info(
        "needle trajectory {}: entry ({:.6g}, {:.6g}, {:.6g}) m, direction ({:.4g}, {:.4g}, {:.4g}), depth {:.4g} mm, "
        "in the mesh's frame ({})",
        path.trajectory.filename().string(), path.entry[0], path.entry[1], path.entry[2], path.direction[0] + 0.0,
        path.direction[1] + 0.0, path.direction[2] + 0.0, 1e3 * path.depth,  // no "-0"
        frame_said);
  const auto& surface = model.cloud().surface;
  std::vector<Index> nearest;
  model.cloud().search->nearest(path.entry, 64, nearest);
  double distance = INFINITY;
  Index closest = -1;
  for (Index i : nearest) {
    if (!surface[i]) continue;
    const double d = (model.nodes()[i] - path.entry).norm();
    if (d < distance) {
      distance = d;
      closest = i;
    }
  }
  const double spacing = spacing_at_entry(path, model);
  if (closest < 0 || distance > 1.5 * spacing) {
    const Vec3 x = closest >= 0 ? model.nodes()[closest] : Vec3::Zero();
    throw InputError(p.pointer(from_markups ? "trajectory" : "entry"),
                     fmt::format("the entry point ({:.6g}, {:.6g}, {:.6g}) m is {:.3g} mm from the body's surface "
                                 "(nearest surface node at ({:.6g}, {:.6g}, {:.6g}) m; local node spacing {:.3g} mm): "
                                 "the needle must enter through the surface; {}",
                                 path.entry[0], path.entry[1], path.entry[2], 1e3 * distance, x[0], x[1], x[2],
                                 1e3 * spacing,
                                 from_markups ? "the trajectory's first point, in the mesh's frame (" + frame_said + ")"
                                              : std::string("entry is in metres")));
  }
  // Some nodes must lie ahead of the entry, near the axis, within the insertion depth.
  const double reach = std::max(path.radius, spacing);
  int ahead = 0;
  for (const auto& x : model.nodes()) {
    const double s = path.axial(x);
    if (s > 0.25 * spacing && s <= path.depth && path.radial(x) <= reach) ++ahead;
  }
  if (ahead == 0)
    throw InputError(p.pointer(from_markups ? "trajectory" : "direction"),
                     fmt::format("the needle path from the entry along ({:.3g}, {:.3g}, {:.3g}) meets no node of the "
                                 "body within the depth of {:.3g} mm: does the direction point into the body?",
                                 path.direction[0], path.direction[1], path.direction[2], 1e3 * path.depth));
}

void TipStrainWatch::setup(const NeedlePath& path, const Discretisation& model, double radius) {
  radius_ = radius;
  watched_.clear();
  for (Index ip = 0; ip < model.points().count(); ++ip)
    if ((model.points().positions[ip] - path.entry).norm() <= radius + path.depth) watched_.push_back(ip);
}

void TipStrainWatch::append_nodes_read(const Discretisation& model, const Vec3& tip, std::vector<Index>& nodes) const {
  for (Index ip : watched_)
    if ((model.points().positions[ip] - tip).norm() <= radius_) model.gradients().append_nodes(ip, nodes);
}

double TipStrainWatch::largest(const Discretisation& model, std::span<const double> u, const Vec3& tip) const {
  double largest = 0.0;
  for (Index ip : watched_) {
    if ((model.points().positions[ip] - tip).norm() > radius_) continue;
    const Mat3 F = model.deformation_gradient(ip, u);
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const Eigen::SelfAdjointEigenSolver<Mat3> eigen(E, Eigen::EigenvaluesOnly);
    largest = std::max(largest, eigen.eigenvalues().cwiseAbs().maxCoeff());
  }
  return largest;
}

}  // namespace mtled
