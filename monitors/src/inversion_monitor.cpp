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
          "after the last, and read the displacement field inside those turned inside out: material folded between "
          "integration points, which no point's J shows; 0 turns the check off")
      .to<&Settings::inversion_every_steps>();
  d.string("inversion")
      .defaults("stop")
      .choices({"warn", "stop"})
      .doc(
          "what a fold of the material between integration points does: \"stop\" ends the run (status "
          "\"unstable\", what \"inverted_between_points\"); \"warn\" logs the first and records them in summary.json "
          "(monitors.inversion). A background tet its vertices' displacements turn inside out is a fold when the "
          "displacement field's J is not positive at a point inside it (its centroid, the degree-2 rule's four "
          "points); with J > 0 there the field turns within it more than its corners follow (a rolled rim), counted "
          "as bent (monitors.inversion.bent_tets), not a fold. Tets around the needle's path (a vertex within the "
          "needle's radius plus that node's support radius of the swept shaft) fold because the kinematic needle "
          "cannot cut the tissue: they are counted as cut (monitors.inversion.cut_tets)")
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

// A set of more nodes than this that a boundary condition holds is a face, of fewer a driver's few nodes.
constexpr std::size_t kHeldFace = 8;

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

// The smallest J of the displacement field inside tet t: at its centroid and the four points of the degree-2 rule,
// all inside it (on its faces the field may lie on the body's surface, where MLS is least accurate and a bonded rim's
// exact gradient is singular). NaN when no support covers a point.
double smallest_jacobian_inside(const Discretisation& model, Index t, std::span<const double> u) {
  double smallest = INFINITY;
  const auto sample = [&](const Vec3& x) {
    const auto field = field_at(model, x, u);
    smallest = field ? std::min(smallest, field->deformation_gradient.determinant()) : NAN;
  };
  sample(tet_centroid(model.mesh(), t));
  for (const Vec3& x : tet_quadrature_points(model.mesh(), t)) sample(x);
  return smallest;
}

}  // namespace

InversionMonitor::Census InversionMonitor::classify(const StepRecord& step) {
  const Discretisation& model = *run_->discretisation;
  const auto& mesh = model.mesh();
  interpolated_.resize(step.u.size());
  kinds_.assign(static_cast<std::size_t>(mesh.tet_count()), TetState::whole);
  model.interpolate(step.u, interpolated_);
  const bool needle = step.needle && step.needle->depth > 0.0;
  Census census;
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const auto& v = mesh.tets[t];
    const Vec3 a = moved(v[0]);
    const double volume = (moved(v[1]) - a).cross(moved(v[2]) - a).dot(moved(v[3]) - a) / 6.0;
    const double ratio = volume / tet_volume(mesh, t);
    if (ratio > 0.0) {
      census.smallest = std::min(census.smallest, ratio);
      continue;
    }
    TetState& state = kinds_[static_cast<std::size_t>(t)];
    if (needle && in_needle_zone(model, t, *step.needle)) {
      state = TetState::cut, ++census.cut;
      continue;
    }
    census.smallest = std::min(census.smallest, ratio);
    // Turned over by its vertices: the material folded there only if the field itself turns inside out within it.
    const double jacobian = smallest_jacobian_inside(model, t, step.u);
    if (jacobian > 0.0) {
      state = TetState::bent, ++census.bent;
      census.bent_jacobian = std::min(census.bent_jacobian, jacobian);
      continue;
    }
    state = TetState::folded, ++census.folded;
    if (!(jacobian >= census.folded_jacobian))
      census.folded_jacobian = jacobian, census.worst = t, census.worst_ratio = ratio;
  }
  return census;
}

Vec3 InversionMonitor::moved(Index node) const {
  const double* d = interpolated_.data() + 3 * static_cast<std::size_t>(node);
  return run_->discretisation->mesh().points[node] + Vec3(d[0], d[1], d[2]);
}

