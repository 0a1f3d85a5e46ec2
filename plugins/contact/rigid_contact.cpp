// `rigid_contact`: a rigid needle (conical tip and cylindrical shaft) in Coulomb frictional contact with the
// tissue, enforced kinematically (no penalty stiffness, so the explicit time step is untouched). An
// alternative to the paper's kinematic model (Wittek et al., section 2.2) to compare it with: instead of the
// image-derived C_D, the tissue's motion along the shaft follows from contact mechanics (the normal pressure
// of the tissue on the needle and a friction coefficient).
//
// Each contact node K carries coordinates on the needle: xi_K, its distance behind the tip along the axis,
// and an azimuth n_K (a unit vector normal to the axis). Its prescribed position is
//   x_K = entry + (advance - xi_K) d + rho_K n_K,   rho_K = sqrt(rho0_K^2 + R(xi_K)^2),
// with R(xi) = min(r, xi tan(theta)) the needle's radius xi behind the tip (cone, then shaft) and rho0_K the
// node's distance from the axis when it joined: the incompressible plane-strain map of a cavity opened to
// radius R around the cut. A node on the axis lands on the needle's surface; a node of the layer beside the
// shaft (within the capture radius, so that coarse clouds have a line of nodes along the needle) moves out as
// the tissue around an opening hole does. All three components are prescribed (interpolated displacement,
// simplified EBCIEM), so the kernel returns one reaction lambda_K per contact node, which the model splits
// into the normal force f_n = lambda.n (n: the normal of the map's level surface, the cone's normal for
// rho0 = 0, radial on the shaft) and the tangential force along the surface's generator f_t = lambda.t (t
// points back along the needle). Coulomb's law along the generator decides, per node and per step:
//  - stick (|f_t| <= mu f_n): xi_K stays, the node moves with the needle;
//  - slip: the node's own advance per step is a state that an integral controller drives until
//    f_t = -+ mu f_n (a return mapping at the velocity level; the gain is the node's explicit-dynamics
//    compliance sum_I N_I(X_K)^2 dt_I^2 / m_I, relaxed adaptively); slip stops when the relative sliding
//    would stop or reverse. The azimuth is held (the needle does not rotate; no circumferential slip).
//  - a node whose normal force stays tensile (the tissue pulls on the needle) for `release_steps` steps
//    leaves the contact; it comes back only if it enters the needle's volume.
// Phases: before puncture the surface nodes under the tip (the footprint) are pinned to the apex (the tissue
// is not cut: they follow the tip, as in the kinematic model); the needle punctures when the largest principal
// Green strain near the tip exceeds `puncture_strain` (as the kinematic model) or, if `puncture_force` is
// given, when the axial contact force exceeds it. From then on the tissue is cut along the path: the footprint
// may slide along the cone, and every node the tip passes within the capture radius, or that enters the
// needle's volume, joins the contact.
// The needle force is the sum of the contact nodes' reactions along the axis (normal and friction parts).
// Modelling choices, parameters and limits: docs/needle-models.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "mtled/needle/needle_geometry.hpp"

