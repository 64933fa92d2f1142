// MRPT's tree to YAML text (config_yaml.h), with libyaml's emitter.
#include <yaml.h>

#include "config_yaml.h"

namespace auvnav::config::detail
{
using mrpt::containers::yaml;

namespace
{
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

std::string emitDocument(const yaml::node_t& root, const std::string& where)
{
	return TextEmitter(where).document(root);
}

}  // namespace auvnav::config::detail
