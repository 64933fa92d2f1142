#pragma once
/** @file csv_source.h
 *  A CSV file with a header row as a RecordSource (import/record.h).
 *
 *  Contract: the first line that is neither empty nor a `#` comment is the
 *  header (a UTF-8 byte-order mark is skipped); every later non-empty,
 *  non-comment line is one record whose values are Text (Missing for an empty
 *  cell). Cells are separated by `delimiter` (default ','); a cell may be
 *  double-quoted ("a,b", "" for a quote). CR-LF line ends are accepted. A row
 *  with another number of cells than the header is returned with `defect`
 *  set ("7 cells, the header has 5"), not thrown, so a lenient import can
 *  count it and go on. `where` is "file:line". Throws ImportError if the
 *  file cannot be opened, has no header, or repeats a column name.
 */
#include <auvnav/import/record.h>

#include <fstream>
#include <string>

namespace auvnav::import
{
class CsvSource final : public RecordSource
{
 public:
	explicit CsvSource(const std::string& path, char delimiter = ',');
	bool next(Record& out) override;
	std::string describe() const override { return path_; }
	const std::vector<std::string>& header() const { return header_; }

 private:
	bool readLine(std::string& line);
	static bool splitCells(const std::string& line, char delimiter, std::vector<std::string>& cells,
	                       std::vector<bool>& quoted);

	std::string path_;
	std::ifstream in_;
	char delimiter_;
	std::vector<std::string> header_;
	std::size_t line_no_ = 0;
	uint64_t layout_id_;
	std::vector<std::string> cells_;
	std::vector<bool> quoted_;
};

}  // namespace auvnav::import
