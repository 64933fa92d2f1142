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
	const Node n =
	    Node::fromText("a: 1.5\nb: {c: [1, 2, 3], d: true, e: hello}\nlist: [{x: 1}, {x: 2}]\n", "t.yaml");
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
	const Node n =
	    Node::fromText("a: -2\nb: {c: [1, 2]}\nbad: .nan\ntext: abc\nlist: [{x: 1.5}]\n", "cfg.yaml");
	EXPECT_EQ(errorOf([&] { n.positive("a"); }), "cfg.yaml: a: expected a positive number, got '-2'");
	EXPECT_EQ(errorOf([&] { n.child("b").vector3("c"); }),
	          "cfg.yaml: b.c: expected exactly 3 numbers, got 2");
	EXPECT_NE(errorOf([&] { n.number("bad"); }).find("cfg.yaml: bad: expected a finite number"),
	          std::string::npos);
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
	EXPECT_NE(errorOf([] { Node::fromText("a: [1, 2\n", "broken.yaml"); }).find("broken.yaml"),
	          std::string::npos);
	EXPECT_NE(errorOf([] { Node::fromText("- 1\n- 2\n", "seq.yaml"); }).find("top level must be a YAML map"),
	          std::string::npos);
}

TEST(Config, AFileItCannotOpenIsNamedWithItsKeyAndFolder)
{
	// A profile copied to another folder without the files it names.
	const Node n = Node::fromText("model: {vehicle_model_file: vehicles/v.yaml}\n", "/tmp/copy/nav.yaml");
	const std::string e = errorOf([&] { n.child("model").loadFile("vehicle_model_file"); });
	EXPECT_EQ(e,
	          "/tmp/copy/nav.yaml: model.vehicle_model_file: cannot open 'vehicles/v.yaml' (looked for "
	          "/tmp/copy/vehicles/v.yaml: a relative path is taken from the folder of /tmp/copy/nav.yaml)");
	const Node absolute = Node::fromText("f: /nonexistent/v.yaml\n", "nav.yaml");
	EXPECT_EQ(errorOf([&] { absolute.loadFile("f"); }), "nav.yaml: f: cannot open '/nonexistent/v.yaml'");
	const Node found =
	    Node::fromText("f: flatfish.yaml\n", std::string(AUVNAV_SOURCE_DIR) + "/config/x.yaml");
	EXPECT_TRUE(found.loadFile("f").has("imu"));
}

// What MRPT's YAML reader takes silently (the last duplicate wins, a second
// document is dropped) or fails on with a multi-line assertion report (an
// alias, a list as a key): refused in one line with file:line:column and key.
TEST(Config, YamlMrptWouldMisreadIsRefusedInOneLine)
{
	const std::string dup = errorOf([] { Node::fromText("a: 1\nb:\n  c: 2\n  d: 3\n  c: 4\n", "dup.yaml"); });
	EXPECT_EQ(dup, "dup.yaml:5:3: b.c: duplicate key (first at line 3)");
	EXPECT_EQ(errorOf([] { Node::fromText("l: [{x: 1}, {x: 2, x: 3}]\n", "f.yaml"); }),
	          "f.yaml:1:20: l[1].x: duplicate key (first at line 1)");
	EXPECT_EQ(errorOf([] { Node::fromText("a: 1\n---\nb: 2\n", "docs.yaml"); }),
	          "docs.yaml:2:1: a second YAML document ('---' or '...'): one document per file");
	EXPECT_EQ(errorOf([] { Node::fromText("a: &x 1\nb: *x\n", "alias.yaml"); }),
	          "alias.yaml:2:4: b: aliases (*x) are not supported");
	EXPECT_EQ(errorOf([] { Node::fromText("? [a, b]\n: 1\n", "key.yaml"); }),
	          "key.yaml:1:3: a key must be a plain name, not a list or a map");
	// The same key in sibling maps is no duplicate.
	EXPECT_EQ(errorOf([] { Node::fromText("a: {x: 1}\nb: {x: 2}\nl: [{x: 1}, {x: 2}]\n", "ok.yaml"); }), "");
	for (const std::string& e : {dup, errorOf([] { Node::fromText("a: \"\\q\"\n", "esc.yaml"); })})
		EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST(Config, OverridesEnterListsByLabelOrIndex)
{
	auto n = Node::fromText(
	    "sensors:\n  - {label: DVL, plugin: dvl}\n  - {label: SONAR, plugin: sonar_heading, config: {mode: "
	    "validate}}\n",
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

// ------------------------------------------------------------ unknown keys

TEST(ConfigUnknownKeys, AllReadKeysPass)
{
	const Node n = Node::fromText("a: 1\nb: {c: 2, d: [1, 2, 3]}\n", "t.yaml");
	n.number("a");
	const auto b = n.child("b");  // a copy: its reads still count for the root
	b.number("c");
	b.numbers("d");
	EXPECT_NO_THROW(n.checkAllKeysUsed());
}

TEST(ConfigUnknownKeys, NestedMisspellingNamesFilePathAndNearestKey)
{
	const Node n = Node::fromText("filter:\n  initial:\n    heading_dg: 25\n    heading_sigma_deg: 30\n",
	                              "config/x.yaml");
	const auto in = n.child("filter").child("initial");
	EXPECT_DOUBLE_EQ(in.number("heading_deg", 0.0), 0.0);  // the misspelling falls back to the default...
	in.positive("heading_sigma_deg");
	// ...which is why the check must refuse it.
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }),
	          "config/x.yaml: filter.initial.heading_dg: unknown key (did you mean 'heading_deg'?)");
}

