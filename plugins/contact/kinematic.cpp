// `kinematic`: the paper's kinematic needle model (Wittek et al., section 2.2). Two image-derived
// parameters, no tissue-needle friction model:
//  - indentation: the surface nodes under the tip (the footprint) follow the tip until the largest
//    principal Green strain at the integration points near the tip exceeds the puncture strain;
//  - penetration: each node within the capture radius of the axis is captured when the tip passes its
//    current position, and from then on is driven along the axis at C_D times the needle's further advance,
//    keeping its lateral position (the gel sticks to the shaft). Captured at their current displacement,
//    nodes never jump.
// The needle force is the force needed to impose this motion: the sum of the driven nodes' reactions along
// the axis. Every modelling choice the paper leaves open is listed in docs/needle-models.md.
#include <fmt/format.h>

#include <algorithm>

#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "needle_geometry.hpp"

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
        .doc("C_D: tissue beside the shaft moves this fraction of the needle's advance (the paper: 0.4, from "
             "X-ray images of Sylgard 527)");
    d.number("puncture_strain")
        .unit("1")
        .non_negative()
        .defaults(1e-5)
        .doc("epsilon_p: the needle punctures the surface when the largest principal Green strain near the tip "
             "exceeds this (the paper: 1e-5, a very short indentation)");
    d.number("capture_radius")
        .unit("m")
        .positive()
        .optional()
        .doc("nodes within this distance of the needle axis are driven once the tip passes them; default: the "
             "larger of the needle radius and 0.6 x the node spacing at the entry, so a coarse cloud still has "
             "nodes on the path");
    d.number("strain_radius")
        .unit("m")
        .positive()
        .optional()
        .doc("integration points within this distance of the tip are watched for the puncture strain; default: "
             "the larger of the needle diameter and the node spacing at the entry");
    d.example({{"entry", {0.0, 0.0, 0.017}}, {"depth", 0.005}});
  }

  explicit KinematicNeedle(const Parameters& p)
      : parameters_(p),
        path_(read_needle_path(p)),
        coefficient_(p.number("deformation_coefficient")),
        puncture_strain_(p.number("puncture_strain")),
        capture_radius_option_(p.optional_number("capture_radius")),
        strain_radius_option_(p.optional_number("strain_radius")) {
    driven_.name = "needle";
    driven_.components = {true, true, true};
  }

  void setup(const Model& model) override {
    check_needle_enters_body(path_, model, parameters_);
    const double spacing = spacing_at_entry(path_, model);
    capture_radius_ = capture_radius_option_.value_or(std::max(path_.radius, 0.6 * spacing));
    strain_radius_ = strain_radius_option_.value_or(std::max(2.0 * path_.radius, spacing));

    // Footprint: surface nodes near the entry within the capture radius of the axis (at least the nearest).
    const auto& surface = model.surface();
    Index nearest = -1;
    double nearest_distance = INFINITY;
    for (Index i = 0; i < model.node_count(); ++i) {
      if (!surface[i]) continue;
      const Vec3& x = model.nodes()[i];
      const double d = (x - path_.entry).norm();
      if (d < nearest_distance) {
        nearest_distance = d;
        nearest = i;
      }
      if (std::abs(path_.axial(x)) <= 0.5 * spacing && path_.radial(x) <= capture_radius_) footprint_.push_back(i);
    }
    if (footprint_.empty()) footprint_.push_back(nearest);

    // Candidates for capture: nodes near the axis, ahead of the entry and within reach of the final depth,
    // ordered along the path.
    for (Index i = 0; i < model.node_count(); ++i) {
      const Vec3& x = model.nodes()[i];
      const double s = path_.axial(x);
      if (path_.radial(x) <= capture_radius_ && s > -0.5 * spacing && s <= path_.depth + spacing)
        candidates_.push_back(i);
    }
    std::sort(candidates_.begin(), candidates_.end(), [&](Index a, Index b) {
      return path_.axial(model.nodes()[a]) < path_.axial(model.nodes()[b]);
    });
    captured_.assign(static_cast<std::size_t>(model.node_count()), 0);

    // Integration points near the entry that the puncture test watches during indentation.
    for (Index ip = 0; ip < model.integration_point_count(); ++ip)
      if ((model.ip_positions()[ip] - path_.entry).norm() <= strain_radius_ + path_.depth) watched_.push_back(ip);

    for (Index n : footprint_) drive(n, Vec3::Zero(), 0.0);
    log().info("kinematic needle: footprint {} nodes, {} candidate nodes within {:.3g} mm of the axis, C_D = {:g}",
               footprint_.size(), candidates_.size(), 1e3 * capture_radius_, coefficient_);
  }

  void update(const LoadState& load, const Model& model, std::span<const double> u) override {
    const double advance = load.load_fraction * path_.depth;
    if (punctured_) {
      capture_passed_nodes(model, u, advance);
    } else if (largest_strain_near_tip(model, u, advance) > puncture_strain_) {
      punctured_ = true;
      puncture_depth_ = depth_;
      log().info("kinematic needle: puncture at depth {:.4g} mm", 1e3 * puncture_depth_);
      capture_passed_nodes(model, u, advance);
    }
    depth_ = advance;
    // Prescribed displacements: the footprint follows the tip until puncture; afterwards every driven node
    // moves C_D times the advance since its capture along the axis.
    for (std::size_t k = 0; k < driven_.nodes.size(); ++k) {
      const double since = std::max(0.0, advance - capture_depth_[k]);
      const double rate = punctured_ ? coefficient_ : 1.0;
      driven_.values[k] = captured_at_[k] + rate * since * path_.direction;
    }
  }

  std::vector<NodalConstraints*> constraints() override { return {&driven_}; }

  NeedleStatus status() const override {
    NeedleStatus s;
    s.depth = depth_;
    double force = 0.0;
    for (const auto& r : driven_.reactions) force += r.dot(path_.direction);
    s.force = force;
    s.phase = punctured_ ? "penetration" : "indentation";
    s.puncture_depth = punctured_ ? puncture_depth_ : -1.0;
    s.driven_nodes = static_cast<Index>(driven_.nodes.size());
    return s;
  }

 private:
  void drive(Index node, const Vec3& displacement, double advance) {
    captured_[node] = 1;
    driven_.nodes.push_back(node);
    driven_.values.push_back(displacement);
    captured_at_.push_back(displacement);
    capture_depth_.push_back(advance);
    ++driven_.revision;
  }

  // Restart the footprint nodes at puncture: from now on they move with C_D like every captured node.
  void capture_passed_nodes(const Model& model, std::span<const double> u, double advance) {
    if (!restarted_footprint_) {
      for (std::size_t k = 0; k < driven_.nodes.size(); ++k) {
        captured_at_[k] = driven_.values[k];
        capture_depth_[k] = depth_;
      }
      restarted_footprint_ = true;
    }
    while (next_candidate_ < candidates_.size()) {
      const Index n = candidates_[next_candidate_];
      if (captured_[n]) {
        ++next_candidate_;
        continue;
      }
      // The tip passes the node when its advance reaches the node's current axial position.
      const Vec3 displacement = model.interpolate_node(n, u);
      const double position = path_.axial(model.nodes()[n] + displacement);
      if (advance < position) break;
      drive(n, displacement, advance);
      ++next_candidate_;
    }
  }

  double largest_strain_near_tip(const Model& model, std::span<const double> u, double advance) const {
    const Vec3 tip = path_.tip(advance);
    double largest = 0.0;
    for (Index ip : watched_) {
      if ((model.ip_positions()[ip] - tip).norm() > strain_radius_) continue;
      const Mat3 F = model.deformation_gradient(ip, u);
      const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
      const Eigen::SelfAdjointEigenSolver<Mat3> eigen(E, Eigen::EigenvaluesOnly);
      largest = std::max(largest, eigen.eigenvalues().cwiseAbs().maxCoeff());
    }
    return largest;
  }

  Parameters parameters_;
  NeedlePath path_;
  double coefficient_, puncture_strain_;
  std::optional<double> capture_radius_option_, strain_radius_option_;
  double capture_radius_ = 0.0, strain_radius_ = 0.0;

  std::vector<Index> footprint_, candidates_, watched_;
  std::vector<char> captured_;
  std::size_t next_candidate_ = 0;
  NodalConstraints driven_;
  std::vector<Vec3> captured_at_;     // displacement when the current driving began
  std::vector<double> capture_depth_;  // needle advance when the current driving began
  bool punctured_ = false, restarted_footprint_ = false;
  double depth_ = 0.0, puncture_depth_ = 0.0;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::NeedleModel, mtled::KinematicNeedle)
