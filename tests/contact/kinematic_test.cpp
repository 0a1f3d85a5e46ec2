// The kinematic needle (plugins/contact/kinematic.cpp, the paper's model) through the real loader and the
// real simulation loop, on a small gel cylinder: puncture and penetration, C_D at the entry, and the
// options of docs/needle-models.md ("drive", "lateral") as they show in the converged state.
#include <gtest/gtest.h>

#include <cmath>

#include "mtled/errors.hpp"
#include "mtled/needle/needle_geometry.hpp"
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"
#include "test_support.hpp"
#include "twin_needles.hpp"

namespace mtled {
namespace {

// A cylinder of the paper's gel, r = 6 mm, h = 8 mm, about 600 nodes (spacing 1.3 mm), bottom fixed; a 1.6 mm
// needle along -z through the top centre to 5 mm with C_D = 0.4.
constexpr double kDepth = 5e-3;
constexpr double kHeight = 8e-3;
constexpr double kCoefficient = 0.4;

json scene_json(const json& needle_options, const json& direction = {0, 0, -1}) {
  json needle = {{"type", "kinematic"},    {"diameter", 1.6e-3}, {"entry", {0.0, 0.0, kHeight}},
                 {"direction", direction}, {"depth", kDepth},    {"deformation_coefficient", kCoefficient}};
  needle.update(needle_options);
  return test::gel_cylinder_scene(kHeight, needle);
}

struct Driven {
  double reference_axial;  // depth of the node's reference position below the entry (m)
  Vec3 displacement;       // interpolated, final
};
struct Outcome {
  NeedleStatus status;
  std::array<bool, 3> components{};
  std::vector<Driven> driven;       // nodes
  std::vector<Driven> shaft;        // material points on the shaft's surface
  std::vector<Vec3> shaft_offsets;  // their reference offsets from the axis
  double spacing = 0.0;
};

Outcome run(const json& needle_options, const json& integrator_options = json::object()) {
  const test::OneThread one_thread;
  json scene_file = scene_json(needle_options);
  scene_file["integrator"].update(integrator_options);
  const Scene scene = validate_scene(parse_scene(scene_file.dump(), "kinematic_test.json"), test::catalog());
  Simulation simulation(scene, test::catalog());
  simulation.loop().run();
  Outcome out;
  out.status = simulation.system().needle()->status();
  const Discretisation& model = simulation.system().discretisation();
  const std::vector<double> u =
      test::interpolated(simulation.system().discretisation(), simulation.system().displacement());
  for (const NodalConstraints* set : simulation.system().constraint_sets()) {
    if (set->name == "needle") {
      out.components = set->components();
      for (Index n : set->nodes())
        out.driven.push_back({kHeight - model.nodes()[n].z(), Vec3(u[3 * n], u[3 * n + 1], u[3 * n + 2])});
    }
    if (set->name != "needle_shaft") continue;
    // The displacement interpolated at each point from the nodal parameters, independently of the kernel's rows.
    std::vector<Index> support;
    std::vector<double> values;
    for (const Vec3& x : set->points()) {
      EXPECT_TRUE(model.shape_functions_at(x, support, values));
      Vec3 displacement = Vec3::Zero();
      for (std::size_t k = 0; k < support.size(); ++k)
        displacement += values[k] * Vec3(simulation.system().displacement().subspan(3 * support[k], 3).data());
      out.shaft.push_back({kHeight - x.z(), displacement});
      out.shaft_offsets.push_back(Vec3(x.x(), x.y(), 0.0));
    }
  }
  for (double h : model.cloud().spacing) out.spacing += h / static_cast<double>(model.node_count());
  return out;
}

// The paper's literal reading: nodes near the axis, C_D times the advance since capture, lateral held.
const json kPaperNodes = {{"driven", "nodes_near_axis"}, {"drive", "since_capture"}, {"lateral", "held"}};

TEST(KinematicNeedle, PuncturesThenDrivesTheEntryAtCdTimesTheAdvance) {
  const Outcome out = run(kPaperNodes);
  EXPECT_EQ(out.status.phase, NeedlePhase::penetration);
  EXPECT_GT(out.status.puncture_depth, 0.0);
  EXPECT_LT(out.status.puncture_depth, 0.05 * kDepth);  // epsilon_p = 1e-5: a very short indentation
  EXPECT_TRUE(std::isfinite(out.status.force));
  EXPECT_GT(out.status.force, 0.0);  // the needle pushes the tissue along its direction
  ASSERT_GE(out.driven.size(), 3u);
  // The footprint (top surface) moves the puncture depth plus C_D times the rest of the advance: U2/U1 = C_D
  // up to the short indentation, enforced on the interpolated field to round-off.
  const double expected = out.status.puncture_depth + kCoefficient * (kDepth - out.status.puncture_depth);
  int at_top = 0;
  for (const Driven& d : out.driven) {
    if (d.reference_axial > 1e-9) continue;
    ++at_top;
    EXPECT_NEAR(-d.displacement.z(), expected, 1e-12);
  }
  EXPECT_GE(at_top, 1);
}

TEST(KinematicNeedle, FromReferenceOnThePathGivesGeometricDisplacements) {
  const Outcome out = run({{"driven", "nodes_near_axis"}, {"drive", "from_reference"}, {"lateral", "path"}});
  ASSERT_GE(out.driven.size(), 3u);
  int checked = 0;
  for (const Driven& d : out.driven) {
    // Captured when the tip reached its reference depth s: axial displacement C_D (depth - s), or more when
    // the node had already been pulled further; lateral displacement returned to the path within one node
    // spacing of advance.
    EXPECT_GE(-d.displacement.z(), kCoefficient * (kDepth - d.reference_axial) - 1e-12);
    if (d.reference_axial < kDepth - 2.0 * out.spacing) {
      ++checked;
      EXPECT_LT(std::hypot(d.displacement.x(), d.displacement.y()), 1e-12);
    }
  }
  EXPECT_GE(checked, 2);
}

TEST(KinematicNeedle, FreeLateralPrescribesOnlyTheAxialComponent) {
  const Outcome out = run({{"driven", "nodes_near_axis"}, {"lateral", "free"}});
  EXPECT_EQ(out.components, (std::array<bool, 3>{false, false, true}));
  EXPECT_EQ(out.status.phase, NeedlePhase::penetration);
  // Nothing holds the driven nodes across the axis: some move sideways.
  double largest_lateral = 0.0;
  for (const Driven& d : out.driven)
    largest_lateral = std::max(largest_lateral, std::hypot(d.displacement.x(), d.displacement.y()));
  EXPECT_GT(largest_lateral, 1e-7);
}

TEST(KinematicNeedle, ShaftSurfacePointsFollowTheNeedleAroundTheAxis) {
  const Outcome out = run(json::object());  // the defaults: shaft_surface, from_reference, path
  EXPECT_EQ(out.status.phase, NeedlePhase::penetration);
  EXPECT_GT(out.status.force, 0.0);
  ASSERT_GE(out.shaft.size(), 9u);  // rings of at least 3 points, one ring per node spacing down to 5 mm
  Vec3 offset_sum = Vec3::Zero();
  int checked = 0;
  for (std::size_t k = 0; k < out.shaft.size(); ++k) {
    const Driven& d = out.shaft[k];
    EXPECT_NEAR(out.shaft_offsets[k].norm(), 0.8e-3, 1e-12);  // on the shaft's surface
    offset_sum += out.shaft_offsets[k];
    // The kernel enforced the prescribed value on the interpolated field: C_D (depth - s) at least, back on
    // the path once the tip is a node spacing past.
    EXPECT_GE(-d.displacement.z(), kCoefficient * (kDepth - d.reference_axial) - 1e-12);
    if (d.reference_axial < kDepth - 2.0 * out.spacing) {
      ++checked;
      EXPECT_LT(std::hypot(d.displacement.x(), d.displacement.y()), 1e-12);
    }
    // The ring at the entry replaced the footprint at puncture: U2 / U1 = C_D exactly.
    if (d.reference_axial < 1e-12) {
      EXPECT_NEAR(-d.displacement.z(), kCoefficient * kDepth, 1e-12);
    }
  }
  EXPECT_GE(checked, 3);
  EXPECT_TRUE(out.driven.empty());
  // Full rings: the points balance about the axis.
  EXPECT_LT(offset_sum.norm(), 1e-12);
}

// drag_limit (not in the paper): the tissue on the shaft follows it at C_D until dragged that far, then stays
// while the shaft slides past; a limit the run never reaches changes nothing.
TEST(KinematicNeedle, ADragLimitHoldsTheTissueThereWhileTheShaftSlidesPast) {
  const double limit = 1e-3;  // the entry would be dragged C_D x 5 mm = 2 mm
  const Outcome out = run({{"drag_limit", limit}});
  EXPECT_EQ(out.status.phase, NeedlePhase::penetration);
  int slipped = 0, following = 0;
  for (const Driven& d : out.shaft) {
    const double unlimited = kCoefficient * (kDepth - d.reference_axial);
    if (unlimited > limit) {
      ++slipped;
      EXPECT_NEAR(-d.displacement.z(), limit, 1e-12) << "at " << d.reference_axial;
    } else if (unlimited > 0.0) {
      ++following;
      EXPECT_GE(-d.displacement.z(), unlimited - 1e-12) << "at " << d.reference_axial;
    }
  }
  EXPECT_GE(slipped, 3);
  EXPECT_GE(following, 3);

  const Outcome paper = run(json::object());
  const Outcome unreached = run({{"drag_limit", 1.01 * kCoefficient * kDepth}});
  EXPECT_EQ(unreached.status.force, paper.status.force);
  // The slipped tissue no longer resists the advance as the dragged tissue did: less force.
  EXPECT_LT(out.status.force, paper.status.force);
}

// settle_steps: each captured entry moves from where it was captured onto C_D x (advance - s) over that many steps, so
// the relaxed state forgets the captures and the ramp rate stops mattering; the default keeps the captured axial
// displacement as a floor, which a faster ramp captures lower.
TEST(KinematicNeedle, SettlingForgetsTheCapturesSoTheRampRateDoesNotMatter) {
  const auto force = [](const json& needle, long load_steps) {
    return run(needle, {{"load_steps", load_steps}, {"tolerance", 1e-6}}).status.force;
  };
  const json settle = {{"settle_steps", 50}};
  const double fast = force(settle, 40), slow = force(settle, 320);
  ASSERT_GT(slow, 0.0);
  // The relaxation's tolerance (1e-6 of the largest displacement) leaves the force within about 1e-4.
  EXPECT_NEAR(fast, slow, 1e-3 * slow);
  const double fast_floor = force(json::object(), 40), slow_floor = force(json::object(), 320);
  EXPECT_GT(std::abs(fast_floor - slow_floor), 1e-2 * slow_floor) << "the default no longer depends on the ramp";
}

TEST(KinematicNeedle, FreeLateralRefusesAnObliqueNeedle) {
  json scene = scene_json({{"lateral", "free"}}, {0.0, 0.6, -0.8});
  try {
    const Scene s = validate_scene(parse_scene(scene.dump(), "kinematic_test.json"), test::catalog());
    Simulation simulation(s, test::catalog());
    FAIL() << "an oblique needle with lateral free was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("/needle/lateral"), std::string::npos) << message;
    EXPECT_NE(message.find("coordinate axis"), std::string::npos) << message;
  }
}

// Under MPI only the nodes a needle declares are gathered before it updates: those must be all it reads
// (tests/support/twin_needles.hpp), in each of the four ways to drive.
TEST(KinematicNeedle, ReadsOnlyTheNodesItDeclares) {
  const test::OneThread one_thread;
  for (const json& options : {json{{"driven", "shaft_surface"}, {"drive", "from_reference"}}, kPaperNodes,
                              json{{"driven", "nodes_near_axis"}, {"drive", "from_reference"}},
                              json{{"driven", "shaft_surface"}, {"drive", "since_capture"}}}) {
    SCOPED_TRACE(options.dump());
    test::expect_needle_reads_only_what_it_declares(scene_json(options));
  }
}

}  // namespace

// The needle's trajectory from a 3D Slicer markups file: the first two placed control points, in metres, in the
// file's frame; what is not a usable markups file is refused naming the field.
TEST(MarkupsTrajectory, ReadsSlicersLineAndPointList) {
  const auto line = parse_markups_trajectory(
      R"({"markups": [{"type": "Line", "coordinateSystem": "LPS", "coordinateUnits": "mm", "controlPoints": [
          {"label": "L-1", "position": [25.0, 6.0, 70.0], "positionStatus": "defined"},
          {"label": "L-2", "position": [25.0, 6.0, -30.0], "positionStatus": "defined"}]}]})",
      "line.mrk.json");
  EXPECT_EQ(line.frame, "LPS");
  EXPECT_NEAR((line.entry - Vec3(0.025, 0.006, 0.070)).norm(), 0.0, 1e-17);
  EXPECT_NEAR((line.target - Vec3(0.025, 0.006, -0.030)).norm(), 0.0, 1e-17);
  // A point list in RAS and micrometres, its first point only previewed (not placed): the next two count.
  const auto points = parse_markups_trajectory(
      R"({"markups": [{"type": "Fiducial", "coordinateSystem": "RAS", "coordinateUnits": "um", "controlPoints": [
          {"position": [1, 2, 3], "positionStatus": "preview"}, {"position": [1000, 0, 0]},
          {"position": [0, 0, -2000]}, {"position": [9, 9, 9]}]}]})",
      "points.mrk.json");
  EXPECT_EQ(points.frame, "RAS");
  EXPECT_NEAR((points.entry - Vec3(0.001, 0, 0)).norm(), 0.0, 1e-18);
  EXPECT_NEAR((points.target - Vec3(0, 0, -0.002)).norm(), 0.0, 1e-18);

  const auto refused = [](const std::string& text, const std::string& expected) {
    try {
      parse_markups_trajectory(text, "bad.mrk.json");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused("222e22222", "not a 3D Slicer markups file");  // a number out of range (found by fuzz_markups)
  refused(R"({"nodes": []})", "no \"markups\" list");
  refused(R"({"markups": [{"type": 3}]})", "/markups/0/type");
  refused(R"({"markups": [{"coordinateSystem": "IJK"}]})", "coordinateSystem");
  refused(R"({"markups": [{"coordinateUnits": "cm"}]})", "coordinateUnits");
  refused(R"({"markups": [{"controlPoints": [{"position": [0, 0, 0]}]}]})", "needs two");
  refused(R"({"markups": [{"controlPoints": [{"position": [0, 0]}, {"position": [0, 0, 1]}]}]})", "/controlPoints/0");
  refused(R"({"markups": [{"controlPoints": [{"position": [1, 1, 1]}, {"position": [1, 1, 1]}]}]})", "same point");
}

}  // namespace mtled
