// libFuzzer harness: auvnav::config (YAML parser, structure check and every
// typed accessor) on arbitrary text.
//
// config.h promises that every failure is a ConfigError naming file and key;
// any other exception escaping is a finding. Every key of the document is
// read through every accessor (most refuse: the wrong type), sub-maps and
// list elements recursively, then toYaml, set() of a path built from the
// document's own keys and checkAllKeysUsed().
#include <auvnav/config.h>

#include <cstdio>
#include <cstdlib>

#include "fuzz_support.h"

using auvnav::config::ConfigError;
using auvnav::config::Node;

namespace
{
/** Runs `f`; a ConfigError is an expected refusal, anything else a finding. */
template <class F>
void expectOnlyConfigError(const char* what, F&& f)
{
	try
	{
		f();
	}
	catch (const ConfigError&)
	{
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "%s threw a non-ConfigError: %s\n", what, e.what());
		std::abort();
	}
}

void readEverything(const Node& n, int depth, std::string& some_path)
{
	if (depth > 8) return;  // deep enough to reach every accessor path
	std::vector<std::string> keys;
	expectOnlyConfigError("keys", [&] { keys = n.keys(); });
	for (const auto& k : keys)
	{
		if (depth == 0 && some_path.empty()) some_path = k;
		(void)n.has(k), (void)n.isScalar(k), (void)n.isSequence(k), (void)n.isMapAt(k);
		expectOnlyConfigError("number", [&] { (void)n.number(k); });
		expectOnlyConfigError("number/default", [&] { (void)n.number(k, 1.0); });
		expectOnlyConfigError("positive", [&] { (void)n.positive(k, 1.0); });
		expectOnlyConfigError("nonNegative", [&] { (void)n.nonNegative(k); });
		expectOnlyConfigError("inRange", [&] { (void)n.inRange(k, -1.0, 1.0); });
		expectOnlyConfigError("integer", [&] { (void)n.integer(k, 0); });
		expectOnlyConfigError("boolean", [&] { (void)n.boolean(k, false); });
		expectOnlyConfigError("string", [&] { (void)n.string(k); });
		expectOnlyConfigError("filePath", [&] { (void)n.filePath(k); });
		expectOnlyConfigError("vector3", [&] { (void)n.vector3(k); });
		expectOnlyConfigError("strings", [&] { (void)n.strings(k); });
		expectOnlyConfigError("numbers", [&] { (void)n.numbers(k); });
		expectOnlyConfigError("child", [&] { readEverything(n.child(k), depth + 1, some_path); });
		expectOnlyConfigError("sequence",
		                      [&]
		                      {
			                      for (const auto& e : n.sequence(k))
				                      if (e.isMap()) readEverything(e, depth + 1, some_path);
		                      });
		expectOnlyConfigError("where", [&] { (void)n.where(k); });
	}
	expectOnlyConfigError("allowOnly", [&] { n.allowOnly({"label", "plugin"}); });
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size)
{
	const std::string text(reinterpret_cast<const char*>(data), size);
	Node root;
	try
	{
		root = Node::fromText(text, "fuzz.yaml");
	}
	catch (const ConfigError&)
	{
		return 0;  // refused with one line: the expected outcome for most inputs
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "fromText threw a non-ConfigError: %s\n", e.what());
		std::abort();
	}
	std::string some_path;
	readEverything(root, 0, some_path);
	expectOnlyConfigError("toYaml", [&] { (void)root.toYaml(); });
	expectOnlyConfigError("checkAllKeysUsed", [&] { root.checkAllKeysUsed(); });
	if (!some_path.empty())
	{
		expectOnlyConfigError("set", [&] { root.set(some_path + ".x.0", "12.5"); });
		expectOnlyConfigError("set", [&] { root.set(some_path, "[1, 2"); });
	}
	return 0;
}
