#include <auvnav/config.h>
#include <yaml.h>
#include <algorithm>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace auvnav::config
{
using mrpt::containers::yaml;

Node::Node(yaml y, std::string file, std::string path, std::shared_ptr<Access> access)
    : y_(std::move(y)), file_(std::move(file)), path_(std::move(path)), access_(std::move(access))
{
}

Node Node::load(const std::string& file)
{
	std::ifstream f(file);
	if (!f) throw ConfigError(file + ": cannot open configuration file");
	std::stringstream ss;
	ss << f.rdbuf();
	return fromText(ss.str(), file);
}

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

/** A plain untagged scalar with this text is null (YAML 1.2 core schema). */
bool readsAsNull(const std::string& text)
{
	return text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL";
}

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
				yaml::node_t done = std::move(open_.back().node);
				open_.pop_back();
				add(std::move(done));
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
			root_ = std::move(n);
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
			top.node.asMap()[std::move(*top.key)] = std::move(n);
			top.key.reset();
		}
	}

	std::vector<Open> open_;
	yaml::node_t root_;
	bool has_root_ = false;
};

/** Parses `text` with libyaml into a tree, refusing in one line
 *  "ORIGIN:LINE:COLUMN: [KEY.PATH: ]what" what StructureCheck refuses and
 *  libyaml's syntax errors. False if the text holds no document. */
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

/** Writes a tree as block YAML with libyaml's emitter (the library that
 *  reads it back): it quotes what needs quoting ('#', ": ", a leading '-' or
 *  '*', ...). Strings that would read back as null if plain are double-quoted;
 *  null scalars are written as ~. */
class TextEmitter
{
 public:
	explicit TextEmitter(std::string where) : where_(std::move(where))
	{
		if (!yaml_emitter_initialize(&emitter_))
			throw ConfigError(where_ + ": cannot initialise the YAML emitter");
		yaml_emitter_set_output(&emitter_, &TextEmitter::append, &out_);
		yaml_emitter_set_unicode(&emitter_, 1);
		yaml_emitter_set_width(&emitter_, -1);  // no folding of long scalars
		yaml_emitter_set_indent(&emitter_, 2);
	}
	~TextEmitter() { yaml_emitter_delete(&emitter_); }
	TextEmitter(const TextEmitter&) = delete;
	TextEmitter& operator=(const TextEmitter&) = delete;

	std::string document(const yaml::node_t& root)
	{
		yaml_event_t e;
		yaml_stream_start_event_initialize(&e, YAML_UTF8_ENCODING);
		emit(e);
		yaml_document_start_event_initialize(&e, nullptr, nullptr, nullptr, 1);
		emit(e);
		node(root);
		yaml_document_end_event_initialize(&e, 1);
		emit(e);
		yaml_stream_end_event_initialize(&e);
		emit(e);
		return out_;
	}

 private:
	static int append(void* data, unsigned char* buffer, size_t size)
	{
		static_cast<std::string*>(data)->append(reinterpret_cast<const char*>(buffer), size);
		return 1;
	}

	void emit(yaml_event_t& event)
	{
		// yaml_emitter_emit takes the event over, also when it fails.
		if (!yaml_emitter_emit(&emitter_, &event))
			throw ConfigError(
			    where_ + ": cannot write YAML: " + (emitter_.problem ? emitter_.problem : "emitter error"));
	}

	void node(const yaml::node_t& n)
	{
		yaml_event_t e;
		if (n.isMap())
		{
			yaml_mapping_start_event_initialize(&e, nullptr, nullptr, 1, YAML_BLOCK_MAPPING_STYLE);
			emit(e);
			for (const auto& kv : n.asMap())
			{
				node(kv.first);
				node(kv.second);
			}
			yaml_mapping_end_event_initialize(&e);
			emit(e);
		}
		else if (n.isSequence())
		{
			yaml_sequence_start_event_initialize(&e, nullptr, nullptr, 1, YAML_BLOCK_SEQUENCE_STYLE);
			emit(e);
			for (const auto& item : n.asSequence()) node(item);
			yaml_sequence_end_event_initialize(&e);
			emit(e);
		}
		else if (n.isNullNode())
			scalar("~", YAML_PLAIN_SCALAR_STYLE);
		else
		{
			std::string text;
			try
			{
				text = n.as<std::string>();
			}
			catch (const std::exception&)
			{
				throw ConfigError(where_ + ": cannot write a value of type " + n.typeName() + " as YAML");
			}
			scalar(text, styleFor(text));
		}
	}

