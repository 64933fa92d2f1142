// YAML text to MRPT's tree (config_yaml.h): libyaml's events, checked for what
// MRPT's reader would get wrong, build the tree.
#include <yaml.h>

#include <map>
#include <optional>
#include <sstream>

#include "config_yaml.h"

namespace auvnav::config::detail
{
using mrpt::containers::yaml;

namespace
{
/** What libyaml's event stream says MRPT's YAML reader would get wrong:
 *  syntax errors (reported on stderr by MRPT, with a partial document),
 *  duplicate keys (the last silently wins), a second document (silently
 *  dropped), aliases and non-scalar keys (a multi-line assertion report).
 *  Each is refused as one line: "ORIGIN:LINE:COLUMN: [KEY.PATH: ]what". */
class StructureCheck
{
 public:
	explicit StructureCheck(std::string origin) : origin_(std::move(origin)) {}

	/** Empty, or the reason `event` makes the document unusable. */
	std::string onEvent(const yaml_event_t& event)
	{
		const auto& mark = event.start_mark;
		switch (event.type)
		{
			case YAML_DOCUMENT_START_EVENT:
				if (++documents_ > 1)
					return at(mark, "", "a second YAML document ('---' or '...'): one document per file");
				return "";
			case YAML_ALIAS_EVENT:
				return at(mark, path(), "aliases (*" + text(event.data.alias.anchor) + ") are not supported");
			case YAML_SCALAR_EVENT:
				return node(mark, text(event.data.scalar.value), true);
			case YAML_SEQUENCE_START_EVENT:
			case YAML_MAPPING_START_EVENT:
			{
				std::string why = node(mark, "", false);
				Level level;
				level.map = event.type == YAML_MAPPING_START_EVENT;
				levels_.push_back(std::move(level));
				return why;
			}
			case YAML_SEQUENCE_END_EVENT:
			case YAML_MAPPING_END_EVENT:
				levels_.pop_back();
				return "";
			default:
				return "";
		}
	}

 private:
	struct Level
	{
		bool map = false;
		bool at_key = true;                // a map's next node is a key
		std::string key;                   // a map's latest key
		int items = 0;                     // a sequence's items so far
		std::map<std::string, int> lines;  // a map's keys and their lines
	};

	static std::string text(const yaml_char_t* s) { return s ? reinterpret_cast<const char*>(s) : ""; }

	std::string node(const yaml_mark_t& mark, const std::string& value, bool scalar)
	{
		if (levels_.empty()) return "";
		Level& l = levels_.back();
		if (!l.map)
		{
			++l.items;
			return "";
		}
		l.at_key = !l.at_key;
		if (l.at_key) return "";  // this was the value
		if (!scalar) return at(mark, path(), "a key must be a plain name, not a list or a map");
		l.key = value;
		const auto [it, fresh] = l.lines.emplace(value, static_cast<int>(mark.line) + 1);
		if (!fresh)
			return at(mark, path(), "duplicate key (first at line " + std::to_string(it->second) + ")");
		return "";
	}

	/** The dotted path of the node being read (list items as [i]). */
	std::string path() const
	{
		std::string p;
		for (const Level& l : levels_)
		{
			if (l.map && !l.key.empty()) p += (p.empty() ? "" : ".") + l.key;
			if (!l.map && l.items > 0) p += "[" + std::to_string(l.items - 1) + "]";
		}
		return p;
	}

	std::string at(const yaml_mark_t& mark, const std::string& key_path, const std::string& what) const
	{
		return origin_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1) + ": " +
		       (key_path.empty() ? "" : key_path + ": ") + what;
	}

