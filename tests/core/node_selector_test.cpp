#include <gtest/gtest.h>

#include "mtled/node_selector.hpp"

namespace mtled {
namespace {

std::vector<Problem> problems_of(const json& value) {
  std::vector<Problem> problems;
  NodeSelector::parse(value, "/boundaries/0/nodes", problems);
  return problems;
}

TEST(NodeSelector, ParsesEveryShape) {
  std::vector<Problem> problems;
  auto plane = NodeSelector::parse({{"plane", {{"point", {0, 0, 1}}, {"normal", {0, 0, 2}}}}}, "/p", problems);
  ASSERT_TRUE(plane);
  EXPECT_EQ(plane->kind, NodeSelector::Kind::plane);
  EXPECT_DOUBLE_EQ(plane->direction.norm(), 1.0);
  EXPECT_TRUE(plane->contains(Vec3(5, -3, 1.0 + 1e-9), 1e-8));
  EXPECT_FALSE(plane->contains(Vec3(0, 0, 1.1), 1e-8));

  auto box = NodeSelector::parse({{"box", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}}, {"surface_only", true}}, "/b", problems);
  ASSERT_TRUE(box);
  EXPECT_TRUE(box->surface_only);
  EXPECT_TRUE(box->contains(Vec3(1, 0.5, 0), 0.0));
  EXPECT_FALSE(box->contains(Vec3(1.1, 0.5, 0), 0.0));

  auto cylinder = NodeSelector::parse(
      {{"cylinder", {{"point", {0, 0, 0}}, {"direction", {0, 0, 1}}, {"radius", 0.5}}}}, "/c", problems);
  ASSERT_TRUE(cylinder);
  EXPECT_TRUE(cylinder->contains(Vec3(0.3, 0.3, 100), 0.0));
  EXPECT_FALSE(cylinder->contains(Vec3(0.4, 0.4, 0), 0.0));

  auto sphere = NodeSelector::parse({{"sphere", {{"center", {1, 1, 1}}, {"radius", 1}}}}, "/s", problems);
  ASSERT_TRUE(sphere);
  EXPECT_TRUE(sphere->contains(Vec3(1, 1, 2), 0.0));

  auto group = NodeSelector::parse({{"group", "bottom"}, {"tolerance", 1e-6}}, "/g", problems);
  ASSERT_TRUE(group);
  EXPECT_EQ(group->group, "bottom");
  EXPECT_TRUE(problems.empty());
}

TEST(NodeSelector, ReportsBadSelectorsWithPointers) {
  auto p = problems_of({{"plane", {{"point", {0, 0, 0}}, {"normal", {0, 0, 0}}}}});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].where, "/boundaries/0/nodes/plane/normal");
  EXPECT_NE(p[0].message.find("zero vector"), std::string::npos);

  p = problems_of({{"group", "a"}, {"sphere", {{"center", {0, 0, 0}}, {"radius", 1}}}});
  ASSERT_FALSE(p.empty());
  EXPECT_NE(p.back().message.find("exactly one"), std::string::npos);

  p = problems_of({{"box", {{"min", {0, 0, 0}}, {"max", {1, -1, 1}}}}});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].message.find("must not exceed"), std::string::npos);

  p = problems_of({{"sphere", {{"centre", {0, 0, 0}}, {"radius", -1}}}});
  ASSERT_GE(p.size(), 2u);
  std::string all;
  for (const auto& q : p) all += q.format() + "\n";
  EXPECT_NE(all.find("did you mean \"center\"?"), std::string::npos) << all;
  EXPECT_NE(all.find("/boundaries/0/nodes/sphere/radius"), std::string::npos) << all;

  p = problems_of("bottom");
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].message.find("{\"group\": \"bottom\"}"), std::string::npos);
}

}  // namespace
}  // namespace mtled
