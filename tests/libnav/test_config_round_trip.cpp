// One YAML library end to end (config.h): the libyaml parser whose checks
// accept a document is the one that builds the tree, and toYaml() writes with
// libyaml's emitter. Regressions: a block key with a trailing comment made
// toYaml() write invalid YAML (a plugin refused a valid config as "malformed
// YAML" at a line of generated text); an under-indented multi-line flow map
// that the check accepted was silently cut by MRPT's reader (a `denial:`
// section vanished); quoted strings with '#' or ": " lost their quotes.
//
// The oracle is libyaml's own reading of the text (canonical() below), not
// the tree under test: what the user wrote is what a plugin gets.
#include <auvnav/config.h>
#include <auvnav/navigator.h>
#include <gtest/gtest.h>
#include <yaml.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

using auvnav::config::ConfigError;
using auvnav::config::Node;

namespace
{
/** libyaml's reading of one node whose first event is `first`, as canonical
 *  text: maps sorted by key, scalars quoted ('...'), YAML 1.2 core nulls (an
 *  untagged plain empty, ~, null, Null, NULL) as `null`. */
std::string canonicalNode(yaml_parser_t& parser, yaml_event_t& first);

std::string nextCanonical(yaml_parser_t& parser, bool& ended)
{
	yaml_event_t e;
	if (!yaml_parser_parse(&parser, &e)) throw std::runtime_error(std::string("libyaml: ") + parser.problem);
	ended = e.type == YAML_SEQUENCE_END_EVENT || e.type == YAML_MAPPING_END_EVENT;
	std::string out = ended ? "" : canonicalNode(parser, e);
	yaml_event_delete(&e);
	return out;
}

std::string canonicalNode(yaml_parser_t& parser, yaml_event_t& first)
{
	if (first.type == YAML_SCALAR_EVENT)
	{
		const auto& s = first.data.scalar;
		const std::string text(reinterpret_cast<const char*>(s.value), s.length);
		const bool plain = s.plain_implicit && s.style == YAML_PLAIN_SCALAR_STYLE;
		if (plain && (text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL"))
			return "null";
		std::string q = "'";
		for (char c : text) q += c == '\'' ? std::string("''") : std::string(1, c);
		return q + "'";
	}
	bool ended = false;
	if (first.type == YAML_SEQUENCE_START_EVENT)
	{
		std::string out = "[";
		for (std::string item = nextCanonical(parser, ended); !ended; item = nextCanonical(parser, ended))
			out += (out.size() > 1 ? ", " : "") + item;
		return out + "]";
	}
	if (first.type == YAML_MAPPING_START_EVENT)
	{
		std::vector<std::pair<std::string, std::string>> kv;
		for (std::string key = nextCanonical(parser, ended); !ended; key = nextCanonical(parser, ended))
			kv.emplace_back(key, nextCanonical(parser, ended));
		std::sort(kv.begin(), kv.end());
		std::string out = "{";
		for (const auto& [k, v] : kv) out += (out.size() > 1 ? ", " : "") + k + ": " + v;
		return out + "}";
	}
	throw std::runtime_error("unexpected libyaml event " + std::to_string(first.type));
}

/** The first document of `text` as libyaml reads it (see canonicalNode). */
std::string canonical(const std::string& text)
{
	yaml_parser_t parser;
	yaml_parser_initialize(&parser);
	yaml_parser_set_input_string(&parser, reinterpret_cast<const unsigned char*>(text.data()), text.size());
	std::string out;
	try
	{
		for (;;)
		{
			yaml_event_t e;
			if (!yaml_parser_parse(&parser, &e))
				throw std::runtime_error(std::string("libyaml: ") + parser.problem);
			const bool content = e.type == YAML_SCALAR_EVENT || e.type == YAML_SEQUENCE_START_EVENT ||
			                     e.type == YAML_MAPPING_START_EVENT;
			const bool end = e.type == YAML_STREAM_END_EVENT;
			if (content) out = canonicalNode(parser, e);
			yaml_event_delete(&e);
			if (content || end) break;
		}
	}
	catch (...)
	{
		yaml_parser_delete(&parser);
		throw;
	}
	yaml_parser_delete(&parser);
	return out;
}

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

/** Documents that tripped MRPT's reader or printer, or could. */
const std::vector<std::string> kTricky = {
    // Comments after block keys, after values, on their own lines.
    "dvl:   # the DVL\n  rate_hz: 5  # fast\n  mode: x\n# between\nother: 1 # last\n",
    "sensors:   # all of them\n  - label: DVL   # the log's label\n    config:   # its block\n      a: 1\n",
    // Flow maps and sequences over several lines, under-indented too.
    "a: 1\ndenial: {start: 10,\nend: 20}\nb: 2\n",
    "a:\n  b: {c: 1,\n  d: 2}\n  e: 3\n",
    "a:\n  b: {c: 1,\n d: 2}\n  e: 3\n",
    "filter:\n  x: 1\ndenial: [{start: 10,\n  end: 20}, {start: 30, end: 40}]\nb: [1,\n2,\n  3]\n",
    "m: {a: [1, 2], # one\n  b: {c: d}}  # two\n",
    // Quoted strings with '#' and ':', plain '#' inside a word, quotes inside.
    "s: 'a # b: c'\nt: \"x: y\"\nh: \"#not a comment\"\nc: a#b\nd: 'it''s'\ne: \"say \\\"hi\\\"\"\n",
    // Empty values and nulls, and the strings that look like them.
    "u:\nv: ~\nw: ''\nx: \"null\"\ny: null\nz: [~, '', \"~\"]\nl:\n  -\n  - x\nem: {}\nes: []\n",
    // Strings a plain writer would break: leading indicators, spaces, escapes, booleans, numbers, unicode.
    "k: '- dash'\nq: '*star'\nr: ' lead'\ns2: 'true'\nt2: '@x'\nu2: \"tab\\there\"\nv2: 'ümlaut'\nn: "
    "'007'\nf: 1e3\n",
    // Block scalars and a plain scalar over two lines.
    "lit: |\n  line1\n  line2\nfold: >\n  folded\n  text\np: a\n  b\n",
    // Keys that need quotes.
    "'a: b': 1\n'#k': 2\n\"\": 3\n'- x': 4\n",
};
}  // namespace

TEST(ConfigRoundTrip, ParseToYamlParseKeepsTheTree)
{
	for (const std::string& doc : kTricky)
	{
		SCOPED_TRACE(doc);
		const Node n = Node::fromText(doc, "tricky.yaml");
		const std::string text = n.toYaml();
		SCOPED_TRACE("toYaml():\n" + text);
		EXPECT_EQ(canonical(text), canonical(doc));
		const std::string again = Node::fromText(text, "generated").toYaml();
		EXPECT_EQ(again, text) << "toYaml() is not a fixed point";
	}
}

TEST(ConfigRoundTrip, BlockKeyWithTrailingCommentReadsBack)
{
	const Node n =
	    Node::fromText("dvl:   # the DVL\n  rate_hz: 5  # fast\n  mode: x\nother: 1\n", "nav.yaml");
	const std::string text = n.toYaml();
	const Node back = Node::fromText(text, "generated");
	EXPECT_DOUBLE_EQ(back.child("dvl").number("rate_hz"), 5);
	EXPECT_EQ(back.child("dvl").string("mode"), "x");
	EXPECT_EQ(back.integer("other"), 1);
	EXPECT_EQ(text.find('#'), std::string::npos) << text;
}

TEST(ConfigRoundTrip, PluginConfigWithCommentsReachesThePlugin)
{
	// The navigator hands a sensor's `config:` block to its plugin as text.
	const Node nav = Node::fromText(
	    "sensors:\n  - label: DVL   # the log's label\n    plugin: dvl\n    config:   # the DVL's own block\n"
	    "      sigma_mps: 0.01   # per beam\n      note: 'see #12: bottom lock'\n",
	    "/cfg/nav.yaml");
	const std::string text = auvnav::pluginConfigText(nav.sequence("sensors")[0]);
	const Node plugin = Node::fromText(text, "dvl plugin config");
	EXPECT_DOUBLE_EQ(plugin.number("sigma_mps"), 0.01);
	EXPECT_EQ(plugin.string("note"), "see #12: bottom lock");
	EXPECT_EQ(plugin.string("config_dir"), "/cfg");
}

TEST(ConfigRoundTrip, UnderIndentedFlowMapIsReadWhole)
{
	// libfyaml ("wrongly indented flow mapping") kept `start` and dropped the
	// rest of the document without an error; libyaml reads it all.
	const Node n = Node::fromText("a: 1\ndenial: {start: 10,\nend: 20}\nb: 2\n", "flow.yaml");
	EXPECT_DOUBLE_EQ(n.child("denial").number("start"), 10);
	EXPECT_DOUBLE_EQ(n.child("denial").number("end"), 20);
	EXPECT_EQ(n.integer("b"), 2);
	const Node m = Node::fromText("a:\n  b: {c: 1,\n  d: 2}\n  e: 3\n", "flow.yaml");
	EXPECT_EQ(m.child("a").child("b").integer("d"), 2);
	EXPECT_EQ(m.child("a").integer("e"), 3);
}

TEST(ConfigRoundTrip, QuotedAndEmptyValuesKeepTheirMeaning)
{
	const Node n = Node::fromText(
	    "s: 'a # b: c'\nt: \"x: y\"\nc: a#b\nu:\nw: ''\nx: \"null\"\nlist: [a,\n  'b, c']\n", "q.yaml");
	const Node back = Node::fromText(n.toYaml(), "generated");
	for (const Node& r : {n, back})
	{
		EXPECT_EQ(r.string("s"), "a # b: c");
		EXPECT_EQ(r.string("t"), "x: y");
		EXPECT_EQ(r.string("c"), "a#b");
		EXPECT_TRUE(r.has("u"));
		EXPECT_EQ(r.string("w"), "");
		EXPECT_EQ(r.string("x"), "null");
		EXPECT_EQ(r.strings("list"), (std::vector<std::string>{"a", "b, c"}));
	}
}

TEST(ConfigRoundTrip, OverriddenValuesAreQuotedWhereNeeded)
{
	Node n = Node::fromText("a: {b: 1}\n", "o.yaml");
	n.set("a.b", "x # y");
	n.set("a.c", "");
	n.set("a.d", "- item");
	const Node back = Node::fromText(n.toYaml(), "generated");
	EXPECT_EQ(back.child("a").string("b"), "x # y");
	EXPECT_EQ(back.child("a").string("c"), "");
	EXPECT_EQ(back.child("a").string("d"), "- item");
}

TEST(ConfigRoundTrip, RefusalsStillNameLineAndColumn)
{
	EXPECT_EQ(errorOf([] { Node::fromText("a: {x: 1,\nx: 2}\n", "dup.yaml"); }),
	          "dup.yaml:2:1: a.x: duplicate key (first at line 1)");
	const std::string bad = errorOf([] { Node::fromText("a: [1, 2\nb: 3\n", "bad.yaml"); });
	EXPECT_EQ(bad.rfind("bad.yaml:", 0), 0u) << bad;
	EXPECT_NE(bad.find("malformed YAML"), std::string::npos) << bad;
	EXPECT_EQ(errorOf([] { Node::fromText("", "empty.yaml"); }), "empty.yaml: top level must be a YAML map");
	EXPECT_EQ(errorOf([] { Node::fromText("# only a comment\n", "c.yaml"); }),
	          "c.yaml: top level must be a YAML map");
}