namespace mtled {
namespace {

// Each node's explicit-dynamics stiffness m_I / dt_I^2 (N/m): the sum over the integration points it supports of
// rho w / (n dt^2), with n the point's support size and dt its critical step. It does not depend on mass scaling
// (a scaled point's rho w / dt^2 is unchanged).
std::vector<double> explicit_node_stiffness(const Discretisation& discretisation) {
  std::vector<double> stiffness(static_cast<std::size_t>(discretisation.node_count()), 0.0);
  const GradientRows& rows = discretisation.gradients();
  const IntegrationPoints& points = discretisation.points();
  for (Index ip = 0; ip < points.count(); ++ip) {
    const double dt = discretisation.critical_time_steps()[ip];
    const double share =
        discretisation.material(ip).density() * points.weights[ip] / (static_cast<double>(rows.size(ip)) * dt * dt);
    for (int k = 0; k < rows.size(ip); ++k) stiffness[rows.node(ip, k)] += share;
  }
  return stiffness;
}

}  // namespace

class RigidContactNeedle final : public NeedleModel {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "A rigid needle (conical tip, cylindrical shaft) in Coulomb frictional contact with the tissue, enforced "
        "kinematically: the tip indents the surface until puncture, then cuts; tissue the needle reaches is "
        "pushed out to the shaft and sticks to it until the friction limit mu f_n is reached, then slips.");
    declare_needle_path(d);
    d.number("tip_angle")
        .unit("deg")
        .greater_than(0.0)
        .less_than(90.0)
        .defaults(15.0)
        .doc(
            "half-angle of the conical tip, in degrees: the cone is r / tan(angle) long and pushes the tissue "
            "out to the shaft radius gradually (15: a sharp conical or bevel-like point)")
        .to<&Settings::tip_angle>();
    d.number("friction_coefficient")
        .unit("1")
        .between(0.0, 2.0)
        .defaults(0.3)
        .doc(
            "Coulomb friction coefficient mu between the needle and the tissue (0.3: the static coefficient "
            "measured for needles in agarose gel, 0.30 +- 0.06; 0 gives a frictionless needle)")
        .to<&Settings::friction_coefficient>();
    d.number("puncture_strain")
        .unit("1")
        .non_negative()
        .defaults(1e-5)
        .doc(
            "epsilon_p: the tip punctures the surface when the largest principal Green strain near the tip "
            "exceeds this (as the kinematic model; the paper: 1e-5); ignored when puncture_force is given")
        .to<&Settings::puncture_strain>();
    d.number("puncture_force")
        .unit("N")
        .positive()
        .optional()
        .doc(
            "if given, the tip punctures the surface when the axial contact force (averaged over about ten "
            "steps) exceeds this, instead of the strain criterion (a measured puncture force)")
        .to<&Settings::puncture_force>();
    d.number("footprint_radius")
        .unit("m")
        .positive()
        .optional()
        .doc(
            "surface nodes within this distance of the axis at the entry are pinned to the tip until puncture; "
            "default: the larger of the needle radius and 0.6 x the node spacing at the entry (as the kinematic "
            "model's capture radius), so a coarse cloud still has a node under the tip")
        .to<&Settings::footprint_radius>();
    d.number("capture_radius")
        .unit("m")
        .positive()
        .optional()
        .doc(
            "after puncture, nodes within this distance of the axis join the contact when the tip passes them "
            "(the layer of tissue beside the shaft; nodes the needle's volume reaches join in any case); default: "
            "the larger of the needle radius and 0.6 x the node spacing at the entry (as the kinematic model), so "
            "a coarse cloud still has a line of nodes along the shaft")
        .to<&Settings::capture_radius>();
    declare_strain_radius(d);
    d.integer("release_steps")
        .unit("1")
        .at_least(1)
        .defaults(20)
        .doc(
            "a contact node whose normal force is tensile (the tissue pulls on the needle) for this many "
            "consecutive steps leaves the contact")
        .to<&Settings::release_steps>();
    d.example({{"entry", {0.0, 0.0, 0.017}}, {"depth", 0.005}});
  }

  explicit RigidContactNeedle(const Parameters& p) : RigidContactNeedle(p, p.read<Settings>()) {}

  void setup(const Discretisation& model) override {
    place_needle_path(path_, model, parameters_);
    // A basis normal to the axis for azimuths of nodes that lie on it.
    const Vec3 helper = std::abs(path_.direction.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    e1_ = path_.direction.cross(helper).normalized();
    e2_ = path_.direction.cross(e1_);
    spacing_ = spacing_at_entry(path_, model);
    footprint_radius_ = footprint_radius_option_.value_or(std::max(path_.radius, 0.6 * spacing_));
    capture_radius_ = capture_radius_option_.value_or(std::max(path_.radius, 0.6 * spacing_));
    strain_radius_ = strain_radius_option_.value_or(std::max(2.0 * path_.radius, spacing_));
    const double cone = path_.radius / tan_tip_;
    if (path_.depth <= cone)
      log().warn(
          "rigid_contact needle: the conical tip ({:.3g} mm long at {:g} deg) is longer than the insertion depth "
          "({:.3g} mm): the shaft never enters the tissue, only the tip acts",
          1e3 * cone, std::atan(tan_tip_) * 180.0 / std::numbers::pi, 1e3 * path_.depth);

    // Explicit-dynamics stiffness of each node, m_I / dt_I^2 (explicit_node_stiffness): what the constraint
    // correction charges per unit of prescribed motion in one step.
    node_stiffness_ = explicit_node_stiffness(model);
    node_mass_ = model.lumped_mass();

    const std::vector<Index> footprint = footprint_nodes(path_, model, spacing_, footprint_radius_);

    // Candidates: nodes that the needle's volume can reach (within a node spacing of the shaft, from just
    // before the entry to just past the final depth).
    for (Index i = 0; i < model.node_count(); ++i) {
      const Vec3& x = model.nodes()[i];
      const double s = path_.axial(x);
      if (path_.radial(x) <= std::max(path_.radius, capture_radius_) + spacing_ && s > -spacing_ &&
          s <= path_.depth + spacing_)
        candidates_.push_back(i);
    }
    in_contact_.assign(static_cast<std::size_t>(model.node_count()), 0);
    released_before_.assign(static_cast<std::size_t>(model.node_count()), 0);

    tip_strain_.setup(path_, model, strain_radius_);

    for (Index n : footprint) catch_node(model, n, model.nodes()[n], 0.0, true);
    set_values(model);
    log().info(
        "rigid_contact needle: footprint {} nodes, {} candidate nodes, capture radius {:.3g} mm, tip half-angle "
        "{:g} deg (cone {:.3g} mm), mu = {:g}",
        footprint.size(), candidates_.size(), 1e3 * capture_radius_, std::atan(tan_tip_) * 180.0 / std::numbers::pi,
        1e3 * cone, mu_);
  }

  void update(const LoadState& load, const Discretisation& model, std::span<const double> u) override {
    const double advance = load.load_fraction * path_.depth;
    const double step_advance = advance - depth_;
    // The integrators' step (time / steps); the gains depend on it where masses are not scaled.
    const double step = load.step > 0 ? load.time / static_cast<double>(load.step) : 0.0;
    if (step > 0.0 && std::abs(step - step_) > 1e-3 * step) {
      step_ = step;
      for (auto& c : contacts_) c.gain = compliance(model, c.node);
    }

    apply_friction_law(step_advance);
    release_open_contacts();

    if (!punctured() && punctures(model, u)) {
      puncture_depth_ = depth_;
      for (auto& c : contacts_) c.pinned = false;
      log().info("rigid_contact needle: puncture at depth {:.4g} mm (axial force {:.4g} N)", 1e3 * *puncture_depth_,
                 axial_force());
    }
    depth_ = advance;
    for (auto& c : contacts_) c.xi += c.slip_rate;
    catch_nodes_inside(model, u);
    // Radial position: the cavity-expansion map sqrt(rho0^2 + R(xi)^2), approached at most a small fraction of
    // the node spacing per step beyond the cone's own rate, so a node caught late is not thrown out in one step.
    for (auto& c : contacts_) {
      const double target = std::hypot(c.rho0, surface_radius(c.xi));
      const double limit = std::max((std::abs(step_advance) + std::abs(c.slip_rate)) * tan_tip_, 0.01 * spacing_);
      c.rho += std::clamp(target - c.rho, -limit, limit);
    }
    set_values(model);
    if (log().should_log(spdlog::level::trace) && load.step % 20 == 0 && contact_.reactions.size() == contacts_.size())
      for (std::size_t k = 0; k < contacts_.size(); ++k) {
        const Contact& c = contacts_[k];
        const Vec3& l = contact_.reactions[k];
        log().trace(
            "rc {} node {} xi {:.4g} rho0 {:.4g} rho {:.4g} fn {:.4g} ft {:.4g} fc {:.4g} {} rate {:.3g} gain {:.3g}",
            load.step, c.node, 1e3 * c.xi, 1e3 * c.rho0, 1e3 * c.rho, l.dot(normal(c)), l.dot(tangent(c)),
            l.dot(path_.direction.cross(c.azimuth)), c.pinned ? "pinned" : (c.slipping ? "slip" : "stick"), c.slip_rate,
            c.gain);
      }
    if (load.step % 200 == 0)
      log().debug(
          "rigid_contact step {}: depth {:.4g} mm, {} contacts ({} slipping; {} caught, {} released so far), "
          "axial force {:.4g} N",
          load.step, 1e3 * depth_, contacts_.size(), slipping_count_, caught_, released_, axial_force());
  }

  // What update() reads: the supports of the candidates not in contact (catch_nodes_inside) and, before a puncture
  // by strain, of the points around the tip.
  bool nodes_read(const LoadState&, const Discretisation& model, std::vector<Index>& nodes) const override {
    if (!punctured() && !puncture_force_) tip_strain_.append_nodes_read(model, path_.tip(depth_), nodes);
    for (const Index n : candidates_)
      if (!in_contact_[n]) model.basis()->interpolation.append_row(n, nodes);
    return true;
  }

  std::vector<NodalConstraints*> constraints() override { return {&contact_}; }

  std::optional<PlannedPath> planned_path() const override { return path_.planned(); }
  NeedleStatus status() const override {
    NeedleStatus s = path_.status(depth_, puncture_depth_);
    s.force = axial_force();
    s.driven_nodes = static_cast<Index>(contacts_.size());
    return s;
  }

 private:
  struct Settings {
    double tip_angle = 0.0;
    double friction_coefficient = 0.0;
    double puncture_strain = 0.0;
    std::optional<double> puncture_force, footprint_radius, capture_radius;
    long release_steps = 0;
  };

  RigidContactNeedle(const Parameters& p, const Settings& s)
      : parameters_(p),
        path_(read_needle_path(p)),
        tan_tip_(std::tan(s.tip_angle * std::numbers::pi / 180.0)),
        cos_tip_(std::cos(s.tip_angle * std::numbers::pi / 180.0)),
        sin_tip_(std::sin(s.tip_angle * std::numbers::pi / 180.0)),
        mu_(s.friction_coefficient),
        puncture_strain_(s.puncture_strain),
        puncture_force_(s.puncture_force),
        footprint_radius_option_(s.footprint_radius),
        capture_radius_option_(s.capture_radius),
        strain_radius_option_(p.read<TipStrainSettings>().strain_radius),
        release_steps_(s.release_steps) {
    if (capture_radius_option_ && *capture_radius_option_ < path_.radius)
      throw InputError(
          p.pointer("capture_radius"),
          fmt::format("a capture radius of {:.3g} mm is below the needle's radius ({:.3g} mm): nodes inside "
                      "the needle join the contact anyway; give at least the radius, or leave it out for "
                      "the default (the larger of the radius and 0.6 x the node spacing at the entry)",
                      1e3 * *capture_radius_option_, 1e3 * path_.radius));
    if (footprint_radius_option_ && *footprint_radius_option_ < path_.radius)
      throw InputError(p.pointer("footprint_radius"),
                       fmt::format("a footprint radius of {:.3g} mm is below the needle's radius ({:.3g} mm): the tip "
                                   "covers at least its own cross-section; give at least the radius, or leave it out "
                                   "for the default",
                                   1e3 * *footprint_radius_option_, 1e3 * path_.radius));
    contact_.name = "needle";
  }

  // Fraction of the controller's full correction applied per step (the node stiffness is a lower bound of
  // the constraint's response: time-step safety factors and neighbouring constraints stiffen it).
  static constexpr double kSlipRelaxation = 0.5;
  static constexpr double kMinSlipRelaxation = 1.0 / 1024.0;

  struct Contact {
    Index node = -1;
    Vec3 azimuth = Vec3::Zero();  // unit, normal to the axis
    double rho0 = 0.0;            // initial radius of the cavity-expansion map (m)
    double rho = 0.0;             // prescribed distance from the axis (m)
    double xi = 0.0;              // distance behind the tip along the axis (m)
    double slip_rate = 0.0;       // change of xi in this step (m): 0 unless slipping
    double carried = 0.0;         // while slipping, the node's own advance per step along the needle (m)
    double gain = 0.0;            // 1 / stiffness of the node against prescribed motion (m/N)
    bool pinned = false;          // footprint before puncture: sticks to the apex whatever the forces
    bool slipping = false;
    long tensile_steps = 0;
    double relaxation = kSlipRelaxation;  // fraction of the estimated correction applied per step
    double last_error = 0.0;              // f_t target - f_t at the previous slip step (N)
  };

  double surface_radius(double xi) const { return std::min(path_.radius, std::max(xi, 0.0) * tan_tip_); }
  // d R / d xi: tan(theta) along the cone, 0 on the shaft (and ahead of the apex).
  double surface_slope(double xi) const { return xi > 0.0 && xi * tan_tip_ < path_.radius ? tan_tip_ : 0.0; }
  // The contact's surface: the level set rho^2 - R(xi)^2 = rho0^2 of the cavity-expansion map. Its outward
  // normal is along rho e_rho + R R' d (the cone's normal for rho0 = 0, radial on the shaft), and its
  // generator t, pointing back along the needle, along R R' e_rho - rho d.
  Vec3 normal(const Contact& c) const {
    const double rr = surface_radius(c.xi) * surface_slope(c.xi);
    if (c.rho <= 1e-9 * path_.radius) return cos_tip_ * c.azimuth + sin_tip_ * path_.direction;
    return (c.rho * c.azimuth + rr * path_.direction).normalized();
  }
  Vec3 tangent(const Contact& c) const {
    const double rr = surface_radius(c.xi) * surface_slope(c.xi);
    if (c.rho <= 1e-9 * path_.radius) return -cos_tip_ * path_.direction + sin_tip_ * c.azimuth;
    return (rr * c.azimuth - c.rho * path_.direction).normalized();
  }
  // Length of the contact's path per unit of xi: |d x / d xi| = sqrt(1 + (R R' / rho)^2).
  double path_stretch(const Contact& c) const {
    const double rr = surface_radius(c.xi) * surface_slope(c.xi);
    if (c.rho <= 1e-9 * path_.radius) return 1.0 / cos_tip_;
    return std::hypot(1.0, rr / c.rho);
  }

  double axial_force() const {
    double force = 0.0;
    for (const auto& r : contact_.reactions) force += r.dot(path_.direction);
    return force;
  }

  // Coulomb's law on each contact from the reactions of the last step; `step_advance` is the needle's advance
  // in this step. Sets each contact's slip rate (the change of xi in this step).
  void apply_friction_law(double step_advance) {
    if (contact_.reactions.size() != contacts_.size()) return;  // just rebuilt: no reactions yet
    slipping_count_ = 0;
    for (std::size_t k = 0; k < contacts_.size(); ++k) {
      Contact& c = contacts_[k];
      const Vec3& lambda = contact_.reactions[k];
      const double fn = lambda.dot(normal(c));
      c.tensile_steps = fn < 0.0 ? c.tensile_steps + 1 : 0;
      c.slip_rate = 0.0;
      if (c.pinned) continue;
      const double ft = lambda.dot(tangent(c));
      const double limit = mu_ * std::max(fn, 0.0);
      if (!c.slipping) {
        if (std::abs(ft) <= limit) continue;
        // Slip starts from the stuck node's motion: it was moving with the needle.
        c.slipping = true;
        c.carried = step_advance;
        c.last_error = 0.0;
      }
      // The node's own advance per step (`carried`, in xi units) is the controlled state, so its motion stays
      // continuous: xi changes by step_advance - carried. Sliding direction: +1 when the tissue slides back
      // along the needle (xi grows), from the relative motion, or when slip starts from the force: the tissue
      // moves the way the needle does not push it.
      const double relative = step_advance - c.carried;
      const double direction = relative != 0.0 ? std::copysign(1.0, relative) : (ft < 0.0 ? 1.0 : -1.0);
      // Target: the friction limit, opposing the sliding.
      const double target = -direction * limit;
      // Integral control: one step of prescribed motion dx along t changes f_t by about dx / gain (dx = dxi
      // |dx/dxi|). The diagonal estimate of the gain ignores the coupling between neighbouring constraints
      // (other contact nodes, a fixed boundary nearby), which stiffens the response: the relaxation halves
      // whenever the error changes sign (overshoot) and recovers slowly while it keeps its sign.
      const double error = target - ft;
      if (error * c.last_error < 0.0)
        c.relaxation = std::max(0.5 * c.relaxation, kMinSlipRelaxation);
      else
        c.relaxation = std::min(1.05 * c.relaxation, kSlipRelaxation);
      c.last_error = error;
      const double carried = c.carried - c.relaxation * error * c.gain / path_stretch(c);
      if ((step_advance - carried) * direction <= 0.0) {  // the relative sliding would stop or reverse: stick
        c.slipping = false;
        continue;
      }
      c.carried = carried;
      c.slip_rate = step_advance - carried;
      ++slipping_count_;
    }
  }

  void release_open_contacts() {
    std::vector<char> keep(contacts_.size(), 1);
    bool changed = false;
    for (std::size_t k = 0; k < contacts_.size(); ++k) {
      const Contact& c = contacts_[k];
      const bool open = !c.pinned && (c.tensile_steps >= release_steps_ || c.xi < -spacing_);
      if (!open) continue;
      in_contact_[c.node] = 0;
      released_before_[c.node] = 1;
      keep[k] = 0;
      changed = true;
      ++released_;
    }
    if (!changed) return;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < contacts_.size(); ++k)
      if (keep[k]) contacts_[kept++] = contacts_[k];
    contacts_.resize(kept);
    contact_.keep_entries(keep);
  }

  bool punctures(const Discretisation& model, std::span<const double> u) {
    if (puncture_force_) {
      // The reactions oscillate from step to step (the explicit pseudo-dynamics; the first step starts the
      // footprint from rest): compare an exponential average over about ten steps.
      smoothed_force_ += 0.1 * (axial_force() - smoothed_force_);
      return smoothed_force_ > *puncture_force_;
    }
    return tip_strain_.largest(model, u, path_.tip(depth_)) > puncture_strain_;
  }

  // Catches the candidate nodes the tip has passed that lie inside the needle's volume, or (after puncture)
  // within the capture radius of the axis unless they were released from the contact before.
  void catch_nodes_inside(const Discretisation& model, std::span<const double> u) {
    for (Index n : candidates_) {
      if (in_contact_[n]) continue;
      const Vec3 x = model.nodes()[n] + model.interpolate_node(n, u);
      const double xi = depth_ - path_.axial(x);
      if (xi <= 0.0) continue;
      const double rho = path_.radial(x);
      const bool inside = rho < surface_radius(xi);
      const bool in_layer = punctured() && !released_before_[n] && rho <= capture_radius_;
      if (inside || in_layer) catch_node(model, n, x, xi, false);
    }
  }

  // The controller's gain: 1 / (the stiffness of the node against one step of prescribed motion), from the
  // diagonal of the constraint correction, sum_I N_I(X_K)^2 / k_I, with k_I the larger of the node's
  // explicit-dynamics stiffness (mass-scaling invariant) and m_I / h^2 for the step h in use (which is larger
  // where no mass scaling lifts the small steps: central differences).
  double compliance(const Discretisation& model, Index node) const {
    double sum = 0.0;
    const auto& rows = model.basis()->interpolation;
    for (std::int64_t k = rows.offsets[node]; k < rows.offsets[node + 1]; ++k) {
      const auto i = static_cast<std::size_t>(rows.nodes[k]);
      const double stiffness = std::max(node_stiffness_[i], step_ > 0.0 ? node_mass_[i] / (step_ * step_) : 0.0);
      if (stiffness > 0.0) sum += rows.values[k] * rows.values[k] / stiffness;
    }
    return sum;
  }

  void catch_node(const Discretisation& model, Index node, const Vec3& x, double xi, bool pinned) {
    Contact c;
    c.node = node;
    const Vec3 offset = (x - path_.entry) - path_.direction * path_.axial(x);
    c.rho = offset.norm();
    if (c.rho > 1e-6 * path_.radius) {
      c.azimuth = offset / c.rho;
    } else {  // on the axis: spread such nodes around it (golden angle) so the cut does not open to one side
      const double angle = 2.399963229728653 * static_cast<double>(axis_nodes_++);
      c.azimuth = std::cos(angle) * e1_ + std::sin(angle) * e2_;
    }
    c.xi = pinned ? depth_ - path_.axial(x) : xi;
    // The map's initial radius, so that it starts at the node's position (or at the needle's surface for a
    // node found inside it; the radial update then moves it out gradually).
    c.rho0 = std::sqrt(std::max(c.rho * c.rho - surface_radius(c.xi) * surface_radius(c.xi), 0.0));
    c.pinned = pinned;
    c.gain = compliance(model, node);
    contacts_.push_back(c);
    contact_.add_node(node, Vec3::Zero());
    in_contact_[node] = 1;
    ++caught_;
  }

  void set_values(const Discretisation& model) {
    for (std::size_t k = 0; k < contacts_.size(); ++k) {
      const Contact& c = contacts_[k];
      const Vec3 x = path_.entry + (depth_ - c.xi) * path_.direction + c.rho * c.azimuth;
      contact_.values[k] = x - model.nodes()[c.node];
    }
  }

  Parameters parameters_;
  NeedlePath path_;
  double tan_tip_, cos_tip_, sin_tip_, mu_, puncture_strain_;
  std::optional<double> puncture_force_, footprint_radius_option_, capture_radius_option_, strain_radius_option_;
  long release_steps_;
  Vec3 e1_, e2_;
  double spacing_ = 0.0, footprint_radius_ = 0.0, capture_radius_ = 0.0, strain_radius_ = 0.0;

  std::vector<double> node_stiffness_, node_mass_;
  double step_ = 0.0;
  std::vector<Index> candidates_;
  TipStrainWatch tip_strain_;
  std::vector<char> in_contact_, released_before_;
  std::vector<Contact> contacts_;
  NodalConstraints contact_;
  bool punctured() const { return puncture_depth_.has_value(); }
  std::optional<double> puncture_depth_;  // where the needle punctured, once it has
  double depth_ = 0.0, smoothed_force_ = 0.0;
  long axis_nodes_ = 0, caught_ = 0, released_ = 0, slipping_count_ = 0;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::NeedleModel, mtled::RigidContactNeedle)
