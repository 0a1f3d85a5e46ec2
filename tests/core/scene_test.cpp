// Reading and validating scenes: syntax errors with file:line:column, problems located by line, --set.
#include <gtest/gtest.h>

#include "mtled/io/run_outputs.hpp"
#include "mtled/monitors/scene_monitors.hpp"
#include "mtled/scene.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

const char* kScene = R"({
  "mesh": {"type": "no_such_mesh"},
  "shape_function": {"type": "no_such_sf"},
  "materails": [],
  "materials": [
    {"type": "good_test_material", "modulus": -3, "regon": "a"}
  ],
  "boundaries": [{"type": "fixd", "nodes": {"group": "bottom"}}],
  "integrator": {"type": "dynamic_relaxation", "tolerance": 2}
})";

std::string problems_text(const InputError& e) {
  std::string text;
  for (const auto& p : e.problems()) text += p.format() + "\n";
  return text;
}

TEST(Scene, SyntaxErrorsNameFileLineAndColumn) {
  try {
    parse_scene("{\n  \"mesh\": {\"type\": \"box\"},\n  \"materials\": [\n", "cut.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where.rfind("cut.json:4:", 0), 0u) << e.problems()[0].where;
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  try {
    parse_scene("{\"a\": 1,}", "comma.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "comma.json:1:9");
  }
  EXPECT_THROW(parse_scene("[1, 2]", "array.json"), InputError);
  EXPECT_THROW(read_scene("/nonexistent/scene.json"), InputError);
}

TEST(Scene, EveryProblemIsLocatedByLine) {
  PluginCatalog catalog({test::plugin_dir(), MTLED_TEST_BAD_PLUGIN_DIR "/good"});
  try {
    validate_scene(parse_scene(kScene, "scene.json"), catalog);
    FAIL();
  } catch (const InputError& e) {
    const std::string text = problems_text(e);
    EXPECT_NE(text.find("scene.json:4: /materails: unknown top-level key \"materails\"; did you mean \"materials\"?"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("scene.json:2: /mesh/type: unknown mesh \"no_such_mesh\""), std::string::npos) << text;
    EXPECT_NE(text.find("scene.json:6: /materials/0/modulus: -3 is out of range: allowed > 0 Pa"), std::string::npos)
        << text;
    EXPECT_NE(text.find("scene.json:6: /materials/0/regon: unknown key \"regon\""), std::string::npos) << text;
    EXPECT_NE(text.find("did you mean \"region\"?"), std::string::npos) << text;
    EXPECT_NE(text.find("scene.json:8: /boundaries/0/type: unknown boundary \"fixd\"; did you mean \"fixed\"?"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("scene.json:9: /integrator/tolerance: 2 is out of range: allowed (0, 1)"), std::string::npos)
        << text;
  }
  // Validation loaded only what it could name; nothing for the unknown types.
  for (const auto& file : catalog.loaded_files()) EXPECT_EQ(file.find("fixd"), std::string::npos);
}

TEST(Scene, OverridesApplyBeforeValidationAndAreLocatedAsSuch) {
  SceneDocument d = parse_scene(kScene, "scene.json", {"/integrator/tolerance=1e-5", "/shape_function/type=mls"});
  EXPECT_DOUBLE_EQ(d.root["integrator"]["tolerance"].get<double>(), 1e-5);
  EXPECT_EQ(d.root["shape_function"]["type"], "mls");
  EXPECT_EQ(d.locate("/shape_function/type"), "--set /shape_function/type");
  EXPECT_EQ(d.locate("/materials/0/modulus"), "scene.json:6: /materials/0/modulus");
  EXPECT_EQ(d.locate("/materials/0/missing"), "scene.json:6: /materials/0/missing");  // closest ancestor
  EXPECT_THROW(parse_scene(kScene, "scene.json", {"integrator/tolerance=1"}), InputError);
  EXPECT_THROW(parse_scene(kScene, "scene.json", {"/materials/7/mu=1"}), InputError);  // past the array's end
  EXPECT_EQ(parse_scene(kScene, "scene.json", {"/output/every_steps=5"}).root["output"]["every_steps"], 5);
}

// An index too large for std::size_t escaped as std::out_of_range ("error: stoul", exit 1) instead of an
// InputError.
TEST(Scene, HugeOverrideIndexIsAnInputError) {
  try {
    parse_scene(kScene, "scene.json", {"/materials/99999999999999999999/mu=1"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "--set /materials/99999999999999999999/mu");
    EXPECT_NE(problems_text(e).find("is not an index of a list of 1 entries"), std::string::npos) << e.what();
  }
}

// Found by tests/fuzz: a number beyond a double's range made json::parse throw out_of_range, which escaped as
// "error: [json.exception.out_of_range.406] ..." (exit 1) instead of a located InputError.
TEST(Scene, NumberBeyondADoubleIsALocatedInputError) {
  try {
    parse_scene("{\n  \"integrator\": {\"tolerance\": 1e400}\n}", "big.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "big.json:2:31");
    EXPECT_NE(problems_text(e).find("the number 1e400 is too large"), std::string::npos) << e.what();
  }
  try {
    parse_scene(kScene, "scene.json", {"/integrator/tolerance=-1e999"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "--set /integrator/tolerance");
  }
}

// Lists nested 100,000 deep parse as JSON, but recording their lines recursed once per level and overflowed
// the stack (a segmentation fault); nesting is now refused with the place where it gets too deep.
TEST(Scene, DeepNestingIsAnInputError) {
  const int levels = 100000;
  const std::string deep = std::string(levels, '[') + std::string(levels, ']');
  try {
    parse_scene("{\n  \"description\": " + deep + "}", "deep.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "deep.json:2:117");
    EXPECT_NE(problems_text(e).find("nested more than 100 deep"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_scene(kScene, "scene.json", {"/description=" + deep}), InputError);
  // Strings may hold any brackets.
  EXPECT_NO_THROW(parse_scene("{\"description\": \"" + std::string(1000, '[') + "\\\"{\"}", "s.json"));
}

// Found by tests/fuzz: an override's bare words are not checked by the JSON parser, and a string that was not
// UTF-8 made the validation messages' dump() throw (std::terminate in the fuzz target).
TEST(Scene, OverrideThatIsNotUtf8IsAnInputError) {
  try {
    parse_scene(kScene, "scene.json", {"/description=caf\xdf!"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "--set /description");
    EXPECT_NE(problems_text(e).find("not valid UTF-8"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(parse_scene(kScene, "scene.json", {"/description=caf\xc3\xa9"}));  // UTF-8 is fine
}

// Found by tests/fuzz: below a missing key a numeric token made nlohmann create a list as long as the index
// (std::length_error for 10^19, all the memory for 10^9). Missing objects are still created.
TEST(Scene, OverrideDoesNotCreateListsBelowAMissingKey) {
  try {
    parse_scene("{}", "empty.json", {"/materials/1000000000/mu=5"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.problems()[0].where, "--set /materials/1000000000/mu");
    EXPECT_NE(problems_text(e).find("\"materials\" does not exist, so \"1000000000\" below it cannot be a list index"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(parse_scene("{}", "empty.json", {"/volumetric/type=nodal_average"}).root["volumetric"]["type"],
            "nodal_average");
}

TEST(Scene, CategoryMismatchIsAnUnknownType) {
  PluginCatalog catalog({test::plugin_dir()});
  try {
    validate_scene(parse_scene(R"({"integrator": {"type": "fixed"}})", "s.json"), catalog);
    FAIL();
  } catch (const InputError& e) {
    const std::string text = problems_text(e);
    EXPECT_NE(text.find("/integrator/type: unknown integrator \"fixed\""), std::string::npos) << text;
    EXPECT_NE(text.find("/mesh: missing \"mesh\""), std::string::npos) << text;
    EXPECT_NE(text.find("/materials: missing \"materials\""), std::string::npos) << text;
  }
}

TEST(Scene, VolumetricTreatmentIsAnOptionalComponentLoadedOnlyWhenNamed) {
  const std::string base = R"({"mesh": {"type": "box", "size": [0.01, 0.01, 0.01], "target_nodes": 300},
    "shape_function": {"type": "mls"}, "materials": [{"type": "neo_hookean", "mu": 1000, "D": 1e-4, "density": 1000}],
    "integrator": {"type": "dynamic_relaxation"})";
  {
    PluginCatalog catalog({test::plugin_dir()});
    const Scene scene = validate_scene(parse_scene(base + R"(, "volumetric": {"type": "nodal_average"}})", "s.json"),
                                       catalog);
    ASSERT_TRUE(scene.volumetric.has_value());
    EXPECT_EQ(scene.volumetric->type, "nodal_average");
  }
  for (const char* off : {"}", R"(, "volumetric": null})"}) {
    PluginCatalog catalog({test::plugin_dir()});
    const Scene scene = validate_scene(parse_scene(base + off, "s.json"), catalog);
    EXPECT_FALSE(scene.volumetric.has_value());
    for (const auto& file : catalog.loaded_files()) EXPECT_EQ(file.find("volumetric"), std::string::npos) << file;
  }
  // Where earlier scenes chose it: one problem that says where it goes now.
  PluginCatalog catalog({test::plugin_dir()});
  try {
    validate_scene(parse_scene(base + R"(, "discretisation": {"volumetric": "nodal_average"}})", "s.json"), catalog);
    FAIL();
  } catch (const InputError& e) {
    ASSERT_EQ(e.problems().size(), 1u) << problems_text(e);
    EXPECT_NE(problems_text(e).find("/discretisation/volumetric: the volumetric treatment is a component now: write "
                                    "\"volumetric\": {\"type\": \"nodal_average\"}"),
              std::string::npos)
        << problems_text(e);
  }
}

TEST(Scene, SchemaListsComponentsPerRole) {
  PluginCatalog catalog({test::plugin_dir()});
  const json schema = scene_json_schema(catalog);
  bool found = false;
  for (const auto& option : schema["properties"]["integrator"]["oneOf"])
    found = found || option["properties"]["type"]["const"] == "dynamic_relaxation";
  EXPECT_TRUE(found);
  EXPECT_EQ(schema["properties"]["discretisation"]["properties"]["integration_points_per_tet"]["enum"],
            json::array({1, 4}));
}

// The kernel knows its own sections only: "output" and "monitors" are declared by the writers and the checks and
// passed in. Without them their keys are unknown; with them the scene's values are checked against their
// declarations and the defaults filled in, and the schema lists them.
TEST(Scene, SectionsAreDeclaredByTheLibrariesThatReadThem) {
  const std::string base = R"({"mesh": {"type": "box", "size": [0.01, 0.01, 0.01]}, "shape_function": {"type": "mls"},
    "materials": [{"type": "neo_hookean", "mu": 1000, "D": 1e-4, "density": 1000}],
    "integrator": {"type": "dynamic_relaxation"}, "monitors": {"inversion": "warn"})";
  PluginCatalog catalog({test::plugin_dir()});
  try {
    validate_scene(parse_scene(base + "}", "s.json"), catalog);
    FAIL() << "a section nobody declared was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(problems_text(e).find("unknown top-level key \"monitors\""), std::string::npos) << problems_text(e);
  }
  const std::vector<SceneSection> sections = {output_section(), monitors_section()};
  const Scene scene = validate_scene(parse_scene(base + "}", "s.json"), catalog, sections);
  EXPECT_EQ(scene.section("monitors").string("inversion"), "warn");
  EXPECT_EQ(scene.section("output").integer("history_every_steps"), 20);  // its declared default
  EXPECT_THROW((void)scene.section("no_such_section"), std::logic_error);
  try {
    validate_scene(parse_scene(base + R"(, "output": {"cell_data": ["strain"]}})", "s.json"), catalog, sections);
    FAIL() << "an unknown cell field was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(problems_text(e).find("/output/cell_data"), std::string::npos) << problems_text(e);
    EXPECT_NE(problems_text(e).find("green_strain"), std::string::npos) << problems_text(e);
  }
  const json schema = scene_json_schema(catalog, sections);
  EXPECT_TRUE(schema["properties"]["monitors"]["properties"].contains("inversion_every_steps")) << schema.dump();
  EXPECT_FALSE(schema["properties"]["output"]["properties"].contains("type"));
}

}  // namespace
}  // namespace mtled
