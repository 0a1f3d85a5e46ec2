#include "inversion_monitor.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "mtled/discretisation.hpp"
#include "mtled/instability.hpp"
#include "mtled/log.hpp"

namespace mtled {

void InversionMonitor::declare(ComponentDeclaration& d) {
  d.integer("inversion_every_steps")
      .defaults(100)
      .non_negative()
      .unit("1")
      .doc(
          "move the background tets by the interpolated displacements at their vertices every this many steps and "
          "after the last, and find those turned inside out: material folded between integration points, which no "
          "point's J shows; 0 turns the check off")
      .to<&Settings::inversion_every_steps>();
  d.string("inversion")
      .defaults("stop")
      .choices({"warn", "stop"})
      .doc(
          "what background tets turned inside out away from the needle's path do: \"stop\" ends the run (status "
          "\"unstable\", what \"inverted_between_points\"); \"warn\" logs the first and records them in summary.json "
          "(monitors.inversion). Tets around the needle's path (a vertex within the needle's radius plus that node's "
          "support radius of the swept shaft) fold because the kinematic needle cannot cut the tissue: they are "
          "counted as cut (monitors.inversion.cut_tets), not folds. Slivers (radius ratio under 0.1; the shipped "
          "scenes' meshes have none) are not judged: they turn over when the interpolated field departs from affine by "
          "their thickness, which a relaxation's transient does without the material folding "
          "(monitors.inversion.slivers_inverted)")
      .to<&Settings::inversion>();
}

std::unique_ptr<InversionMonitor> InversionMonitor::from_section(const Parameters& monitors, FoldAdvice advice,
                                                                 std::shared_ptr<FoldedTets> folded) {
  const auto settings = monitors.read<Settings>();
  if (settings.inversion_every_steps == 0) return nullptr;
  return std::make_unique<InversionMonitor>(settings.inversion_every_steps, settings.inversion == "stop", advice,
                                            std::move(folded));
}

namespace {

// Whether tet t lies in the needle's zone: a vertex within the needle's radius plus that node's support radius of the
// swept shaft (the segment from the entry to the tip). The kinematic needle prescribes the motion on its shaft and
// cannot cut the tissue; the nodes whose supports reach the shaft are dragged along with it, so the tets around the
// path fold (on the brain phantom's 3 mm cloud, tets up to 3 mm from the 0.8 mm needle's axis). Those are cuts; a fold
// outside the zone is the material folding.
bool in_needle_zone(const Discretisation& model, Index t, const NeedleStatus& needle) {
  const TetMesh& mesh = model.mesh();
  for (const Index v : mesh.tets[t]) {
    const Vec3& x = mesh.points[v];
    const double along = std::clamp(needle.direction.dot(x - needle.entry), 0.0, needle.depth);
    if ((x - (needle.entry + along * needle.direction)).norm() <= needle.radius + model.cloud().support_radius[v])
      return true;
  }
  return false;
}

}  // namespace

void InversionMonitor::check(const StepRecord& step) {
  const Discretisation& model = *run_->discretisation;
  if (sliver_.empty()) {
    sliver_.resize(static_cast<std::size_t>(model.mesh().tet_count()));
    // A sliver (mesh.hpp) is too thin to judge (the shipped scenes' worst tets have 0.21 to 0.30, a regular one 1).
    for (Index t = 0; t < model.mesh().tet_count(); ++t)
      sliver_[static_cast<std::size_t>(t)] = tet_radius_ratio(model.mesh(), t) < kSliverRadiusRatio;
  }
  interpolated_.resize(step.u.size());
  ratios_.resize(static_cast<std::size_t>(model.mesh().tet_count()));
  model.interpolate(step.u, interpolated_);
  const auto& mesh = model.mesh();
  const auto moved = [&](Index node) {
    const double* d = interpolated_.data() + 3 * static_cast<std::size_t>(node);
    return Vec3(mesh.points[node] + Vec3(d[0], d[1], d[2]));
  };
  const bool needle = step.needle && step.needle->depth > 0.0;
  double smallest = INFINITY;
  Index worst = 0;
  long inverted = 0, cut = 0, slivers = 0;
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const auto& v = mesh.tets[t];
    const Vec3 a = moved(v[0]);
    const double volume = (moved(v[1]) - a).cross(moved(v[2]) - a).dot(moved(v[3]) - a) / 6.0;
    const double ratio = volume / tet_volume(mesh, t);
    ratios_[static_cast<std::size_t>(t)] = ratio;
    if (ratio <= 0.0 && needle && in_needle_zone(model, t, *step.needle)) {
      ++cut;
      continue;
    }
    if (sliver_[static_cast<std::size_t>(t)]) {
      slivers += ratio <= 0.0;
      continue;
    }
    if (ratio < smallest) smallest = ratio, worst = t;
    inverted += ratio <= 0.0;
  }
  ++checks_;
  last_checked_ = step.load.step;
  cut_tets_ = std::max(cut_tets_, cut);
  slivers_inverted_ = std::max(slivers_inverted_, slivers);
  if (smallest < smallest_ratio_) smallest_ratio_ = smallest, smallest_at_ = step.load.step;
  if (smallest > 0.0) return;
  // Name the vertex that moved farthest: the node a driver pushed through its neighbours.
  Index node = mesh.tets[worst][0];
  for (Index v : mesh.tets[worst])
    if ((moved(v) - mesh.points[v]).norm() > (moved(node) - mesh.points[node]).norm()) node = v;
  const bool first = inverted_tets_ == 0;
  inverted_tets_ = std::max(inverted_tets_, inverted);
  if (first) {
    first_inverted_at_ = step.load.step;
    first_node_ = node;
    first_position_ = mesh.points[node];
  }
  if (stop_) stop(step, worst, smallest, node, moved(node) - mesh.points[node]);
  if (first)
    log().warn(
        "step {}: {} background tets turned inside out away from the needle (the worst {:.3g} times its "
        "volume, around node {} at {} m): material folded between integration points; /monitors/inversion "
        "= \"stop\" ends such runs",
        step.load.step, inverted, smallest, node, point_text(mesh.points[node]));
}

