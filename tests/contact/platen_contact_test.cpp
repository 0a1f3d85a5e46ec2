// The `platen_contact` boundary against what contact mechanics says: a cube pushed across a gap onto a frictionless
// platen ends in the exact homogeneous uniaxial state (the platen's reaction balancing the pushed face's), touches
// nothing while the gap is open, and a sticking platen holds the face where it touched; the semi-confined
// compression's free side, which passes through its bonded platens without it, stays on their planes with it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hyperelastic_exact.hpp"
#include "mtled/analysis/result_file.hpp"
#include "test_support.hpp"

namespace mtled::test {
namespace {

namespace fs = std::filesystem;

constexpr double kSide = 0.01;   // m: the cube's edge
constexpr double kGap = 0.0005;  // m: from the cube's bottom face down to the platen

// The shipped Ogden cube (uniaxial_cube_ogden.json: planes x = 0 and y = 0 held normal to themselves), its top face
// moved `push` down, its bottom face free `gap` above a platen.
json cube_over_platen(double gap, double push, const std::string& tangential) {
  json scene = read_json(source_dir() / "share/scenes/uniaxial_cube_ogden.json");
  scene.erase("description");
  scene["boundaries"][0] = {{"type", "platen_contact"},
                            {"name", "platen"},
                            {"point", {0.0, 0.0, -gap}},
                            {"normal", {0.0, 0.0, 1.0}},
                            {"tangential", tangential}};
  scene["boundaries"][1]["displacement"] = {0.0, 0.0, -push};
  return scene;
}

struct Outcome {
  json summary;
  ResultField field;
};

Outcome run_scene(const json& scene, const std::string& name) {
  const fs::path folder = scratch_dir("platen_" + name);
  write_text(folder / "scene.json", scene.dump(2));
  const auto result =
      run_mtled({"run", (folder / "scene.json").string(), "-o", (folder / "out").string(), "--no-progress"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return {read_json(folder / "out" / "summary.json"), read_result_vtu(folder / "out" / "result.vtu")};
}

double reaction_z(const Outcome& run, const std::string& set) {
  return run.summary["final_reactions_N"][set][2].get<double>();
}

// Pushed 2.5 mm, the cube crosses the 0.5 mm gap as a rigid body and is then compressed 2 mm against the platen: the
// stretch 0.8 of the shipped uniaxial scene, whose exact nominal stress the top face's force must give to the same
// 1e-4 (a homogeneous state the consistent integration reproduces exactly; what is left is the relaxation's stop).
TEST(PlatenContact, ACubePushedOntoAFrictionlessPlatenEndsInExactUniaxialCompression) {
  const Outcome run = run_scene(cube_over_platen(kGap, kGap + 0.002, "free"), "frictionless");
  const double exact = exact_uniaxial_stress(ogden(722.0, -1.3, 5.57738e-5), 0.8);
  const double top = reaction_z(run, "top") / (kSide * kSide);
  EXPECT_LT(std::abs(top / exact - 1.0), 1e-4) << top << " Pa against " << exact << " Pa";
  // Nothing else holds the cube along z: the platen's reaction balances the pushed face's.
  EXPECT_LT(std::abs(reaction_z(run, "platen") + reaction_z(run, "top")), 1e-6 * std::abs(reaction_z(run, "top")));
  // Every node on the platen's side stays on it (to the relaxation's 1e-7 of the displacement); the bottom face lies
  // on it, and slid outwards on it as the cube's sides expanded.
  double lowest = INFINITY, widest = 0.0;
  for (std::size_t i = 0; i < run.field.points.size(); ++i) {
    const Vec3 x = run.field.points[i] + run.field.displacement[i];
    lowest = std::min(lowest, x.z());
    if (run.field.points[i].z() == 0.0) {
      EXPECT_NEAR(x.z(), -kGap, 1e-9) << "node " << i;
      widest = std::max(widest, run.field.displacement[i].x());
    }
  }
  EXPECT_GE(lowest, -kGap - 1e-9);
  const double lateral = exact_uniaxial_lateral_stretch(ogden(722.0, -1.3, 5.57738e-5), 0.8);
  EXPECT_NEAR(widest, (lateral - 1.0) * kSide, 1e-4 * kSide);
}

// Pushed 0.4 mm, less than the gap: a rigid translation, no force anywhere and no node on the platen.
TEST(PlatenContact, NothingTouchesWhileTheGapIsOpen) {
  const Outcome run = run_scene(cube_over_platen(kGap, 0.0004, "free"), "open_gap");
  EXPECT_EQ(reaction_z(run, "platen"), 0.0);
  // The relaxation stops within 1e-7 of the displacement: a force of that order times the cube's axial stiffness
  // (E A / L, about 22 N/m), 1e-9 N.
  EXPECT_LT(std::abs(reaction_z(run, "top")), 1e-8);
  for (std::size_t i = 0; i < run.field.points.size(); ++i)
    EXPECT_NEAR(run.field.displacement[i].z(), -0.0004, 1e-9) << "node " << i;
}

// The cube's top face carried 2 mm sideways as it is pushed 1 mm into the platen (held in every direction, the
// symmetry planes dropped): on a frictionless platen the cube slides along and nothing resists the sideways motion;
// a sticking platen holds the face where it touched, the cube shears, and the platen's sideways reaction balances
// the pushed face's.
TEST(PlatenContact, AStickingPlatenHoldsTheFaceWhereItTouched) {
  double sideways[2] = {0.0, 0.0};
  int k = 0;
  for (const std::string tangential : {"free", "stick"}) {
    json scene = cube_over_platen(kGap, kGap + 0.001, tangential);
    scene["boundaries"][1]["displacement"][0] = 0.002;
    scene["boundaries"][1].erase("components");
    scene["boundaries"].erase(3);  // the symmetry planes
    scene["boundaries"].erase(2);
    const Outcome run = run_scene(scene, "sheared_" + tangential);
    const double top = run.summary["final_reactions_N"]["top"][0].get<double>();
    const double platen = run.summary["final_reactions_N"]["platen"][0].get<double>();
    sideways[k++] = top;
    if (tangential == "free")
      EXPECT_EQ(platen, 0.0);
    else
      EXPECT_LT(std::abs(top + platen), 1e-4 * std::abs(top)) << top << " N against " << platen << " N";
  }
  // Shearing the 10 mm cube by its top's sideways travel after the touch (about 1.3 mm) takes about mu A gamma =
  // 722 Pa x 1e-4 m^2 x 0.13, some 0.01 N; sliding takes only the relaxation's residual.
  EXPECT_GT(sideways[1], 1e-3);
  EXPECT_LT(std::abs(sideways[0]), 1e-3 * sideways[1]);
}

// The shipped semi-confined compression, relaxed once at 20%: its free side rolls past the bonded rims onto the
// platens' planes (the converged axisymmetric solution does too, docs/stability.md). Without contact some nodes end
// beyond a platen; with it none, and the platens' forces (bonded face plus contact) still balance.
TEST(PlatenContact, TheSideRollingOntoABondedPlatenStaysOnIt) {
  json scene = read_json(source_dir() / "share/scenes/compression_semiconfined.json");
  scene.erase("description");
  scene["integrator"]["relaxed_increments"] = 1;
  const auto beyond = [](const Outcome& run) {
    int count = 0;
    for (std::size_t i = 0; i < run.field.points.size(); ++i) {
      const double z = run.field.points[i].z() + run.field.displacement[i].z();
      count += z > 0.0136 + 1e-9 || z < -1e-9;
    }
    return count;
  };
  ASSERT_EQ(scene["boundaries"][0]["platen"], "frictionless") << "the shipped scene models both platens";
  ASSERT_EQ(scene["boundaries"][1]["platen"], "frictionless");
  json without = scene;
  for (json& boundary : without["boundaries"]) boundary["platen"] = "none";
  EXPECT_GT(beyond(run_scene(without, "semiconfined_without")), 0) << "nothing to keep out at this resolution";
  const Outcome run = run_scene(scene, "semiconfined");
  EXPECT_EQ(beyond(run), 0);
  const double top = reaction_z(run, "top") + reaction_z(run, "top_contact");
  const double bottom = reaction_z(run, "bottom") + reaction_z(run, "bottom_contact");
  EXPECT_LT(reaction_z(run, "top_contact"), 0.0) << "the top platen pushes down where the side rolled onto it";
  EXPECT_LT(std::abs(top + bottom), 1e-3 * std::abs(top));
}

}  // namespace
}  // namespace mtled::test
