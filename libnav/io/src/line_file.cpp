#include <auvnav/io/line_file.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace auvnav::io
{
LineFile::LineFile(const std::string& path, std::size_t flush_at_bytes)
    : path_(path), flush_at_(flush_at_bytes)
{
	fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
	if (fd_ < 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
	buffer_.reserve(flush_at_ + 4096);
}

LineFile::LineFile(LineFile&& other) noexcept
{
	*this = std::move(other);
}

LineFile& LineFile::operator=(LineFile&& other) noexcept
{
	if (this == &other) return *this;
	close();
	fd_ = other.fd_;
	path_ = std::move(other.path_);
	buffer_ = std::move(other.buffer_);
	flush_at_ = other.flush_at_;
	lines_ = other.lines_;
	other.fd_ = -1;
	return *this;
}

LineFile::~LineFile()
{
	close();
}

void LineFile::close() noexcept
{
	if (fd_ < 0) return;
	try
	{
		flush();
	}
	catch (const std::exception&)
	{
		// A destructor cannot report; flush() explicitly to see the error.
	}
	::close(fd_);
	fd_ = -1;
}

void LineFile::line(std::string_view text)
{
	if (text.find('\n') != std::string_view::npos)
		throw std::invalid_argument(path_ + ": a line to write holds a newline");
	buffer_.append(text);
	buffer_.push_back('\n');
	++lines_;
	if (buffer_.size() >= flush_at_) flush();
}

void LineFile::flush()
{
	std::size_t done = 0;
	while (done < buffer_.size())
	{
		// One call for the whole buffer; another only after a short write
		// (a signal, a full disk), which then carries on from where it stopped.
		const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
		if (n < 0 && errno == EINTR) continue;
		if (n <= 0)
		{
			buffer_.erase(0, done);
			throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(n < 0 ? errno : ENOSPC));
		}
		done += static_cast<std::size_t>(n);
	}
	buffer_.clear();
}
}  // namespace auvnav::io
