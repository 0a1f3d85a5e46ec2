#pragma once
// The refinement along a segment that every mesh generator offers (Gmsh's and the label map's), with one set of
// parameter names: a needle's path is known before meshing, and the cloud beside the shaft sets what the needle
// holds (docs/stability.md), so a scene grades the cloud along it. Header-only: the generators are separate plugins
// and the label map's must not link Gmsh.
#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <utility>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/log.hpp"
#include "mtled/markups.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

inline constexpr double kDefaultRefineRatio = 0.4;

// The size within `distance` of what is refined, growing linearly to the size elsewhere over `transition` (Gmsh's
// Threshold field).
struct RefinedSize {
  std::optional<double> ratio, size;  // at most one given; neither: kDefaultRefineRatio
  double distance = 0.0, transition = 0.0;

  // The size near the refined set where the size elsewhere is h (an absolute size above h refines nothing).
  double fine(double h) const { return size ? std::min(*size, h) : ratio.value_or(kDefaultRefineRatio) * h; }
  double at_distance(double d, double h) const {
    const double fine_size = fine(h);
    if (d <= distance) return fine_size;
    if (d >= distance + transition) return h;
    return fine_size + (h - fine_size) * (d - distance) / transition;
  }
};

// Declares refine_along_needle, refine_from, refine_to, refine_ratio, refine_size, refine_distance and
// refine_transition, bound to the members of the same names of `Settings` (bool along_needle, optional<Vec3> ends,
// optional<double> ratio, size and transition, double distance). `also` names what else the sizes apply to in this
// generator (" (and the rims, with refine_rims)").
template <class Settings>
void declare_path_refinement(ComponentDeclaration& declaration, const std::string& also = "") {
  declaration.boolean("refine_along_needle")
      .defaults(false)
      .doc(
          "refine the mesh along the scene's needle's path, from its entry to its tip at the final depth (its entry, "
          "direction and depth, or its trajectory's markups file, placed in the mesh's frame), instead of giving "
          "refine_from and refine_to; target_nodes then counts the refined mesh's nodes")
      .template to<&Settings::refine_along_needle>();
  declaration.vector3("refine_from")
      .optional()
      .unit("m")
      .doc(
          "with refine_to: refine the mesh along the segment between them (for a needle: its entry point and its tip "
          "at the final depth); target_nodes then counts the refined mesh's nodes")
      .template to<&Settings::refine_from>();
  declaration.vector3("refine_to")
      .optional()
      .unit("m")
      .doc("the other end of the segment to refine along")
      .template to<&Settings::refine_to>();
  declaration.number("refine_ratio")
      .optional()
      .greater_than(0.0)
      .at_most(1.0)
      .unit("1")
      .doc(fmt::format("mesh size near the segment{} as a fraction of mesh_size (default {:g}; or give refine_size)",
                       also, kDefaultRefineRatio))
      .template to<&Settings::refine_ratio>();
  declaration.number("refine_size")
      .optional()
      .positive()
      .unit("m")
      .doc(fmt::format(
          "mesh size near the segment{}, instead of refine_ratio: the same whatever mesh_size or target_nodes, so "
          "that clouds of one body share the spacing beside a needle's shaft, which sets the needle's force "
          "(docs/stability.md)",
          also))
      .template to<&Settings::refine_size>();
  declaration.number("refine_distance")
      .defaults(0.002)
      .positive()
      .unit("m")
      .doc(fmt::format("distance from the segment{} within which the refined size holds", also))
      .template to<&Settings::refine_distance>();
  declaration.number("refine_transition")
      .optional()
      .positive()
      .unit("m")
      .doc("distance beyond refine_distance over which the size grows back (default: 2 x refine_distance)")
      .template to<&Settings::refine_transition>();
}

// The segment of `settings` (none when neither end is given); throws InputError when one end is missing or both
// refine_ratio and refine_size are given.
template <class Settings>
std::optional<std::pair<Vec3, Vec3>> read_refined_segment(const Settings& settings, const Parameters& p) {
  const auto& from = settings.refine_from;
  const auto& to = settings.refine_to;
  if (static_cast<bool>(from) != static_cast<bool>(to))
    throw InputError(p.pointer(from ? "refine_to" : "refine_from"),
                     "refine_from and refine_to go together: give both ends of the segment to refine along (for a "
                     "needle, its entry point and its tip at the final depth)");
  if (settings.refine_ratio && settings.refine_size)
    throw InputError(p.pointer("refine_size"),
                     "give refine_ratio (a fraction of mesh_size) or refine_size (metres), not both");
  if (settings.refine_along_needle && from)
    throw InputError(p.pointer("refine_along_needle"),
                     "give refine_along_needle or refine_from and refine_to, not both: the needle's path is the "
                     "segment refine_along_needle refines along");
  if (!from) return std::nullopt;
  return std::make_pair(*from, *to);
}

// The segment to refine along when the mesh is made: refine_from and refine_to, or with refine_along_needle the
// scene's needle's planned path, placed in the mesh's frame `mesh_frame` ("LPS", "RAS", or empty: none recorded).
template <class Settings>
std::optional<std::pair<Vec3, Vec3>> refined_segment_for(const Settings& settings, const Parameters& p,
                                                         const MeshContext& context, const std::string& mesh_frame) {
  auto segment = read_refined_segment(settings, p);
  if (!settings.refine_along_needle) return segment;
  std::optional<PlannedPath> path;
  if (context.needle_path) path = context.needle_path();
  if (!path)
    throw InputError(p.pointer("refine_along_needle"),
                     "the scene has no needle whose path is known before meshing: add a \"needle\" section (entry, "
                     "direction and depth, or a trajectory), or give refine_from and refine_to");
  if (frames_differ(path->frame, mesh_frame))
    path->entry = flip_lps_ras(path->entry), path->tip = flip_lps_ras(path->tip);
  log().info("{}: refining along the needle's path from ({:.6g}, {:.6g}, {:.6g}) to ({:.6g}, {:.6g}, {:.6g}) m",
             p.pointer("refine_along_needle"), path->entry[0], path->entry[1], path->entry[2], path->tip[0],
             path->tip[1], path->tip[2]);
  return std::make_pair(path->entry, path->tip);
}

// A refined size with nothing to refine along (no segment, and no rims where `rims` is false) changes nothing: said,
// not refused, since a scene switches its refinement off by dropping the segment or the rims and may keep the size.
template <class Settings>
void warn_if_refining_nothing(const Settings& settings, const Parameters& p, bool rims) {
  if (settings.refine_from || settings.refine_along_needle || rims || (!settings.refine_ratio && !settings.refine_size))
    return;
  log().warn(
      "{} is given but refines nothing: refine_from and refine_to (or refine_along_needle) name the segment to "
      "refine along",
      p.pointer(settings.refine_size ? "refine_size" : "refine_ratio"));
}

template <class Settings>
RefinedSize read_refined_size(const Settings& settings) {
  return {settings.refine_ratio, settings.refine_size, settings.refine_distance,
          settings.refine_transition.value_or(2.0 * settings.refine_distance)};
}

// Distance from x to the segment [a, b].
inline double distance_to_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((x - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (x - (a + t * ab)).norm();
}

}  // namespace mtled
