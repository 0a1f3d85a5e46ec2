// Parameter declarations and validation: every problem found in one pass, each with its pointer, the
// allowed range and a suggestion.
#include <gtest/gtest.h>

#include "mtled/interfaces/material.hpp"
#include "mtled/parameters.hpp"
#include "mtled/registry.hpp"

namespace mtled {
namespace {

ComponentDeclaration sample() {
  ComponentDeclaration d("sample", Category::material);
  d.summary("a sample");
  d.number("mu").unit("Pa").positive().doc("shear modulus");
  d.number("alpha").unit("1").nonzero().defaults(2.0).doc("exponent");
  d.number("coefficient").unit("1").between(0.0, 1.0).defaults(0.4).doc("a fraction");
  d.integer("points").unit("1").defaults(1).choices({1, 4}).doc("points per tet");
  d.string("basis").defaults("linear").choices({"linear", "quadratic"}).doc("basis");
  d.vector3("direction").unit("1").nonzero().defaults(json::array({0, 0, -1})).doc("direction");
  d.number("capture").unit("m").positive().optional().doc("optional length");
  return d;
}

std::string messages(const std::vector<Problem>& problems) {
  std::string text;
  for (const auto& p : problems) text += p.format() + "\n";
  return text;
}

TEST(Parameters, DefaultsFillInAndOptionalStaysAbsent) {
  std::vector<Problem> problems;
  const Parameters p = validate_parameters(sample(), {{"type", "sample"}, {"mu", 722}}, "/materials/0", problems);
  ASSERT_TRUE(problems.empty()) << messages(problems);
  EXPECT_DOUBLE_EQ(p.number("mu"), 722.0);
  EXPECT_DOUBLE_EQ(p.number("alpha"), 2.0);
  EXPECT_EQ(p.integer("points"), 1);
  EXPECT_EQ(p.string("basis"), "linear");
  EXPECT_EQ(p.vector3("direction"), Vec3(0, 0, -1));
  EXPECT_FALSE(p.get<std::optional<double>>("capture").has_value());
  EXPECT_EQ(p.pointer("mu"), "/materials/0/mu");
}

// A component binds each parameter to the member it fills, so its name is written once (ParameterBuilder::to):
// read<Settings>() fills every member bound to Settings, given or defaulted, an absent optional as nullopt, and
// leaves a member bound to nothing, or bound in another struct, at its initialiser.
struct BoundSettings {
  double mu = -1.0;
  int points = -1;
  std::string basis;
  Vec3 direction = Vec3::Zero();
  std::optional<double> capture = 99.0;
  double unbound = 7.0;
};
struct OtherSettings {
  long count = 3;
};

TEST(Parameters, BoundMembersAreFilledByRead) {
  ComponentDeclaration d("bound", Category::material);
  d.number("mu").unit("Pa").positive().doc("shear modulus").to<&BoundSettings::mu>();
  d.integer("points").unit("1").defaults(4).doc("points per tet").to<&BoundSettings::points>();
  d.string("basis").defaults("linear").doc("basis").to<&BoundSettings::basis>();
  d.vector3("direction").unit("1").defaults(json::array({0, 0, -1})).doc("direction").to<&BoundSettings::direction>();
  d.number("capture").unit("m").positive().optional().doc("optional length").to<&BoundSettings::capture>();
  d.integer("count").unit("1").defaults(8).doc("in another struct").to<&OtherSettings::count>();
  std::vector<Problem> problems;
  const Parameters absent = validate_parameters(d, {{"type", "bound"}, {"mu", 722}}, "/materials/0", problems);
  const Parameters given = validate_parameters(d, {{"type", "bound"}, {"mu", 5}, {"capture", 0.002}, {"count", 2}},
                                               "/materials/1", problems);
  ASSERT_TRUE(problems.empty()) << messages(problems);
  const auto settings = absent.read<BoundSettings>();
  EXPECT_EQ(settings.mu, 722.0);
  EXPECT_EQ(settings.points, 4);
  EXPECT_EQ(settings.basis, "linear");
  EXPECT_EQ(settings.direction, Vec3(0, 0, -1));
  EXPECT_FALSE(settings.capture.has_value());
  EXPECT_EQ(settings.unbound, 7.0);
  EXPECT_EQ(absent.read<OtherSettings>().count, 8);
  EXPECT_EQ(given.read<BoundSettings>().capture, std::optional<double>(0.002));
  EXPECT_EQ(given.read<BoundSettings>().mu, 5.0);
  EXPECT_EQ(given.read<OtherSettings>().count, 2);
}

// A parameter declared but bound to no member would be read nowhere, or by a second spelling of its name: a plugin
// that declares one is refused when it registers, naming the parameter.
TEST(Parameters, RegistrationRefusesAParameterBoundToNoMember) {
  ComponentDeclaration d("unbound", Category::material);
  d.summary("a material with one parameter bound and one not");
  d.number("mu").unit("Pa").positive().doc("shear modulus").to<&BoundSettings::mu>();
  d.number("lambda").unit("Pa").positive().doc("Lame's first parameter");
  Registry registry;
  try {
    registry.add<Material>(d, Factory<Material>{});
    FAIL() << "registered a parameter bound to no member";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("\"lambda\" is bound to no member"), std::string::npos) << e.what();
  }
}

TEST(Parameters, EveryProblemIsReportedInOnePass) {
  std::vector<Problem> problems;
  const json block = {{"type", "sample"},      {"mu", -5},          {"alpha", 0},          {"coefficient", 1.5},
                      {"points", 3},           {"basis", "quadratc"}, {"direction", {0, 0, 0}}, {"muu", 1},
                      {"capture", "far"}};
  validate_parameters(sample(), block, "/materials/0", problems);
  const std::string text = messages(problems);
  EXPECT_EQ(problems.size(), 8u) << text;
  EXPECT_NE(text.find("/materials/0/mu: -5 is out of range: allowed > 0 Pa"), std::string::npos) << text;
  EXPECT_NE(text.find("/materials/0/alpha: 0 is out of range: allowed != 0"), std::string::npos) << text;
  EXPECT_NE(text.find("/materials/0/coefficient: 1.5 is out of range: allowed [0, 1]"), std::string::npos) << text;
  EXPECT_NE(text.find("/materials/0/points: 3 is not one of 1, 4"), std::string::npos) << text;
  EXPECT_NE(text.find("did you mean \"quadratic\"?"), std::string::npos) << text;
  EXPECT_NE(text.find("/materials/0/direction: must not be the zero vector"), std::string::npos) << text;
  EXPECT_NE(text.find("/materials/0/muu: unknown key \"muu\" for material \"sample\"; did you mean \"mu\"?"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("/materials/0/capture: expected a number m, got string \"far\""), std::string::npos) << text;
}

TEST(Parameters, MissingRequiredNamesTheKeyAndRange) {
  std::vector<Problem> problems;
  validate_parameters(sample(), {{"type", "sample"}}, "/materials/2", problems);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].where, "/materials/2/mu");
  EXPECT_NE(problems[0].message.find("required"), std::string::npos);
  EXPECT_NE(problems[0].message.find("> 0 Pa"), std::string::npos);
}