std::string fold_lever(const FoldAdvice& advice, const NeedleStatus* needle, double radial,
                       const NodalConstraints* boundary) {
  // A whole face held (a bonded platen): the free surface beside it creases, a fold only self-contact could follow. A
  // crease has no length scale: a finer cloud there resolves it sooner (docs/stability.md), so refining is no lever.
  constexpr std::size_t kFace = 8;
  if (boundary && boundary->nodes().size() > kFace)
    return fmt::format(
        "the free surface creases where it meets the face boundary \"{}\" holds, a fold of the surface onto itself "
        "that only self-contact (not modelled) could follow, and which a finer cloud there resolves sooner, not "
        "later: stop the load before this state (docs/stability.md)",
        boundary->name);
  if (boundary)
    return "a boundary condition pushes single nodes through the tissue: drive a surface or material points instead, "
           "or refine the mesh where it pushes";
  if (!needle)
    return "the material folds over itself (a crease, such as where a free surface meets a face a boundary condition "
           "holds), which only self-contact (not modelled) could follow, and which a finer cloud resolves sooner, not "
           "later: stop the load before this state (docs/stability.md)";
  if (advice.needle_drives_nodes)
    return "the needle drives single nodes: drive material points on the shaft's surface instead "
           "(/needle/driven \"shaft_surface\")";
  // Measured on the brain phantom (docs/stability.md): a cloud refined along the path folds earlier, not later, and a
  // slower ramp only delays it; the needle's drag shears the sleeve beside the shaft past what a cloud can follow.
  if (radial < kBesideTheNeedle)
    return fmt::format(
        "the needle's drag has sheared the tissue beside its shaft past what the cloud can follow; "
        "refining the cloud along the path makes it fold earlier, not later (docs/stability.md){}. {}, "
        "or stop the insertion before this depth (/needle/depth)",
        !advice.refined_along    ? ""
        : advice.refined_to_size ? ": coarsen the refinement (a larger /mesh/refine_size)"
                                 : ": coarsen the refinement (/mesh/refine_ratio closer to 1)",
        advice.drag_limited ? "Lower the drag limit (/needle/drag_limit; docs/needle-models.md)"
                            : "Let the tissue slip along the shaft once dragged a few millimetres (/needle/drag_limit, "
                              "e.g. 0.006 m; docs/needle-models.md)");
  return "a driver pushes the material through itself away from the needle: drive a surface or material points "
         "there instead, or refine the mesh where it pushes";
}