	std::string origin_;
	int documents_ = 0;
	std::vector<Level> levels_;
};

/** Builds the document tree from the very events StructureCheck accepted, so
 *  that the check that accepts a document is the parser that reads it. (MRPT's
 *  own reader, libfyaml, silently cut an under-indented flow map that libyaml
 *  accepts, refused empty values, and kept comments that its printer then
 *  turned into invalid YAML.) MRPT's yaml is the container only. Scalars are
 *  strings, as MRPT stores them; an untagged plain empty, ~, null, Null or NULL
 *  is a null scalar (an empty std::any), as MRPT's reader made it; quoted,
 *  they are the strings. Comments are not kept. */
class TreeBuilder
{
 public:
	void onEvent(const yaml_event_t& event)
	{
		switch (event.type)
		{
			case YAML_SCALAR_EVENT:
				add(scalar(event));
				return;
			case YAML_SEQUENCE_START_EVENT:
				open(event, yaml::sequence_t());
				return;
			case YAML_MAPPING_START_EVENT:
				open(event, yaml::map_t());
				return;
			case YAML_SEQUENCE_END_EVENT:
			case YAML_MAPPING_END_EVENT:
			{
				yaml::node_t done = open_.back().node;
				open_.pop_back();
				add(done);
				return;
			}
			default:
				return;
		}
	}
	/** The document's root; false if the text holds no document (empty or comments only). */
	bool root(yaml::node_t& out) const
	{
		if (!has_root_) return false;
		out = root_;
		return true;
	}

 private:
	struct Open
	{
		yaml::node_t node;
		std::optional<yaml::node_t> key;  // a map's key waiting for its value
	};

	static void mark(yaml::node_t& n, const yaml_event_t& event)
	{
		n.marks.input_pos = event.start_mark.index;
		n.marks.line = static_cast<int>(event.start_mark.line);
		n.marks.column = static_cast<int>(event.start_mark.column);
	}

	static yaml::node_t scalar(const yaml_event_t& event)
	{
		const auto& s = event.data.scalar;
		const std::string text(reinterpret_cast<const char*>(s.value), s.length);
		yaml::node_t n;
		const bool plain = s.plain_implicit && s.style == YAML_PLAIN_SCALAR_STYLE;
		if (plain && readsAsNull(text))
			n.d.emplace<yaml::scalar_t>();
		else
			n.d.emplace<yaml::scalar_t>().emplace<std::string>(text);
		mark(n, event);
		return n;
	}

	template <class Collection>
	void open(const yaml_event_t& event, Collection empty)
	{
		Open o;
		o.node.d = std::move(empty);
		mark(o.node, event);
		open_.push_back(std::move(o));
	}

	void add(yaml::node_t n)
	{
		if (open_.empty())
		{
			root_ = n;
			has_root_ = true;
			return;
		}
		Open& top = open_.back();
		if (top.node.isSequence())
			top.node.asSequence().push_back(std::move(n));
		else if (!top.key)
			top.key = std::move(n);
		else
		{
			// StructureCheck refused non-scalar and duplicate keys; a null key is its text.
			if (top.key->isNullNode()) top.key->d.emplace<yaml::scalar_t>().emplace<std::string>("");
			top.node.asMap()[std::move(*top.key)] = n;
			top.key.reset();
		}
	}

	std::vector<Open> open_;
	yaml::node_t root_;
	bool has_root_ = false;
};
}  // namespace

bool readsAsNull(const std::string& text)
{
	return text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL";
}

bool parseDocument(const std::string& text, const std::string& origin, yaml::node_t& root)
{
	yaml_parser_t parser;
	if (!yaml_parser_initialize(&parser)) throw ConfigError(origin + ": cannot initialise the YAML parser");
	yaml_parser_set_input_string(&parser, reinterpret_cast<const unsigned char*>(text.data()), text.size());
	StructureCheck structure(origin);
	TreeBuilder tree;
	std::string error;
	for (bool done = false; !done && error.empty();)
	{
		yaml_event_t event;
		if (!yaml_parser_parse(&parser, &event))
		{
			std::ostringstream m;
			m << origin << ":" << parser.problem_mark.line + 1 << ":" << parser.problem_mark.column + 1
			  << ": malformed YAML: " << (parser.problem ? parser.problem : "syntax error");
			if (parser.context) m << " " << parser.context;
			error = m.str();
			break;
		}
		error = structure.onEvent(event);
		if (error.empty()) tree.onEvent(event);
		done = event.type == YAML_STREAM_END_EVENT;
		yaml_event_delete(&event);
	}
	yaml_parser_delete(&parser);
	if (!error.empty()) throw ConfigError(error);
	return tree.root(root);
}

}  // namespace auvnav::config::detail