	/** Plain where libyaml finds it safe; double-quoted if plain would read
	 *  back as null; multi-line text as a literal block where libyaml allows
	 *  one (else it quotes). */
	static yaml_scalar_style_t styleFor(const std::string& text)
	{
		if (readsAsNull(text)) return YAML_DOUBLE_QUOTED_SCALAR_STYLE;
		return text.find('\n') != std::string::npos ? YAML_LITERAL_SCALAR_STYLE : YAML_ANY_SCALAR_STYLE;
	}

	void scalar(const std::string& text, yaml_scalar_style_t style)
	{
		yaml_event_t e;
		auto* value = reinterpret_cast<yaml_char_t*>(const_cast<char*>(text.data()));
		if (!yaml_scalar_event_initialize(&e, nullptr, nullptr, value, static_cast<int>(text.size()), 1, 1,
		                                  style))
			throw ConfigError(where_ + ": cannot write YAML: out of memory");
		emit(e);
	}

	std::string where_;
	std::string out_;
	yaml_emitter_t emitter_;
};
}  // namespace

Node Node::fromText(const std::string& text, const std::string& origin)
{
	yaml::node_t root;
	if (!parseDocument(text, origin, root) || !root.isMap())
		throw ConfigError(origin + ": top level must be a YAML map");
	yaml y;
	y.node() = std::move(root);
	return Node(std::move(y), origin, "", std::make_shared<Access>());
}

std::string Node::filePath(const std::string& key) const
{
	const std::string p = string(key);
	if (p.empty()) fail(key, "expected a file path");
	if (p[0] == '/') return p;
	const auto slash = file_.find_last_of('/');
	return slash == std::string::npos ? p : file_.substr(0, slash + 1) + p;
}

std::string Node::toYaml() const
{
	if (y_.isNullNode() || (y_.isMap() && y_.empty())) return "{}\n";
	return TextEmitter(file_ + (path_.empty() ? "" : ": " + path_)).document(y_.node());
}

void Node::set(const std::string& dotted_path, const std::string& value)
{
	std::vector<std::string> keys;
	std::stringstream ss(dotted_path);
	for (std::string k; std::getline(ss, k, '.');)
	{
		if (k.empty()) throw ConfigError("override '" + dotted_path + "': empty key");
		keys.push_back(k);
	}
	if (keys.empty()) throw ConfigError("override: empty key path");
	yaml::node_t* n = &y_.node();
	std::string walked;
	std::string canonical = path_;  // list elements by index, as checkAllKeysUsed() names them
	for (std::size_t i = 0; i < keys.size(); ++i)
	{
		if (n->isSequence())
		{
			// A list is entered by an element's `label` (sensors.SONAR.config.mode)
			// or by its index.
			yaml::node_t* found = nullptr;
			auto& seq = n->asSequence();
			const bool numeric = keys[i].find_first_not_of("0123456789") == std::string::npos;
			for (std::size_t j = 0; j < seq.size() && !found; ++j)
			{
				if (numeric && std::stoul(keys[i]) == j)
					found = &seq[j];
				else if (seq[j].isMap())
				{
					const auto& m = seq[j].asMap();
					const auto it = m.find(yaml::node_t("label"));
					if (it != m.end() && it->second.isScalar() && it->second.as<std::string>() == keys[i])
						found = &seq[j];
				}
			}
			if (!found)
				throw ConfigError(file_ + ": override '" + dotted_path + "': no element '" + keys[i] +
				                  "' (label or index) in '" + walked + "'");
			n = found;
			walked += (walked.empty() ? "" : ".") + keys[i];
			canonical += "[" + std::to_string(found - &seq[0]) + "]";
			continue;
		}
		if (n->isNullNode()) n->d.emplace<yaml::map_t>();
		if (!n->isMap())
			throw ConfigError(file_ + ": override '" + dotted_path + "': '" + walked + "' is not a map");
		auto& m = n->asMap();
		n = &m[yaml::node_t(keys[i])];
		walked += (walked.empty() ? "" : ".") + keys[i];
		canonical += (canonical.empty() ? "" : ".") + keys[i];
		access_->overridden.insert(canonical);
	}
	n->d.emplace<yaml::scalar_t>().emplace<std::string>(value);
}

std::string Node::where(const std::string& key) const
{
	return file_ + ": " + (path_.empty() ? key : path_ + "." + key);
}

void Node::fail(const std::string& key, const std::string& what) const
{
	throw ConfigError(where(key) + ": " + what);
}

std::string Node::fullPath(const std::string& key) const
{
	return path_.empty() ? key : path_ + "." + key;
}

