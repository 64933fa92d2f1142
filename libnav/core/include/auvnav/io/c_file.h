#pragma once
/** @file c_file.h
 *  A C stdio stream owned by a std::unique_ptr, for the binary scratch files
 *  that want a FILE's buffering and fseeko (the smoother's stretch file and
 *  its reversed rows; text outputs use LineFile).
 *
 *  Contract: the stream is closed on every path out of its owner, a
 *  constructor that throws half way included (its members are destroyed),
 *  so an owning class needs neither a destructor nor a try/catch for it.
 *  Closing does not report errors: a writer that must know its data
 *  reached the kernel calls fflush first and checks it.
 */
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

namespace auvnav::io
{
struct CFileCloser
{
	void operator()(std::FILE* f) const noexcept { std::fclose(f); }
};
using CFile = std::unique_ptr<std::FILE, CFileCloser>;

/** fopen(path, mode), or std::runtime_error "<path>: <what> (<strerror>)". */
inline CFile openCFile(const std::string& path, const char* mode, const std::string& what)
{
	errno = 0;
	CFile f(std::fopen(path.c_str(), mode));
	if (!f)
		throw std::runtime_error(path + ": " + what +
		                         (errno ? std::string(" (") + std::strerror(errno) + ")" : ""));
	return f;
}
}  // namespace auvnav::io
