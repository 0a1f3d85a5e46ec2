// Bad input through the mtled executable: every case of tests/scenes/bad/cases.json must exit
// with its code (2: invalid input), print the expected message fragments (the file and line or the JSON
// pointer, the allowed range, a suggestion), show no crash or stack trace, and leave nothing in the output
// folder that looks like a successful run. One GoogleTest case per entry, so ctest lists them one by one.
#include <gtest/gtest.h>

#include <fstream>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

const fs::path kCaseDir = test::source_dir() / "tests/scenes/bad";

struct BadCase {
  std::string name;
  json spec;
};
// ctest shows the case's name, not its bytes.
void PrintTo(const BadCase& c, std::ostream* out) { *out << c.name; }

// Read when the test executable starts (also while ctest lists the tests); a broken index shows as one
// failing case rather than none.
std::vector<BadCase> load_cases() {
  std::vector<BadCase> cases;
  std::ifstream in(kCaseDir / "cases.json");
  json index;
  try {
    index = json::parse(in);
  } catch (const json::exception& e) {
    cases.push_back({"index_is_readable", {{"index_error", e.what()}}});
    return cases;
  }
  for (const auto& spec : index.at("cases")) cases.push_back({spec.at("name").get<std::string>(), spec});
  return cases;
}

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (auto at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, IsRefusedCleanly) {
  const json& spec = GetParam().spec;
  ASSERT_FALSE(spec.contains("index_error")) << "tests/scenes/bad/cases.json: " << spec["index_error"];
  const fs::path scratch = test::scratch_dir("bad-input");
  const fs::path out = scratch / "out";
  const fs::path regular_file = scratch / "a_regular_file";
  test::write_text(regular_file, "not a folder\n");

  std::vector<std::string> arguments;
  const json default_arguments = json::array({"run", "{scene}", "-o", "{out}"});
  for (const auto& a : spec.value("arguments", default_arguments)) {
    std::string argument = a.get<std::string>();
    argument = replace_all(argument, "{scene}", (kCaseDir / spec.value("scene", "")).string());
    argument = replace_all(argument, "{out}", out.string());
    argument = replace_all(argument, "{file}", regular_file.string());
    argument = replace_all(argument, "{bad_plugins}", MTLED_TEST_BAD_PLUGIN_DIR);
    arguments.push_back(argument);
  }
  const auto result = test::run_mtled(arguments, {"MTLED_PLUGIN_PATH="});
  const std::string& output = result.output;

  EXPECT_EQ(result.exit_code, spec.value("exit_code", 2)) << output;
  for (const auto& part : spec.at("message_contains")) {
    const std::string text = replace_all(part.get<std::string>(), "{file}", regular_file.string());
    EXPECT_NE(output.find(text), std::string::npos) << "expected \"" << text << "\" in:\n" << output;
  }
  // A refusal, not a crash: no uncaught exception, abort, sanitizer report or stack trace.
  for (const char* crash : {"terminate called", "what():", "Aborted", "Segmentation fault", "core dumped",
                            "Stack trace", "stack trace", "AddressSanitizer", "runtime error:", "#0 0x"})
    EXPECT_EQ(output.find(crash), std::string::npos) << "\"" << crash << "\" in:\n" << output;
  EXPECT_LT(output.size(), 4000u) << "a refusal is a few lines, not pages:\n" << output;

  // Nothing that looks like a successful run: no result, and a summary (if any) that says what went wrong.
  if (fs::is_directory(out)) {
    for (const char* file : {"result.vtu", "series.pvd", "needle.csv", "needle_transient.csv", "reactions.csv", "reactions_transient.csv"})
      EXPECT_FALSE(fs::exists(out / file)) << file << " written for refused input";
    if (fs::exists(out / "summary.json")) {
      const json summary = test::read_json(out / "summary.json");
      EXPECT_EQ(summary.value("status", ""), "invalid_input") << summary.dump(2);
      EXPECT_FALSE(summary.value("error", "").empty()) << summary.dump(2);
    }
    for (const auto& entry : fs::directory_iterator(out)) {
      const std::string name = entry.path().filename().string();
      EXPECT_EQ(name.find(".tmp"), std::string::npos) << "a temporary file left behind: " << name;
      EXPECT_EQ(name.find(".partial"), std::string::npos) << "a partial file left behind: " << name;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, BadInput, ::testing::ValuesIn(load_cases()),
                         [](const ::testing::TestParamInfo<BadCase>& param) { return param.param.name; });

// Every scene file in the folder is a case of the index (a forgotten entry would never be run).
TEST(BadInputIndex, ListsEveryFileInTheFolder) {
  std::set<std::string> listed;
  for (const auto& c : load_cases()) listed.insert(c.spec.value("scene", ""));
  for (const auto& entry : fs::directory_iterator(kCaseDir)) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() == ".json" && name != "cases.json") {
      EXPECT_TRUE(listed.count(name)) << name << " is not a case of tests/scenes/bad/cases.json";
    }
  }
}

}  // namespace
}  // namespace mtled