namespace
{
/** "sensors[2].config" -> "sensors[].config": the elements of a list share
 *  their candidate keys. */
std::string levelOf(const std::string& path)
{
	std::string out;
	for (std::size_t i = 0; i < path.size(); ++i)
	{
		out += path[i];
		if (path[i] == '[')
		{
			while (i + 1 < path.size() && path[i + 1] != ']') ++i;
		}
	}
	return out;
}

/** Optimal-string-alignment distance (a swap of neighbours costs 1), case-insensitive. */
std::size_t editDistance(const std::string& a, const std::string& b)
{
	auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
	const std::size_t n = a.size(), m = b.size();
	std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
	for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
	for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
	for (std::size_t i = 1; i <= n; ++i)
		for (std::size_t j = 1; j <= m; ++j)
		{
			const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
			d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
			if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
				d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
		}
	return d[n][m];
}

/** " (did you mean 'x'?)" for the nearest candidate within a third of the
 *  key's length (at least 1, at most 3 edits), else the list of valid keys. */
std::string suggestion(const std::string& key, const std::set<std::string>& candidates)
{
	const std::size_t limit = std::max<std::size_t>(1, std::min<std::size_t>(3, key.size() / 3));
	std::string best;
	std::size_t best_d = limit + 1;
	for (const auto& c : candidates)
	{
		const std::size_t d = editDistance(key, c);
		if (d < best_d && d < key.size()) best_d = d, best = c;  // "d" is no typo of "c"
	}
	if (!best.empty()) return " (did you mean '" + best + "'?)";
	if (candidates.empty()) return " (nothing is read here)";
	std::string list;
	std::size_t shown = 0;
	for (const auto& c : candidates)
	{
		if (++shown > 16)
		{
			list += ", ...";
			break;
		}
		list += (list.empty() ? "" : ", ") + c;
	}
	return " (valid here: " + list + ")";
}
}  // namespace

void Node::noteAccess(const std::string& key) const
{
	access_->asked[levelOf(path_)].insert(key);
	if (y_.isMap() && y_.has(key)) access_->used.insert(fullPath(key));
}

bool Node::has(const std::string& key) const
{
	noteAccess(key);
	return y_.isMap() && y_.has(key);
}

void Node::markFreeForm(const std::string& key) const
{
	noteAccess(key);
	access_->free_form.insert(fullPath(key));
}

void Node::checkAllKeysUsed(const std::vector<std::string>& except) const
{
	checkUnder(y_, path_, except);
}

void Node::checkUnder(const yaml& y, const std::string& path, const std::vector<std::string>& except) const
{
	if (y.isSequence())
	{
		const auto& seq = y.asSequence();
		for (std::size_t i = 0; i < seq.size(); ++i)
			checkUnder(yaml(seq[i]), path + "[" + std::to_string(i) + "]", {});
		return;
	}
	if (!y.isMap()) return;
	for (const auto& kv : y.asMap())
	{
		const std::string k = kv.first.as<std::string>();
		if (std::find(except.begin(), except.end(), k) != except.end()) continue;
		const std::string full = path.empty() ? k : path + "." + k;
		if (access_->free_form.count(full)) continue;
		if (!access_->used.count(full))
		{
			const auto it = access_->asked.find(levelOf(path));
			const std::string hint =
			    suggestion(k, it == access_->asked.end() ? std::set<std::string>{} : it->second);
			throw ConfigError(file_ + ": " + full + ": unknown key" + hint +
			                  (access_->overridden.count(full) ? " [given as an override]" : ""));
		}
		checkUnder(yaml(kv.second), full, {});
	}
}
bool Node::isScalar(const std::string& key) const
{
	return has(key) && yaml(y_[key].node()).isScalar();
}
bool Node::isSequence(const std::string& key) const
{
	return has(key) && yaml(y_[key].node()).isSequence();
}
bool Node::isMapAt(const std::string& key) const
{
	return has(key) && yaml(y_[key].node()).isMap();
}

std::vector<std::string> Node::keys() const
{
	std::vector<std::string> out;
	if (!y_.isMap()) return out;
	for (const auto& kv : y_.asMap()) out.push_back(kv.first.as<std::string>());
	return out;
}

void Node::allowOnly(const std::vector<std::string>& allowed) const
{
	for (const auto& a : allowed) noteAccess(a);
	for (const auto& k : keys())
		if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
		{
			std::string list;
			for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
			std::string hint = suggestion(k, std::set<std::string>(allowed.begin(), allowed.end()));
			hint = hint.rfind(" (did you mean", 0) == 0 ? hint.substr(0, hint.size() - 1) + " " : " (";
			fail(k, "unknown key" + hint + "expected one of: " + list + ")");
		}
}

Node Node::child(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required section");
	yaml sub(y_[key].node());
	if (!sub.isMap()) fail(key, "expected a map of keys");
	return Node(std::move(sub), file_, fullPath(key), access_);
}