void InversionMonitor::stop(const StepRecord& step, Index worst, double smallest, Index node, Vec3 moved_by) const {
  const Discretisation& model = *run_->discretisation;
  const TetMesh& mesh = model.mesh();
  const NeedleStatus* needle = step.needle && step.needle->depth > 0.0 ? &*step.needle : nullptr;
  if (folded_) {  // last_good_state.vtu's "folded": the tets this check found turned over
    folded_->per_tet.assign(static_cast<std::size_t>(mesh.tet_count()), 0.0);
    for (Index t = 0; t < mesh.tet_count(); ++t)
      if (ratios_[static_cast<std::size_t>(t)] <= 0.0)
        folded_->per_tet[static_cast<std::size_t>(t)] = needle && in_needle_zone(model, t, *needle) ? 0.5
                                                        : sliver_[static_cast<std::size_t>(t)]      ? 0.0
                                                                                                    : 1.0;
  }
  // A vertex of the folded tet in a set a boundary condition drives (not the needle's): that condition pushes it.
  const NodalConstraints* boundary = nullptr;
  for (const NodalConstraints* set : run_->constraint_sets)
    if (set->name != "needle" && set->name != "needle_shaft")
      for (const Index v : mesh.tets[worst])
        if (std::find(set->nodes().begin(), set->nodes().end(), v) != set->nodes().end()) boundary = set;
  std::string where;
  double radial = 0.0;
  if (needle) {
    const Vec3 x = tet_centroid(mesh, worst) - needle->entry;
    const double axial = needle->direction.dot(x);
    radial = (x - axial * needle->direction).norm();
    where = fmt::format(
        " at a needle depth of {:.1f} mm, {:.1f} mm from the needle's axis and {:.1f} mm under its "
        "entry,",
        1e3 * needle->depth, 1e3 * radial, 1e3 * axial);
  }
  throw node_instability(
      step.load.step, step.load.time, "inverted_between_points",
      fmt::format("background tet {} is turned inside out by the interpolated displacements{} away from the needle's "
                  "zone (moved volume {:.3g} times its reference volume; node {} moved {:.3g} mm): the material folded "
                  "between integration points. To go on: {}; or set /monitors/inversion to \"warn\" to finish and "
                  "record the folds (last_good_state.vtu marks them in its cell field \"folded\")",
                  worst, where, smallest, node, 1e3 * moved_by.norm(), fold_lever(advice_, needle, radial, boundary)),
      model, node);
}

json InversionMonitor::report() const {
  json record = {{"every_steps", every_},
                 {"checks", checks_},
                 {"action", stop_ ? "stop" : "warn"},
                 {"inverted_tets", inverted_tets_},
                 {"cut_tets", cut_tets_},
                 {"slivers", std::count(sliver_.begin(), sliver_.end(), 1)},
                 {"slivers_inverted", slivers_inverted_},
                 {"smallest_volume_ratio", std::isfinite(smallest_ratio_) ? json(smallest_ratio_) : json(nullptr)},
                 {"smallest_volume_ratio_step", smallest_at_}};
  if (inverted_tets_ > 0)
    record["first_inverted"] = {{"step", first_inverted_at_},
                                {"node", first_node_},
                                {"coordinates_m", {first_position_[0], first_position_[1], first_position_[2]}}};
  return record;
}

}  // namespace mtled
