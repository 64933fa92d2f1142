// Node's key bookkeeping (config.h): which keys were read, unknown-key checks
// and the "did you mean" suggestions.
#include <auvnav/config.h>

#include <algorithm>
#include <cctype>

namespace auvnav::config
{
using mrpt::containers::yaml;

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

}  // namespace auvnav::config