void InversionMonitor::check(const StepRecord& step) {
  const Census census = classify(step);
  ++checks_;
  last_checked_ = step.load.step;
  cut_tets_ = std::max(cut_tets_, census.cut);
  if (census.bent > 0 && bent_tets_ == 0)
    log().info(
        "step {}: {} background tets turned inside out by their vertices' displacements alone: the field stays whole "
        "inside them (J >= {:.3g}), it turns within them more than a tet's corners follow; not a fold "
        "(monitors.inversion.bent_tets)",
        step.load.step, census.bent, census.bent_jacobian);
  bent_tets_ = std::max(bent_tets_, census.bent);
  smallest_bent_jacobian_ = std::min(smallest_bent_jacobian_, census.bent_jacobian);
  if (census.smallest < smallest_ratio_) smallest_ratio_ = census.smallest, smallest_at_ = step.load.step;
  if (census.folded == 0) return;
  // Name the vertex that moved farthest: the node a driver pushed through its neighbours.
  const TetMesh& mesh = run_->discretisation->mesh();
  const Index worst = census.worst;
  Index node = mesh.tets[worst][0];
  for (Index v : mesh.tets[worst])
    if ((moved(v) - mesh.points[v]).norm() > (moved(node) - mesh.points[node]).norm()) node = v;
  const bool first = inverted_tets_ == 0;
  inverted_tets_ = std::max(inverted_tets_, census.folded);
  if (first) {
    first_inverted_at_ = step.load.step;
    first_node_ = node;
    first_position_ = mesh.points[node];
  }
  if (stop_) stop(step, census, node, moved(node) - mesh.points[node]);
  if (first)
    log().warn(
        "step {}: {} background tets folded away from the needle (the field's J down to {:.3g} inside them, around "
        "node {} at {} m): material folded between integration points; /monitors/inversion = \"stop\" ends such "
        "runs",
        step.load.step, census.folded, census.folded_jacobian, node, point_text(mesh.points[node]));
}

std::string fold_lever(const FoldAdvice& advice, const NeedleStatus* needle, double radial,
                       const NodalConstraints* boundary) {
  // A whole face held (a bonded platen): the free surface beside it creases, a fold only self-contact could follow. A
  // crease has no length scale: a finer cloud there resolves it sooner (docs/stability.md), so refining is no lever.
  if (boundary && boundary->nodes().size() > kHeldFace)
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

void InversionMonitor::stop(const StepRecord& step, const Census& census, Index node, Vec3 moved_by) const {
  const Index worst = census.worst;
  const Discretisation& model = *run_->discretisation;
  const TetMesh& mesh = model.mesh();
  const NeedleStatus* needle = step.needle && step.needle->depth > 0.0 ? &*step.needle : nullptr;
  if (folded_) {  // last_good_state.vtu's "folded": the tets this check found turned over
    folded_->per_tet.assign(static_cast<std::size_t>(mesh.tet_count()), 0.0);
    for (std::size_t t = 0; t < kinds_.size(); ++t)
      folded_->per_tet[t] = kinds_[t] == TetState::folded ? 1.0
                            : kinds_[t] == TetState::cut  ? 0.5
                            : kinds_[t] == TetState::bent ? 0.25
                                                          : 0.0;
  }
  // The set a boundary condition drives (not the needle's) that holds a vertex of a folded tet, in the scene's order: a
  // driver's few nodes push the material through itself, before a held face creases the surface beside it.
  const NodalConstraints* boundary = nullptr;
  const auto holds_a_folded_vertex = [&](const NodalConstraints& set) {
    for (Index t = 0; t < mesh.tet_count(); ++t)
      if (kinds_[static_cast<std::size_t>(t)] == TetState::folded)
        for (const Index v : mesh.tets[t])
          if (std::find(set.nodes().begin(), set.nodes().end(), v) != set.nodes().end()) return true;
    return false;
  };
  for (const NodalConstraints* set : run_->constraint_sets)
    if (set->name != "needle" && set->name != "needle_shaft" &&
        (!boundary || (boundary->nodes().size() > kHeldFace && set->nodes().size() <= kHeldFace)) &&
        holds_a_folded_vertex(*set))
      boundary = set;
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
      fmt::format(
          "background tet {} is turned inside out{} away from the needle's zone (the displacement field's J "
          "down to {:.3g} inside it, its vertices' moved volume {:.3g} times its own; node {} moved {:.3g} mm): "
          "the material folded between integration points. To go on: {}; or set /monitors/inversion to "
          "\"warn\" to finish and record the folds (last_good_state.vtu marks them in its cell field "
          "\"folded\")",
          worst, where, census.folded_jacobian, census.worst_ratio, node, 1e3 * moved_by.norm(),
          fold_lever(advice_, needle, radial, boundary)),
      model, node);
}

json InversionMonitor::report() const {
  json record = {{"every_steps", every_},
                 {"checks", checks_},
                 {"action", stop_ ? "stop" : "warn"},
                 {"inverted_tets", inverted_tets_},
                 {"cut_tets", cut_tets_},
                 {"bent_tets", bent_tets_},
                 {"bent_smallest_jacobian",
                  std::isfinite(smallest_bent_jacobian_) ? json(smallest_bent_jacobian_) : json(nullptr)},
                 {"smallest_volume_ratio", std::isfinite(smallest_ratio_) ? json(smallest_ratio_) : json(nullptr)},
                 {"smallest_volume_ratio_step", smallest_at_}};
  if (inverted_tets_ > 0)
    record["first_inverted"] = {{"step", first_inverted_at_},
                                {"node", first_node_},
                                {"coordinates_m", {first_position_[0], first_position_[1], first_position_[2]}}};
  return record;
}

}  // namespace mtled