std::vector<Node> Node::sequence(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list");
	yaml sub(y_[key].node());
	if (!sub.isSequence()) fail(key, "expected a list");
	std::vector<Node> out;
	const auto& seq = sub.asSequence();
	for (std::size_t i = 0; i < seq.size(); ++i)
		out.push_back(Node(yaml(seq[i]), file_, fullPath(key) + "[" + std::to_string(i) + "]", access_));
	return out;
}

std::string Node::scalarText(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required value");
	const yaml v = y_[key];
	if (!v.isScalar()) fail(key, "expected a single value");
	try
	{
		return v.as<std::string>();
	}
	catch (const std::exception&)
	{
		fail(key, "unreadable value");
	}
}

namespace
{
bool parseFinite(const std::string& s, double& out)
{
	const char* b = s.c_str();
	char* e = nullptr;
	out = std::strtod(b, &e);
	while (e && *e == ' ') ++e;
	return e != b && e && *e == '\0' && std::isfinite(out);
}
}  // namespace

double Node::number(const std::string& key) const
{
	const std::string s = scalarText(key);
	double v = 0;
	if (!parseFinite(s, v)) fail(key, "expected a finite number, got '" + s + "'");
	return v;
}
double Node::number(const std::string& key, double d) const
{
	return has(key) ? number(key) : d;
}

double Node::positive(const std::string& key) const
{
	const double v = number(key);
	if (!(v > 0)) fail(key, "expected a positive number, got '" + scalarText(key) + "'");
	return v;
}
double Node::positive(const std::string& key, double d) const
{
	return has(key) ? positive(key) : d;
}

double Node::nonNegative(const std::string& key) const
{
	const double v = number(key);
	if (!(v >= 0)) fail(key, "expected a number >= 0, got '" + scalarText(key) + "'");
	return v;
}
double Node::nonNegative(const std::string& key, double d) const
{
	return has(key) ? nonNegative(key) : d;
}

double Node::inRange(const std::string& key, double lo, double hi) const
{
	const double v = number(key);
	if (v < lo || v > hi)
	{
		std::ostringstream m;
		m << "expected a number in [" << lo << ", " << hi << "], got '" << scalarText(key) << "'";
		fail(key, m.str());
	}
	return v;
}
double Node::inRange(const std::string& key, double lo, double hi, double d) const
{
	return has(key) ? inRange(key, lo, hi) : d;
}

int Node::integer(const std::string& key) const
{
	const double v = number(key);
	if (std::floor(v) != v || std::abs(v) > 2e9)
		fail(key, "expected an integer, got '" + scalarText(key) + "'");
	return static_cast<int>(v);
}
int Node::integer(const std::string& key, int d) const
{
	return has(key) ? integer(key) : d;
}

bool Node::boolean(const std::string& key, bool d) const
{
	if (!has(key)) return d;
	const std::string s = scalarText(key);
	if (s == "true" || s == "True" || s == "yes" || s == "1") return true;
	if (s == "false" || s == "False" || s == "no" || s == "0") return false;
	fail(key, "expected true or false, got '" + s + "'");
}

std::string Node::string(const std::string& key) const
{
	return scalarText(key);
}
std::string Node::string(const std::string& key, const std::string& d) const
{
	return has(key) ? string(key) : d;
}

std::vector<double> Node::numbers(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list of numbers");
	yaml sub(y_[key].node());
	if (!sub.isSequence() || sub.asSequence().empty()) fail(key, "expected a non-empty list of numbers");
	std::vector<double> out;
	for (const auto& n : sub.asSequence())
	{
		double v = 0;
		std::string s;
		try
		{
			s = yaml(n).as<std::string>();
		}
		catch (const std::exception&)
		{
			fail(key, "expected a list of numbers");
		}
		if (!parseFinite(s, v)) fail(key, "expected finite numbers, got '" + s + "'");
		out.push_back(v);
	}
	return out;
}

std::vector<std::string> Node::strings(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list");
	yaml sub(y_[key].node());
	if (!sub.isSequence() || sub.asSequence().empty()) fail(key, "expected a non-empty list");
	std::vector<std::string> out;
	for (const auto& n : sub.asSequence())
	{
		if (!yaml(n).isScalar()) fail(key, "expected a list of names");
		out.push_back(yaml(n).as<std::string>());
	}
	return out;
}

Eigen::Vector3d Node::vector3(const std::string& key) const
{
	const auto v = numbers(key);
	if (v.size() != 3) fail(key, "expected exactly 3 numbers, got " + std::to_string(v.size()));
	return {v[0], v[1], v[2]};
}
Eigen::Vector3d Node::vector3(const std::string& key, const Eigen::Vector3d& d) const
{
	return has(key) ? vector3(key) : d;
}

}  // namespace auvnav::config
