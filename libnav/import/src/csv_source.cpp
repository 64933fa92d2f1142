#include <auvnav/import/csv_source.h>

#include <atomic>
#include <set>

namespace auvnav::import
{
namespace
{
uint64_t newLayoutId()
{
	static std::atomic<uint64_t> next{1};
	return next++;
}

constexpr std::size_t kMaxLineBytes = 16u << 20;

bool isBlankOrComment(const std::string& line)
{
	for (char c : line)
	{
		if (c == ' ' || c == '\t') continue;
		return c == '#';
	}
	return true;
}

std::string trimmed(const std::string& s)
{
	const auto b = s.find_first_not_of(" \t");
	if (b == std::string::npos) return {};
	const auto e = s.find_last_not_of(" \t");
	return s.substr(b, e - b + 1);
}
}  // namespace

CsvSource::CsvSource(const std::string& path, char delimiter)
    : path_(path), in_(path, std::ios::binary), delimiter_(delimiter), layout_id_(newLayoutId())
{
	if (!in_) throw ImportError(path + ": cannot open CSV file");
	std::string line;
	while (readLine(line))
	{
		if (line_no_ == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
		if (isBlankOrComment(line)) continue;
		if (!splitCells(line, delimiter_, cells_, quoted_))
			throw ImportError(path + ":" + std::to_string(line_no_) +
			                  ": header row has an unterminated quote");
		std::set<std::string> seen;
		for (auto& c : cells_)
		{
			c = trimmed(c);
			if (c.empty())
				throw ImportError(path + ":" + std::to_string(line_no_) +
				                  ": header row has an empty column name");
			if (!seen.insert(c).second)
				throw ImportError(path + ":" + std::to_string(line_no_) + ": column '" + c +
				                  "' appears twice in the header row");
		}
		header_ = cells_;
		return;
	}
	throw ImportError(path + ": empty CSV file (no header row)");
}

bool CsvSource::readLine(std::string& line)
{
	// Bounded while reading: std::getline would first hold the whole "line" (a
	// binary without line breaks: its whole size) and only then be checked.
	line.clear();
	std::streambuf* sb = in_.rdbuf();
	bool any = false;
	for (;;)
	{
		const int c = sb->sbumpc();
		if (c == std::char_traits<char>::eof())
		{
			in_.setstate(std::ios::eofbit);
			if (!any) return false;
			break;
		}
		any = true;
		if (c == '\n') break;
		if (line.size() >= kMaxLineBytes)
			throw ImportError(path_ + ":" + std::to_string(line_no_ + 1) + ": line longer than " +
			                  std::to_string(kMaxLineBytes / (1 << 20)) + " MiB (not a CSV file?)");
		line.push_back(static_cast<char>(c));
	}
	++line_no_;
	if (!line.empty() && line.back() == '\r') line.pop_back();
	return true;
}

bool CsvSource::splitCells(const std::string& line, char delimiter, std::vector<std::string>& cells,
                           std::vector<bool>& quoted)
{
	cells.clear();
	quoted.clear();
	std::string cur;
	bool in_quotes = false, was_quoted = false;
	for (std::size_t i = 0; i < line.size(); ++i)
	{
		const char c = line[i];
		if (in_quotes)
		{
			if (c == '"')
			{
				if (i + 1 < line.size() && line[i + 1] == '"')
				{
					cur.push_back('"');
					++i;
				}
				else
					in_quotes = false;
			}
			else
				cur.push_back(c);
		}
		else if (c == '"')
			in_quotes = was_quoted = true;
		else if (c == delimiter)
		{
			cells.push_back(std::move(cur));
			quoted.push_back(was_quoted);
			cur.clear();
			was_quoted = false;
		}
		else
			cur.push_back(c);
	}
	cells.push_back(std::move(cur));
	quoted.push_back(was_quoted);
	return !in_quotes;
}

bool CsvSource::next(Record& out)
{
	std::string line;
	while (readLine(line))
	{
		if (isBlankOrComment(line)) continue;
		out.where = path_ + ":" + std::to_string(line_no_);
		out.defect.clear();
		out.has_record_time = false;
		if (out.layout_id != layout_id_)
		{
			out.names = header_;
			out.layout_id = layout_id_;
		}
		out.values.resize(header_.size());
		if (!splitCells(line, delimiter_, cells_, quoted_))
		{
			out.defect = "unterminated quote";
			for (auto& v : out.values) v.kind = Value::Kind::Missing;
			return true;
		}
		if (cells_.size() != header_.size())
		{
			out.defect =
			    std::to_string(cells_.size()) + " cells, the header has " + std::to_string(header_.size());
			for (auto& v : out.values) v.kind = Value::Kind::Missing;
			return true;
		}
		for (std::size_t i = 0; i < cells_.size(); ++i)
		{
			Value& v = out.values[i];
			std::string& c = cells_[i];
			// An empty cell, quoted or not, is no value.
			const bool blank = c.find_first_not_of(" \t") == std::string::npos;
			if (blank)
			{
				v.kind = Value::Kind::Missing;
				continue;
			}
			v.kind = Value::Kind::Text;
			v.text.swap(c);
		}
		return true;
	}
	if (in_.bad()) throw ImportError(path_ + ":" + std::to_string(line_no_ + 1) + ": read error");
	return false;
}

}  // namespace auvnav::import
