// The rigid_contact needle (plugins/contact/rigid_contact.cpp) through the real loader and the real
// simulation loop, on a small gel cylinder: parameter checks, non-penetration, Coulomb's law at every contact
// node, and the friction coefficient's effect on the needle force.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"
#include "test_support.hpp"
#include "twin_needles.hpp"

namespace mtled {
namespace {

// A cylinder of the paper's gel, r = 6 mm, h = 8 mm, about 600 nodes (spacing 1.3 mm), bottom fixed; a 1.6 mm
// needle along -z through the top centre to 5 mm. A 25 deg cone (1.7 mm long) leaves 3.3 mm of shaft in the
// tissue.
constexpr double kRadius = 0.8e-3;
constexpr double kDepth = 5e-3;
constexpr double kHeight = 8e-3;
constexpr double kTipAngleDeg = 25.0;
constexpr double kShearModulus = 722.0;  // the gel's Ogden mu (Pa)
const Vec3 kEntry(0.0, 0.0, kHeight);
const Vec3 kDirection(0.0, 0.0, -1.0);

json needle_block(double mu) {
  return {{"type", "rigid_contact"},   {"diameter", 2 * kRadius}, {"entry", {0.0, 0.0, kHeight}},
          {"direction", {0, 0, -1}},   {"depth", kDepth},         {"tip_angle", kTipAngleDeg},
          {"friction_coefficient", mu}};
}

json scene_json(const json& needle) { return test::gel_cylinder_scene(kHeight, needle); }

Scene make_scene(const json& scene) {
  return validate_scene(parse_scene(scene.dump(), "contact_test.json"), test::catalog());
}

// The state of a finished run that the checks need (the simulation itself is not kept: one run per case).
struct Contact {
  Vec3 position;  // interpolated, current
  Vec3 reaction;  // force the contact exerts on the tissue (N)
};
struct Outcome {
  NeedleStatus status;
  std::vector<Contact> contacts;
  std::vector<Vec3> positions;  // every node, interpolated, current
  double error_bound = 0.0;     // dynamic relaxation's bound on the distance to the steady state (m)
  double spacing = 0.0;         // mean node spacing (m)
};


Outcome run(const json& needle) {
  const test::OneThread one_thread;
  const Scene scene = make_scene(scene_json(needle));
  Simulation simulation(scene, test::catalog());
  simulation.loop().run();
  Outcome out;
  out.status = simulation.system().needle()->status();
  const Discretisation& model = simulation.system().discretisation();
  const std::vector<double> u =
      test::interpolated(simulation.system().discretisation(), simulation.system().displacement());
  for (Index i = 0; i < model.node_count(); ++i)
    out.positions.push_back(model.nodes()[i] + Vec3(u[3 * i], u[3 * i + 1], u[3 * i + 2]));
  for (const NodalConstraints* set : simulation.system().constraint_sets()) {
    if (set->name != "needle") continue;
    for (std::size_t k = 0; k < set->nodes().size(); ++k)
      out.contacts.push_back({out.positions[set->nodes()[k]], set->reactions[k]});
  }
  out.error_bound = simulation.loop().integrator().report().relaxation.value().error_bound;
  for (double h : model.cloud().spacing) out.spacing += h / static_cast<double>(model.node_count());
  return out;
}

// One run per friction coefficient, shared by the tests.
const Outcome& outcome(double mu) {
  static std::map<double, Outcome> runs;
  auto it = runs.find(mu);
  if (it == runs.end()) it = runs.emplace(mu, run(needle_block(mu))).first;
  return it->second;
}

// Needle geometry at the final depth: distance behind the tip along the axis, distance from the axis, and
// the needle's radius there (cone, then shaft).
struct Local {
  double xi, rho, surface;
  Vec3 radial;  // unit, normal to the axis
};
Local local(const Vec3& x) {
  const Vec3 from_entry = x - kEntry;
  const double axial = from_entry.dot(kDirection);
  const Vec3 offset = from_entry - axial * kDirection;
  Local l;
  l.xi = kDepth - axial;
  l.rho = offset.norm();
  l.radial = l.rho > 0.0 ? Vec3(offset / l.rho) : Vec3::UnitX();
  const double tan_tip = std::tan(kTipAngleDeg * std::numbers::pi / 180.0);
  l.surface = std::min(kRadius, std::max(l.xi, 0.0) * tan_tip);
  return l;
}

// The contact frame the model documents (docs/needle-models.md): the level set rho^2 - R(xi)^2 = const of the
// cavity-expansion map, normal along rho e_rho + R R' d, generator t along R R' e_rho - rho d.
void frame(const Contact& c, Vec3& normal, Vec3& tangent) {
  const Local l = local(c.position);
  const double tan_tip = std::tan(kTipAngleDeg * std::numbers::pi / 180.0);
  const double slope = l.xi > 0.0 && l.xi * tan_tip < kRadius ? tan_tip : 0.0;
  const double rr = l.surface * slope;
  normal = (l.rho * l.radial + rr * kDirection).normalized();
  tangent = (rr * l.radial - l.rho * kDirection).normalized();
}

bool on_shaft(const Contact& c) { return local(c.position).surface >= kRadius; }

// ---- parameters

TEST(RigidContact, DeclaresItsParametersWithUnitsAndRanges) {
  const ComponentDeclaration& d = test::catalog().load(Category::needle, "rigid_contact");
  for (const char* name : {"diameter", "entry", "direction", "depth", "tip_angle", "friction_coefficient",
                           "puncture_strain", "puncture_force", "capture_radius", "footprint_radius"}) {
    const ParameterSpec* spec = d.find(name);
    ASSERT_NE(spec, nullptr) << name;
    EXPECT_FALSE(spec->unit.empty()) << name;
    EXPECT_FALSE(spec->doc.empty()) << name;
  }
  EXPECT_EQ(d.find("tip_angle")->unit, "deg");
  EXPECT_EQ(d.find("friction_coefficient")->range.describe(), "[0, 2]");
}

TEST(RigidContact, RefusesOutOfRangeValuesNamingThePointer) {
  const ComponentDeclaration& d = test::catalog().load(Category::needle, "rigid_contact");
  json block = needle_block(0.3);
  block["tip_angle"] = 95;
  block["friction_coefficient"] = -0.1;
  std::vector<Problem> problems;
  validate_parameters(d, block, "/needle", problems);
  ASSERT_EQ(problems.size(), 2u);
  std::string text;
  for (const auto& p : problems) text += p.format() + "\n";
  EXPECT_NE(text.find("/needle/tip_angle"), std::string::npos) << text;
  EXPECT_NE(text.find("/needle/friction_coefficient"), std::string::npos) << text;
}

TEST(RigidContact, RefusesACaptureRadiusInsideTheNeedle) {
  // Valid on its own (> 0), but nodes inside the needle join the contact anyway: the scene is contradictory.
  json needle = needle_block(0.3);
  needle["capture_radius"] = 0.5e-3;
  const ComponentDeclaration& d = test::catalog().load(Category::needle, "rigid_contact");
  std::vector<Problem> problems;
  needle.erase("type");
  const Parameters p = validate_parameters(d, needle, "/needle", problems);
  ASSERT_TRUE(problems.empty());
  try {
    test::catalog().create<NeedleModel>("rigid_contact", p);
    FAIL() << "a capture radius below the needle radius was accepted";
  } catch (const InputError& e) {
    ASSERT_EQ(e.problems().size(), 1u);
    EXPECT_EQ(e.problems()[0].where, "/needle/capture_radius");
    EXPECT_NE(e.problems()[0].message.find("below the needle's radius (0.8 mm)"), std::string::npos) << e.what();
  }
}

TEST(RigidContact, RefusesAnEntryOffTheBody) {
  json needle = needle_block(0.3);
  needle["entry"] = {0.0, 0.0, kHeight + 0.005};  // 5 mm above the top face
  const test::OneThread one_thread;
  const Scene scene = make_scene(scene_json(needle));
  try {
    Simulation simulation(scene, test::catalog());
    FAIL() << "an entry 5 mm off the surface was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.problems().at(0).where.find("/needle/entry"), std::string::npos) << e.what();
  }
}

// ---- mechanics

// ctest runs each test in its own process: tests sharing a run are kept together.
TEST(RigidContact, PuncturesKeepsTissueOutOfTheNeedleAndReportsTheForce) {
  const Outcome& o = outcome(0.3);
  EXPECT_EQ(o.status.phase, NeedlePhase::penetration);
  EXPECT_GE(o.status.puncture_depth, 0.0);
  EXPECT_LT(o.status.puncture_depth, kDepth);
  EXPECT_DOUBLE_EQ(o.status.depth, kDepth);
  EXPECT_TRUE(std::isfinite(o.status.force));
  EXPECT_GT(o.status.force, 0.0);  // the needle pushes the tissue the way it goes
  EXPECT_GT(o.status.driven_nodes, 0);
  EXPECT_EQ(static_cast<std::size_t>(o.status.driven_nodes), o.contacts.size());
  double sum = 0.0;
  for (const auto& c : o.contacts) sum += c.reaction.dot(kDirection);
  EXPECT_NEAR(o.status.force, sum, 1e-12 * std::abs(sum));  // the force is the contacts' axial reactions

  // Contact nodes are prescribed onto (or outside) the needle's surface and enforced to round-off; any other
  // node is caught in the step after it enters, so at most the last step's motion, which the steady-state
  // error bound of dynamic relaxation covers, can be inside.
  ASSERT_GT(o.contacts.size(), 0u);
  int on_the_shaft = 0;
  for (const auto& c : o.contacts) {
    const Local l = local(c.position);
    EXPECT_GE(l.rho, l.surface - 1e-9 * kRadius) << "contact node inside the needle: xi " << l.xi;
    if (on_shaft(c)) ++on_the_shaft;
  }
  EXPECT_GT(on_the_shaft, 0);
  for (const Vec3& x : o.positions) {
    const Local l = local(x);
    EXPECT_GE(l.rho, l.surface - o.error_bound) << "node inside the needle at xi " << l.xi;
  }
}

TEST(RigidContact, CoulombHoldsAtEveryContactNodeAndFrictionAddsToTheForce) {
  // |f_t| <= mu f_n along the generator: stick nodes by the test that keeps them stuck, slip nodes because
  // the slip controller converges onto mu f_n. The reactions are read one step after the last decision; at
  // the steady state a step moves nodes by at most the error bound e, which changes a reaction by at most
  // the stiffness of the tissue around a node, about 2 pi G h (a rigid inclusion of size h in an
  // incompressible solid), times e.
  for (double mu : {0.0, 0.3}) {
    const Outcome& o = outcome(mu);
    const double slack = 2.0 * std::numbers::pi * kShearModulus * o.spacing * o.error_bound;
    int compressed = 0;
    for (const auto& c : o.contacts) {
      Vec3 n, t;
      frame(c, n, t);
      const double fn = c.reaction.dot(n), ft = c.reaction.dot(t);
      EXPECT_LE(std::abs(ft), mu * std::max(fn, 0.0) + slack)
          << "mu " << mu << ": f_t " << ft << " N, f_n " << fn << " N at xi " << local(c.position).xi;
      if (fn > 0.0) ++compressed;
    }
    EXPECT_GT(compressed, 0) << "the needle must press on some tissue";
  }

  // mu = 0: the tissue slides freely along the shaft, so the axial force comes from the cone's normal forces
  // only, and it is smaller than with friction.
  const Outcome& smooth = outcome(0.0);
  const Outcome& rough = outcome(0.3);
  double shaft = 0.0, tip = 0.0;
  for (const auto& c : smooth.contacts) {
    const double axial = c.reaction.dot(kDirection);
    (on_shaft(c) ? shaft : tip) += axial;
  }
  const double slack = 2.0 * std::numbers::pi * kShearModulus * smooth.spacing * smooth.error_bound;
  EXPECT_LE(std::abs(shaft), slack * static_cast<double>(smooth.contacts.size())) << "tip " << tip;
  EXPECT_GT(tip, 0.0);
  EXPECT_LT(smooth.status.force, rough.status.force);
}

TEST(RigidContact, BeforePunctureTheFootprintFollowsTheTip) {
  // A puncture force far above anything the tissue can carry: the tip only indents, and the footprint nodes
  // (pinned to the apex) move exactly with the needle.
  constexpr double kIndentation = 0.003;
  json needle = needle_block(0.3);
  needle["puncture_force"] = 100.0;
  needle["depth"] = kIndentation;
  const test::OneThread one_thread;
  const Scene scene = make_scene(scene_json(needle));
  Simulation simulation(scene, test::catalog());
  simulation.loop().run();
  const NeedleStatus s = simulation.system().needle()->status();
  EXPECT_EQ(s.phase, NeedlePhase::indentation);
  EXPECT_LT(s.puncture_depth, 0.0);
  EXPECT_GT(s.force, 0.0);
  const std::vector<double> u =
      test::interpolated(simulation.system().discretisation(), simulation.system().displacement());
  for (const NodalConstraints* set : simulation.system().constraint_sets()) {
    if (set->name != "needle") continue;
    ASSERT_FALSE(set->nodes().empty());
    for (Index n : set->nodes()) {
      const Vec3 d(u[3 * n], u[3 * n + 1], u[3 * n + 2]);
      EXPECT_NEAR((d - kIndentation * kDirection).norm(), 0.0, 1e-9 * kIndentation) << "node " << n;
    }
  }
}

// What the needle says it reads is all it reads (tests/support/twin_needles.hpp), with friction and without, and
// with the puncture decided by the strain near the tip.
TEST(RigidContact, ReadsOnlyTheNodesItDeclares) {
  const test::OneThread one_thread;
  for (const double mu : {0.0, 0.3}) {
    SCOPED_TRACE(mu);
    test::expect_needle_reads_only_what_it_declares(scene_json(needle_block(mu)));
  }
}

}  // namespace
}  // namespace mtled
