// `kinematic`: the paper's kinematic needle model (Wittek et al., section 2.2). Two image-derived
// parameters, no tissue-needle friction model:
//  - indentation: the surface nodes under the tip (the footprint) follow the tip until the largest
//    principal Green strain at the integration points near the tip exceeds the puncture strain;
//  - penetration: each node within the capture radius of the axis (or, with `driven` = shaft_surface, each
//    material point on rings on the shaft's surface) is captured when the tip passes it and from then on is
//    driven along the axis at C_D times the needle's advance (`drive` says from when), its lateral
//    displacement held, returned to the needle's path or left free (`lateral`). Captured at their current
//    displacement, driven entries never jump. With `drag_limit` (not in the paper) an entry dragged that far
//    along the axis slips: it stays there while the shaft slides past. With `settle_steps` an entry moves from
//    where it was captured to the prescription over that many steps, so the relaxed state forgets the capture.
// The needle force is the force needed to impose this motion: the sum of the driven nodes' reactions along
// the axis. Every modelling choice the paper leaves open is listed in docs/needle-models.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "mtled/needle/needle_geometry.hpp"

namespace mtled {

class KinematicNeedle final : public NeedleModel {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The paper's kinematic needle: indentation until the puncture strain is exceeded, then tissue beside "
        "the shaft driven at C_D times the needle's advance.");
    declare_needle_path(d);
    d.number("deformation_coefficient")
        .unit("1")
        .between(0.0, 1.0)
        .defaults(0.4)
        .doc(
            "C_D: tissue beside the shaft moves this fraction of the needle's advance (the paper: 0.4, from "
            "X-ray images of Sylgard 527)")
        .to<&Settings::deformation_coefficient>();
    d.number("puncture_strain")
        .unit("1")
        .non_negative()
        .defaults(1e-5)
        .doc(
            "epsilon_p: the needle punctures the surface when the largest principal Green strain near the tip "
            "exceeds this (the paper: 1e-5, a very short indentation)")
        .to<&Settings::puncture_strain>();
    d.string("drive")
        .defaults("from_reference")
        .choices({"since_capture", "from_reference"})
        .doc(
            "since_capture: a node is captured when the tip reaches its current axial position and then moves "
            "C_D times the advance since; from_reference: captured when the tip reaches its reference axial "
            "position s, its axial displacement is then C_D x (advance - s) once that exceeds what it had at "
            "capture, so the final driven displacements depend on the geometry alone, not on the material")
        .to<&Settings::drive>();
    d.string("lateral")
        .defaults("path")
        .choices({"held", "path", "free"})
        .doc(
            "a driven node's displacement across the axis: held at its value at capture; path: returned to "
            "zero (the tissue stays on the straight needle's path) over one node spacing of advance; free: "
            "only the axial component is prescribed (needs a direction along a coordinate axis)")
        .to<&Settings::lateral>();
    d.string("driven")
        .defaults("shaft_surface")
        .choices({"nodes_near_axis", "shaft_surface"})
        .doc(
            "what the shaft drives: nodes_near_axis, the nodes within capture_radius of the axis (the paper's "
            "\"nodes located close to the needle shaft\"); shaft_surface, material points on rings on the "
            "shaft's surface (radius = the needle's, one ring per node spacing at the entry, about one point per "
            "node spacing around), whose interpolated displacement is prescribed: the same needle on every cloud, "
            "symmetric about its axis")
        .to<&Settings::driven>();
    declare_limits_and_radii(d);
    d.example({{"entry", {0.0, 0.0, 0.017}}, {"depth", 0.005}});
  }

  explicit KinematicNeedle(const Parameters& p) : KinematicNeedle(p, p.read<Settings>()) {}

  void setup(const Discretisation& model) override {
    place_needle_path(path_, model, parameters_);
    const double spacing = spacing_at_entry(path_, model);
    capture_radius_ = capture_radius_option_.value_or(std::max(path_.radius, 0.6 * spacing));
    strain_radius_ = strain_radius_option_.value_or(std::max(2.0 * path_.radius, spacing));
    lateral_ramp_ = spacing;

    // The footprint within the capture radius of the axis.
    footprint_ = footprint_nodes(path_, model, spacing, capture_radius_);

    if (shaft_surface_) {
      place_shaft_points(model, spacing);
    } else {
      // Nodes near the axis, ahead of the entry and within reach of the final depth, ordered along the path.
      for (Index i = 0; i < model.node_count(); ++i) {
        const Vec3& x = model.nodes()[i];
        const double s = path_.axial(x);
        if (path_.radial(x) <= capture_radius_ && s > -0.5 * spacing && s <= path_.depth + spacing)
          candidates_.push_back(i);
      }
      std::sort(candidates_.begin(), candidates_.end(), [&](Index a, Index b) {
        return path_.axial(model.nodes()[a]) < path_.axial(model.nodes()[b]);
      });
    }
    captured_.assign(static_cast<std::size_t>(model.node_count()), 0);

    tip_strain_.setup(path_, model, strain_radius_);

    for (Index n : footprint_) {
      captured_[n] = 1;
      nodes_.add_node(n, path_.axial(model.nodes()[n]), Vec3::Zero(), 0.0, 0);
    }
    if (shaft_surface_)
      log().info("kinematic needle: footprint {} nodes, {} points on the shaft's surface in {} rings, C_D = {:g}",
                 footprint_.size(), shaft_candidates_.size(), rings_, coefficient_);
    else
      log().info("kinematic needle: footprint {} nodes, {} candidate nodes within {:.3g} mm of the axis, C_D = {:g}",
                 footprint_.size(), candidates_.size(), 1e3 * capture_radius_, coefficient_);
  }

  void update(const LoadState& load, const Discretisation& model, std::span<const double> u) override {
    const double advance = load.load_fraction * path_.depth;
    step_ = load.step;
    if (punctured()) {
      capture_passed(model, u, advance);
    } else if (tip_strain_.largest(model, u, path_.tip(advance)) > puncture_strain_) {
      puncture_depth_ = depth_;
      log().info("kinematic needle: puncture at depth {:.4g} mm", 1e3 * *puncture_depth_);
      capture_passed(model, u, advance);
    }
    depth_ = advance;
    for (DrivenSet* set : {&nodes_, &shaft_})
      for (std::size_t k = 0; k < set->constraints.size(); ++k) set->constraints.values[k] = prescribed(*set, k, advance);
  }

  // What update() reads: before the puncture the supports of the points around the tip; the supports of the
  // candidates the capture looks at (up to the first the tip has not reached; every remaining one under
  // since_capture, where reaching depends on their displacement).
  bool nodes_read(const LoadState& load, const Discretisation& model, std::vector<Index>& nodes) const override {
    const double advance = load.load_fraction * path_.depth;
    if (!punctured()) tip_strain_.append_nodes_read(model, path_.tip(advance), nodes);
    for (std::size_t k = next_candidate_; k < candidates_.size(); ++k) {
      const Index n = candidates_[k];
      if (captured_[n]) continue;
      model.basis()->interpolation.append_row(n, nodes);
      if (from_reference_ && advance < path_.axial(model.nodes()[n])) break;
    }
    for (std::size_t k = next_point_; k < shaft_candidates_.size(); ++k) {
      const ShaftPoint& point = shaft_candidates_[k];
      nodes.insert(nodes.end(), point.support.begin(), point.support.end());
      if (from_reference_ && advance < path_.axial(point.position)) break;
    }
    return true;
  }

  std::vector<NodalConstraints*> constraints() override {
    if (shaft_surface_) return {&nodes_.constraints, &shaft_.constraints};
    return {&nodes_.constraints};
  }

  std::optional<PlannedPath> planned_path() const override { return path_.planned(); }
  NeedleStatus status() const override {
    NeedleStatus s = path_.status(depth_, puncture_depth_);
    double force = 0.0;
    for (const DrivenSet* set : {&nodes_, &shaft_})
      for (const auto& r : set->constraints.reactions) force += r.dot(path_.direction);
    s.force = force;
    s.driven_nodes = static_cast<Index>(nodes_.constraints.size() + shaft_.constraints.size());
    return s;
  }

 private:
  struct Settings {
    double deformation_coefficient = 0.0;
    double puncture_strain = 0.0;
    std::string drive, lateral, driven;
    std::optional<double> drag_limit;
    std::optional<long> settle_steps;
    std::optional<double> capture_radius;
  };

  // What the paper leaves open: how far the shaft drags, how captured entries settle, the capture and strain radii.
  static void declare_limits_and_radii(ComponentDeclaration& d) {
    d.number("drag_limit")
        .unit("m")
        .positive()
        .optional()
        .doc(
            "not in the paper: tissue on the shaft is dragged at C_D until its axial displacement reaches this, "
            "then slips along the shaft and stays there (a sticking interface that gives way). Default: no limit, "
            "the paper's model, under which the tissue at the entry is dragged C_D x depth (40 mm at 100 mm), "
            "enough shear to fold the tissue beside the entry on some clouds (docs/stability.md). The paper's "
            "experiments drag at most 0.4 x 15 mm = 6 mm, so a limit of 6 mm or more leaves them unchanged")
        .to<&Settings::drag_limit>();
    d.integer("settle_steps")
        .unit("1")
        .at_least(1)
        .optional()
        .doc(
            "with drive = from_reference: an entry captured at its current displacement moves to C_D x (advance - s) "
            "along the axis (and, with lateral = path, onto the path) over this many time steps, whether the load "
            "advances or is held, so the relaxed state does not depend on how fast the load was ramped. Default: "
            "none, the captured axial displacement stays a floor under C_D x (advance - s), which the ramp rate "
            "changes (docs/validation.md)")
        .to<&Settings::settle_steps>();
    d.number("capture_radius")
        .unit("m")
        .positive()
        .optional()
        .doc(
            "with driven = nodes_near_axis, nodes within this distance of the needle axis are driven once the tip "
            "passes them; the footprint (the surface nodes the tip indents) is chosen within it too; default: the "
            "larger of the needle radius and 0.6 x the node spacing at the entry, so a coarse cloud still has "
            "nodes on the path")
        .to<&Settings::capture_radius>();
    declare_strain_radius(d);
  }

  KinematicNeedle(const Parameters& p, const Settings& s)
      : parameters_(p),
        path_(read_needle_path(p)),
        coefficient_(s.deformation_coefficient),
        puncture_strain_(s.puncture_strain),
        drag_limit_(s.drag_limit),
        settle_steps_(s.settle_steps),
        capture_radius_option_(s.capture_radius),
        strain_radius_option_(p.read<TipStrainSettings>().strain_radius),
        from_reference_(s.drive == "from_reference"),
        return_to_path_(s.lateral == "path"),
        shaft_surface_(s.driven == "shaft_surface") {
    nodes_.constraints.name = "needle";
    shaft_.constraints.name = "needle_shaft";
    if (s.lateral == "free") {
      // The kernel constrains whole Cartesian components, so "axial only" needs an axis-aligned needle.
      const Vec3 d = path_.direction.cwiseAbs();
      Index axis = 0;
      d.maxCoeff(&axis);
      if (d[axis] < 1.0 - 1e-12)
        throw InputError(p.pointer("lateral"),
                         fmt::format("\"free\" prescribes only the axial component, which needs a direction along "
                                     "x, y or z; got ({:g}, {:g}, {:g}). Use \"held\" or \"path\", or rotate the "
                                     "scene so that the needle runs along a coordinate axis",
                                     path_.direction.x(), path_.direction.y(), path_.direction.z()));
      nodes_.constraints.set_components({axis == 0, axis == 1, axis == 2});
      shaft_.constraints.set_components({axis == 0, axis == 1, axis == 2});
    }
    if (settle_steps_ && !from_reference_)
      throw InputError(p.pointer("settle_steps"),
                       "settling onto the prescription needs a prescription that does not depend on the capture: "
                       "set \"drive\" to \"from_reference\" (the default), or leave settle_steps out");
  }

  // A constraint set the needle drives and, per entry, what its law needs.
  struct DrivenSet {
    NodalConstraints constraints;
    std::vector<Vec3> captured_at;        // displacement when the current driving began
    std::vector<double> capture_depth;    // needle advance when the current driving began
    std::vector<long> capture_step;       // the time step it began at
    std::vector<double> reference_axial;  // axial coordinate of the entry's reference position

    void add_node(Index node, double reference, const Vec3& displacement, double advance, long step) {
      constraints.add_node(node, displacement);
      remember(reference, displacement, advance, step);
    }
    void add_point(const Vec3& point, double reference, const Vec3& displacement, double advance, long step) {
      constraints.add_point(point, displacement);
      remember(reference, displacement, advance, step);
    }
    void clear() {
      constraints.clear();
      captured_at.clear();
      capture_depth.clear();
      capture_step.clear();
      reference_axial.clear();
    }

   private:
    void remember(double reference, const Vec3& displacement, double advance, long step) {
      captured_at.push_back(displacement);
      capture_depth.push_back(advance);
      capture_step.push_back(step);
      reference_axial.push_back(reference);
    }
  };

  // Rings of points on the shaft's surface, one per `spacing` along the path from the entry to the final depth,
  // each with about one point per spacing around (at least 3), alternate rings turned by half a step. Points
  // outside every support (off the body) are left out.
  void place_shaft_points(const Discretisation& model, double spacing) {
    const Vec3 e1 = path_.direction.unitOrthogonal();
    const Vec3 e2 = path_.direction.cross(e1);
    const int around = std::max(3, static_cast<int>(std::lround(2.0 * std::numbers::pi * path_.radius / spacing)));
    std::vector<Index> support;
    std::vector<double> values;
    for (double s = 0.0; s <= path_.depth + 1e-12 * spacing; s += spacing, ++rings_) {
      for (int j = 0; j < around; ++j) {
        const double angle = 2.0 * std::numbers::pi * (j + 0.5 * (rings_ % 2)) / around;
        const Vec3 x = path_.tip(s) + path_.radius * (std::cos(angle) * e1 + std::sin(angle) * e2);
        if (!model.shape_functions_at(x, support, values)) continue;
        shaft_candidates_.push_back({x, support, values});
      }
    }
  }

  // The displacement of entry k of `set` at this advance: the footprint follows the tip until puncture;
  // afterwards every driven entry moves along the axis at C_D times the advance (`drive`), up to the drag limit,
  // its lateral part as `lateral` says.
  Vec3 prescribed(const DrivenSet& set, std::size_t k, double advance) const {
    const Vec3& start = set.captured_at[k];
    const double start_axial = start.dot(path_.direction);
    const Vec3 start_lateral = start - start_axial * path_.direction;
    const double since = std::max(0.0, advance - set.capture_depth[k]);
    double axial = start_axial + (punctured() ? coefficient_ : 1.0) * since;
    if (punctured() && from_reference_ && settle_steps_) {
      // From the captured displacement to the prescription, linearly in steps.
      const Vec3 target = limited_drag(coefficient_ * (advance - set.reference_axial[k])) * path_.direction +
                          (return_to_path_ ? Vec3::Zero() : start_lateral);
      const double remaining =
          std::max(0.0, 1.0 - static_cast<double>(step_ - set.capture_step[k]) / static_cast<double>(*settle_steps_));
      return target + remaining * (start - target);
    }
    if (punctured() && from_reference_)
      axial = std::max(start_axial, limited_drag(coefficient_ * (advance - set.reference_axial[k])));
    else if (punctured())
      axial = start_axial + limited_drag(coefficient_ * since);
    double lateral_share = 1.0;
    if (return_to_path_) lateral_share = std::max(0.0, 1.0 - since / lateral_ramp_);
    return axial * path_.direction + lateral_share * start_lateral;
  }

  double limited_drag(double drag) const { return drag_limit_ ? std::min(drag, *drag_limit_) : drag; }

  // Captures what the tip has passed. At the first call (puncture) the footprint restarts: from then on it
  // moves with C_D like every captured entry; with shaft_surface the ring at the entry replaces it (the
  // footprint, a few nodes on one side of the axis, would pull the surface off-centre for the whole insertion).
  void capture_passed(const Discretisation& model, std::span<const double> u, double advance) {
    if (!restarted_footprint_) {
      for (std::size_t k = 0; k < nodes_.constraints.size(); ++k) {
        nodes_.captured_at[k] = nodes_.constraints.values[k];
        nodes_.capture_depth[k] = depth_;
        nodes_.capture_step[k] = step_;
      }
      if (shaft_surface_) nodes_.clear();
      restarted_footprint_ = true;
    }
    // The tip passes an entry when its advance reaches the entry's current (or reference) axial position.
    auto passed = [&](const Vec3& reference, const Vec3& displacement) {
      return advance >= path_.axial(from_reference_ ? reference : Vec3(reference + displacement));
    };
    for (; next_candidate_ < candidates_.size(); ++next_candidate_) {
      const Index n = candidates_[next_candidate_];
      if (captured_[n]) continue;
      const Vec3 displacement = model.interpolate_node(n, u);
      if (!passed(model.nodes()[n], displacement)) break;
      captured_[n] = 1;
      nodes_.add_node(n, path_.axial(model.nodes()[n]), displacement, advance, step_);
    }
    for (; next_point_ < shaft_candidates_.size(); ++next_point_) {
      const ShaftPoint& point = shaft_candidates_[next_point_];
      Vec3 displacement = Vec3::Zero();
      for (std::size_t k = 0; k < point.support.size(); ++k)
        displacement += point.values[k] * Vec3(&u[3 * static_cast<std::size_t>(point.support[k])]);
      if (!passed(point.position, displacement)) break;
      shaft_.add_point(point.position, path_.axial(point.position), displacement, advance, step_);
    }
  }

  struct ShaftPoint {
    Vec3 position;  // reference
    std::vector<Index> support;
    std::vector<double> values;
  };

  Parameters parameters_;
  NeedlePath path_;
  double coefficient_, puncture_strain_;
  std::optional<double> drag_limit_;  // none: the paper's unlimited drag
  std::optional<long> settle_steps_;  // none: the captured axial displacement stays a floor
  std::optional<double> capture_radius_option_, strain_radius_option_;
  bool from_reference_;
  bool return_to_path_;  // lateral "path"; "free" only changes the constrained components
  bool shaft_surface_;
  double capture_radius_ = 0.0, strain_radius_ = 0.0, lateral_ramp_ = 0.0;

  std::vector<Index> footprint_, candidates_;
  TipStrainWatch tip_strain_;
  std::vector<ShaftPoint> shaft_candidates_;  // ordered along the path
  int rings_ = 0;
  std::vector<char> captured_;
  std::size_t next_candidate_ = 0, next_point_ = 0;
  DrivenSet nodes_, shaft_;  // footprint and captured nodes; captured shaft points
  bool restarted_footprint_ = false;
  bool punctured() const { return puncture_depth_.has_value(); }
  std::optional<double> puncture_depth_;  // where the needle punctured, once it has
  double depth_ = 0.0;
  long step_ = 0;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::NeedleModel, mtled::KinematicNeedle)