TEST(Parameters, IntegersAcceptWholeFloatsOnly) {
  std::vector<Problem> problems;
  validate_parameters(sample(), {{"mu", 1}, {"points", 4.0}}, "", problems);
  EXPECT_TRUE(problems.empty()) << messages(problems);
  validate_parameters(sample(), {{"mu", 1}, {"points", 4.5}}, "", problems);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].message.find("expected an integer"), std::string::npos);
}

TEST(Parameters, NonFiniteNumbersAreRefused) {
  std::vector<Problem> problems;
  validate_parameters(sample(), {{"mu", std::numeric_limits<double>::infinity()}}, "", problems);
  EXPECT_EQ(problems.size(), 1u);
}

TEST(Parameters, NotAnObject) {
  std::vector<Problem> problems;
  validate_parameters(sample(), json::array({1, 2}), "/needle", problems);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].where, "/needle");
}

// A map of named numbers: each entry checked against the range under its own pointer, the names left to the
// component; not an object is a type error.
TEST(Parameters, NumberMapEntriesAreCheckedOneByOne) {
  ComponentDeclaration d("sample", Category::mesh);
  d.number_map("sizes").unit("m").positive().optional().doc("sizes by region");
  std::vector<Problem> problems;
  const Parameters p = validate_parameters(d, {{"type", "sample"}, {"sizes", {{"stem", 0.001}, {"cerebellum", 0.002}}}},
                                           "/mesh", problems);
  ASSERT_TRUE(problems.empty()) << messages(problems);
  EXPECT_EQ(p.number_map("sizes"), (std::map<std::string, double>{{"cerebellum", 0.002}, {"stem", 0.001}}));
  validate_parameters(d, {{"type", "sample"}, {"sizes", {{"stem", -1}, {"a/b", "small"}}}}, "/mesh", problems);
  validate_parameters(d, {{"type", "sample"}, {"sizes", {0.001}}}, "/mesh", problems);
  const std::string text = messages(problems);
  EXPECT_EQ(problems.size(), 3u) << text;
  EXPECT_NE(text.find("/mesh/sizes/stem: -1 is out of range: allowed > 0 m"), std::string::npos) << text;
  EXPECT_NE(text.find("/mesh/sizes/a~1b: expected a number m, got string \"small\""), std::string::npos) << text;
  EXPECT_NE(text.find("/mesh/sizes: expected an object of named numbers"), std::string::npos) << text;
  EXPECT_EQ(d.find("sizes")->to_json_schema()["additionalProperties"]["exclusiveMinimum"], 0.0);
}

