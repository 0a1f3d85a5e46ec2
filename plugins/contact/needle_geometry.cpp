#include "mtled/needle/needle_geometry.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>

namespace mtled {

void declare_needle_path(ComponentDeclaration& d) {
  d.number("diameter").unit("m").positive().defaults(1.6e-3).doc("needle shaft diameter (the paper: 1.6 mm)");
  d.vector3("entry").unit("m").doc("point on the body surface where the tip enters (reference coordinates)");
  d.vector3("direction").unit("1").nonzero().defaults(json::array({0, 0, -1})).doc(
      "insertion direction (normalised internally)");
  d.number("depth").unit("m").positive().doc("final insertion depth: the tip's advance from the entry point");
}

NeedlePath read_needle_path(const Parameters& p) {
  NeedlePath path;
  path.entry = p.vector3("entry");
  path.direction = p.vector3("direction").normalized();
  path.depth = p.number("depth");
  path.radius = 0.5 * p.number("diameter");
  return path;
}

std::vector<Index> footprint_nodes(const NeedlePath& path, const ModelView& model, double spacing, double radius) {
  const auto& surface = model.surface();
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

double spacing_at_entry(const NeedlePath& path, const ModelView& model) {
  std::vector<Index> nearest;
  model.node_search().nearest(path.entry, 8, nearest);
  double sum = 0.0;
  for (Index i : nearest) sum += model.node_spacing()[i];
  return nearest.empty() ? 0.0 : sum / static_cast<double>(nearest.size());
}

void check_needle_enters_body(const NeedlePath& path, const ModelView& model, const Parameters& p) {
  const auto& surface = model.surface();
  std::vector<Index> nearest;
  model.node_search().nearest(path.entry, 64, nearest);
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
    throw InputError(p.pointer("entry"),
                     fmt::format("the entry point ({:.6g}, {:.6g}, {:.6g}) m is {:.3g} mm from the body's surface "
                                 "(nearest surface node at ({:.6g}, {:.6g}, {:.6g}) m; local node spacing {:.3g} mm): "
                                 "the needle must enter through the surface; entry is in metres",
                                 path.entry[0], path.entry[1], path.entry[2], 1e3 * distance, x[0], x[1], x[2],
                                 1e3 * spacing));
  }
  // Some nodes must lie ahead of the entry, near the axis, within the insertion depth.
  const double reach = std::max(path.radius, spacing);
  int ahead = 0;
  for (const auto& x : model.nodes()) {
    const double s = path.axial(x);
    if (s > 0.25 * spacing && s <= path.depth && path.radial(x) <= reach) ++ahead;
  }
  if (ahead == 0)
    throw InputError(p.pointer("direction"),
                     fmt::format("the needle path from the entry along ({:.3g}, {:.3g}, {:.3g}) meets no node of the "
                                 "body within the depth of {:.3g} mm: does the direction point into the body?",
                                 path.direction[0], path.direction[1], path.direction[2], 1e3 * path.depth));
}

void TipStrainWatch::setup(const NeedlePath& path, const ModelView& model, double radius) {
  radius_ = radius;
  watched_.clear();
  for (Index ip = 0; ip < model.integration_point_count(); ++ip)
    if ((model.ip_positions()[ip] - path.entry).norm() <= radius + path.depth) watched_.push_back(ip);
}

double TipStrainWatch::largest(const ModelView& model, std::span<const double> u, const Vec3& tip) const {
  double largest = 0.0;
  for (Index ip : watched_) {
    if ((model.ip_positions()[ip] - tip).norm() > radius_) continue;
    const Mat3 F = model.deformation_gradient(ip, u);
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const Eigen::SelfAdjointEigenSolver<Mat3> eigen(E, Eigen::EigenvaluesOnly);
    largest = std::max(largest, eigen.eigenvalues().cwiseAbs().maxCoeff());
  }
  return largest;
}

}  // namespace mtled
