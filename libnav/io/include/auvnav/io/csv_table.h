#pragma once
/** @file csv_table.h
 *  Reads a CSV file with a header row (auvnav-run's states.csv, nis.csv,
 *  position_fixes.csv; auvnav-sim's ground_truth.csv) row by row, columns by
 *  name. Errors name the file and line. Header only.
 */
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav::io
{
class CsvTable
{
 public:
	explicit CsvTable(const std::string& file) : file_(file), in_(file)
	{
		if (!in_) throw std::runtime_error("cannot read " + file);
		std::string header;
		if (!std::getline(in_, header)) throw std::runtime_error(file + ": empty");
		std::stringstream ss(header);
		std::size_t i = 0;
		for (std::string name; std::getline(ss, name, ',');) col_[name] = i++;
	}
	/** Whether the header names the column. */
	bool has(const std::string& name) const { return col_.count(name) > 0; }
	/** Index of a required column. */
	std::size_t column(const std::string& name) const
	{
		const auto it = col_.find(name);
		if (it == col_.end()) throw std::runtime_error(file_ + ": no column '" + name + "'");
		return it->second;
	}
	/** Advances to the next row; false at the end. */
	bool next()
	{
		std::string line;
		if (!std::getline(in_, line)) return false;
		++line_;
		fields_.clear();
		std::stringstream ss(line);
		for (std::string f; std::getline(ss, f, ',');) fields_.push_back(f);
		return true;
	}
	const std::string& text(std::size_t i) const
	{
		if (i >= fields_.size()) throw std::runtime_error(where() + ": too few fields");
		return fields_[i];
	}
	double number(std::size_t i) const
	{
		const std::string& f = text(i);
		try
		{
			return std::stod(f);
		}
		catch (const std::exception&)
		{
			throw std::runtime_error(where() + ": '" + f + "' is not a number");
		}
	}
	/** "file:line" of the current row. */
	std::string where() const { return file_ + ":" + std::to_string(line_); }
	const std::string& file() const { return file_; }

 private:
	std::string file_;
	std::ifstream in_;
	std::map<std::string, std::size_t> col_;
	std::vector<std::string> fields_;
	int line_ = 1;
};
}  // namespace auvnav::io