TEST(ConfigUnknownKeys, TranspositionsAndMissingSuffixesAreSuggested)
{
	const Node n = Node::fromText("use_dpeth: true\n", "p.yaml");
	n.boolean("use_depth", false);
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }),
	          "p.yaml: use_dpeth: unknown key (did you mean 'use_depth'?)");
	const Node m = Node::fromText("max_gap: 0.5\n", "i.yaml");
	m.number("max_gap_s", 1.0);
	EXPECT_EQ(errorOf([&] { m.checkAllKeysUsed(); }),
	          "i.yaml: max_gap: unknown key (did you mean 'max_gap_s'?)");
}

TEST(ConfigUnknownKeys, FarKeyListsTheValidOnes)
{
	const Node n = Node::fromText("a: 1\ncompletely_else: 2\n", "t.yaml");
	n.number("a");
	n.number("bee", 0.0);
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }),
	          "t.yaml: completely_else: unknown key (valid here: a, bee)");
}

TEST(ConfigUnknownKeys, MisspelledSectionIsRefusedAtTheTop)
{
	const Node n = Node::fromText("gatse: {recovery_after_s: 5}\nhealth: {}\n", "t.yaml");
	EXPECT_FALSE(n.has("gates"));  // has() of an absent key makes it a candidate, not known
	n.has("health");
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }), "t.yaml: gatse: unknown key (did you mean 'gates'?)");
}

TEST(ConfigUnknownKeys, ListElementsAreCheckedWithTheirIndex)
{
	const Node n = Node::fromText(
	    "sensors:\n  - {label: A, plugin: dvl}\n  - {label: B, plugn: gps, plugin: gps}\n", "nav.yaml");
	for (const auto& s : n.sequence("sensors"))
	{
		s.string("label");
		s.string("plugin");
	}
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }),
	          "nav.yaml: sensors[1].plugn: unknown key (did you mean 'plugin'?)");
}

TEST(ConfigUnknownKeys, KeyOfAnotherLevelIsNotSuggested)
{
	// 'rate_hz' is read, but under imu: the top level's 'rate_h' must not be told to use it.
	const Node n = Node::fromText("imu: {rate_hz: 100}\nrate_h: 5\nname: x\n", "t.yaml");
	n.child("imu").number("rate_hz");
	n.string("name");
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }), "t.yaml: rate_h: unknown key (valid here: imu, name)");
}

TEST(ConfigUnknownKeys, UnreadSubtreeOfAReadSectionIsRefused)
{
	const Node n = Node::fromText("a: {b: {c: 1, d: 2}}\n", "t.yaml");
	n.child("a").child("b").number("c");
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }), "t.yaml: a.b.d: unknown key (valid here: c)");
}

TEST(ConfigUnknownKeys, FreeFormSubtreesAndExceptionsAreSkipped)
{
	const Node n = Node::fromText("metadata: {anything: 1, goes: [x]}\nrun_only: {x: 1}\nv: 1\n", "t.yaml");
	n.number("v");
	EXPECT_NE(errorOf([&] { n.checkAllKeysUsed(); }), "");
	EXPECT_NO_THROW(n.checkAllKeysUsed({"metadata", "run_only"}));
	n.markFreeForm("metadata");
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }),
	          "t.yaml: run_only: unknown key (valid here: metadata, v)");
}

TEST(ConfigUnknownKeys, ChecksOnlyTheSubtreeOfAChild)
{
	const Node n = Node::fromText("mine: {a: 1}\nsomeone_elses: 2\n", "t.yaml");
	const auto mine = n.child("mine");
	mine.number("a");
	EXPECT_NO_THROW(mine.checkAllKeysUsed());
	EXPECT_NE(errorOf([&] { n.checkAllKeysUsed(); }), "");
}

TEST(ConfigUnknownKeys, AllowOnlyCountsAsReadAndSuggests)
{
	const Node n = Node::fromText("mode: x\nconfig_dir: /tmp\n", "t.yaml");
	n.allowOnly({"mode", "config_dir"});
	n.string("mode");
	EXPECT_NO_THROW(n.checkAllKeysUsed());
	const Node m = Node::fromText("mdoe: x\n", "t.yaml");
	EXPECT_EQ(errorOf(
	              [&] {
		              m.allowOnly({"mode", "gain"});
	              }),
	          "t.yaml: mdoe: unknown key (did you mean 'mode'? expected one of: mode, gain)");
}

TEST(ConfigUnknownKeys, MisspelledOverrideIsRefusedAsAnOverride)
{
	Node n = Node::fromText("filter: {initial: {heading_deg: 30}}\nsensors:\n  - {label: DVL, plugin: dvl}\n",
	                        "nav.yaml");
	n.set("filter.initial.heading_dg", "25");
	n.child("filter").child("initial").number("heading_deg");
	for (const auto& s : n.sequence("sensors"))
	{
		s.string("label");
		s.string("plugin");
	}
	EXPECT_EQ(errorOf([&] { n.checkAllKeysUsed(); }),
	          "nav.yaml: filter.initial.heading_dg: unknown key (did you mean 'heading_deg'?) [given as an "
	          "override]");
	Node m = Node::fromText("sensors:\n  - {label: DVL, plugin: dvl}\n", "nav.yaml");
	m.set("sensors.DVL.plugn", "gps");  // entered by label, reported by index
	for (const auto& s : m.sequence("sensors"))
	{
		s.string("label");
		s.string("plugin");
	}
	EXPECT_EQ(errorOf([&] { m.checkAllKeysUsed(); }),
	          "nav.yaml: sensors[0].plugn: unknown key (did you mean 'plugin'?) [given as an override]");
}
