// Checked configuration access: every bad value is named by file and key.
#include <auvnav/config.h>
#include <gtest/gtest.h>

using auvnav::config::ConfigError;
using auvnav::config::Node;

namespace
{
std::string errorOf(const std::function<void()>& f)
{
	try
	{
		f();
	}
	catch (const ConfigError& e)
	{
		return e.what();
	}
	return "";
}
}  // namespace

TEST(Config, ReadsTypedValuesAndNestedSections)
{
	const Node n = Node::fromText(
		"a: 1.5\nb: {c: [1, 2, 3], d: true, e: hello}\nlist: [{x: 1}, {x: 2}]\n", "t.yaml");
	EXPECT_DOUBLE_EQ(n.number("a"), 1.5);
	EXPECT_DOUBLE_EQ(n.positive("a"), 1.5);
	EXPECT_EQ(n.child("b").vector3("c"), Eigen::Vector3d(1, 2, 3));
	EXPECT_TRUE(n.child("b").boolean("d", false));
	EXPECT_EQ(n.child("b").string("e"), "hello");
	EXPECT_DOUBLE_EQ(n.number("missing", 7.0), 7.0);
	const auto list = n.sequence("list");
	ASSERT_EQ(list.size(), 2u);
	EXPECT_EQ(list[1].integer("x"), 2);
}

TEST(Config, ErrorsNameFileKeyPathAndValue)
{
	const Node n = Node::fromText("a: -2\nb: {c: [1, 2]}\nbad: .nan\ntext: abc\nlist: [{x: 1.5}]\n", "cfg.yaml");
	EXPECT_EQ(errorOf([&] { n.positive("a"); }), "cfg.yaml: a: expected a positive number, got '-2'");
	EXPECT_EQ(errorOf([&] { n.child("b").vector3("c"); }), "cfg.yaml: b.c: expected exactly 3 numbers, got 2");
	EXPECT_NE(errorOf([&] { n.number("bad"); }).find("cfg.yaml: bad: expected a finite number"), std::string::npos);
	EXPECT_NE(errorOf([&] { n.number("text"); }).find("got 'abc'"), std::string::npos);
	EXPECT_EQ(errorOf([&] { n.number("nope"); }), "cfg.yaml: nope: missing required value");
	EXPECT_EQ(errorOf([&] { n.sequence("list")[0].integer("x"); }),
			  "cfg.yaml: list[0].x: expected an integer, got '1.5'");
	EXPECT_NE(errorOf([&] { n.inRange("a", 0, 1); }).find("expected a number in [0, 1]"), std::string::npos);
}

TEST(Config, MissingOrMalformedFilesAreRefused)
{
	EXPECT_NE(errorOf([] { Node::load("/nonexistent/x.yaml"); }).find("/nonexistent/x.yaml: cannot open"),
			  std::string::npos);
	EXPECT_NE(errorOf([] { Node::fromText("a: [1, 2\n", "broken.yaml"); }).find("broken.yaml"), std::string::npos);
	EXPECT_NE(errorOf([] { Node::fromText("- 1\n- 2\n", "seq.yaml"); }).find("top level must be a YAML map"),
			  std::string::npos);
}

TEST(Config, OverridesEnterListsByLabelOrIndex)
{
	auto n = Node::fromText(
		"sensors:\n  - {label: DVL, plugin: dvl}\n  - {label: SONAR, plugin: sonar_heading, config: {mode: validate}}\n",
		"nav.yaml");
	n.set("sensors.SONAR.config.mode", "update");
	n.set("sensors.0.plugin", "dvl2");
	const auto s = n.sequence("sensors");
	EXPECT_EQ(s[1].child("config").string("mode"), "update");
	EXPECT_EQ(s[0].string("plugin"), "dvl2");
	try
	{
		n.set("sensors.GPS.config.sigma_m", "2");
		FAIL() << "override of a missing element accepted";
	}
	catch (const ConfigError& e)
	{
		EXPECT_NE(std::string(e.what()).find("no element 'GPS'"), std::string::npos) << e.what();
	}
}
