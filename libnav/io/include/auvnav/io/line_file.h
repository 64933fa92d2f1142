#pragma once
/** @file line_file.h
 *  An output text file that only ever holds whole lines, for auvnav-run's
 *  CSV and TUM outputs: a run killed at any moment (kill -9 included)
 *  leaves every file ending in a complete line.
 *
 *  Why not std::ofstream: its buffer goes to the file whenever it fills,
 *  which is in the middle of a line (a states.csv row is ~1.5 kB), and a
 *  killed process leaves that half line behind.
 *
 *  Contract:
 *   - line(text) appends `text` and a '\n'; `text` must not hold a '\n'
 *     (std::invalid_argument), so a line is one record;
 *   - the buffer holds only whole lines and is handed to the kernel with one
 *     write(2) per flush (and at `flush_at_bytes`); once write() returns, the
 *     lines survive the process being killed. Linux can cut a write(2) short
 *     only if the process is killed during that very call while it copies
 *     a buffer spanning several pages (a window of microseconds per flush);
 *   - flush() and the destructor write what is buffered; a write error
 *     throws std::runtime_error naming the file (the destructor swallows it).
 */
#include <cstddef>
#include <string>
#include <string_view>

namespace auvnav::io
{
class LineFile
{
 public:
	LineFile() = default;
	/** Creates (truncates) `path`; throws std::runtime_error naming it. */
	explicit LineFile(const std::string& path, std::size_t flush_at_bytes = 64 * 1024);
	LineFile(LineFile&& other) noexcept;
	LineFile& operator=(LineFile&& other) noexcept;
	LineFile(const LineFile&) = delete;
	LineFile& operator=(const LineFile&) = delete;
	~LineFile();

	bool isOpen() const { return fd_ >= 0; }
	const std::string& path() const { return path_; }
	/** Appends one line (see the file comment). */
	void line(std::string_view text);
	/** Writes the buffered lines with one write(2). */
	void flush();
	/** Lines appended since opened. */
	std::size_t lines() const { return lines_; }

 private:
	void close() noexcept;

	int fd_ = -1;
	std::string path_;
	std::string buffer_;
	std::size_t flush_at_ = 64 * 1024;
	std::size_t lines_ = 0;
};
}  // namespace auvnav::io