TEST(Parameters, RangeDescriptions) {
  NumericRange r;
  EXPECT_EQ(r.describe(), "any");
  r.min = 0;
  r.min_exclusive = true;
  EXPECT_EQ(r.describe(), "> 0");
  r.max = 1;
  EXPECT_EQ(r.describe(), "(0, 1]");
  EXPECT_FALSE(r.contains(0.0));
  EXPECT_TRUE(r.contains(1.0));
  EXPECT_FALSE(r.contains(std::nan("")));
}

TEST(Parameters, JsonSchemaCarriesBoundsUnitsAndDefaults) {
  const json schema = sample().to_json_schema();
  EXPECT_EQ(schema["properties"]["type"]["const"], "sample");
  EXPECT_EQ(schema["properties"]["mu"]["exclusiveMinimum"], 0.0);
  EXPECT_NE(schema["properties"]["mu"]["description"].get<std::string>().find("[Pa]"), std::string::npos);
  EXPECT_EQ(schema["properties"]["basis"]["enum"], json::array({"linear", "quadratic"}));
  EXPECT_EQ(schema["required"], json::array({"type", "mu"}));
  EXPECT_FALSE(schema["additionalProperties"].get<bool>());
}

TEST(Parameters, WrongGetterIsAProgrammingError) {
  std::vector<Problem> problems;
  const Parameters p = validate_parameters(sample(), {{"mu", 1}}, "", problems);
  EXPECT_THROW(p.string("mu"), std::logic_error);
  EXPECT_THROW(p.number("nonexistent"), std::logic_error);
  EXPECT_THROW(p.number("capture"), std::logic_error);  // optional and absent: must be checked first
}

TEST(Suggestions, ClosestNames) {
  EXPECT_EQ(did_you_mean("ogdn", {"ogden", "neo_hookean"}), "did you mean \"ogden\"?");
  EXPECT_EQ(did_you_mean("completely_different", {"ogden", "neo_hookean"}), "");
}

}  // namespace
}  // namespace mtled
