// elfNeededLibraries() (plugin_host.h): a plugin's DT_NEEDED entries, read
// before dlopen runs any of its code. Every read is bounded by the file's
// size; a non-ELF, truncated or inconsistent file is a PluginError naming it.
#include <auvnav/plugin_host.h>
#include <elf.h>

#include <algorithm>
#include <cstring>
#include <fstream>

namespace auvnav
{
namespace
{
/** Reads of one file, each checked against its size. */
class BoundedFile
{
 public:
	explicit BoundedFile(const std::string& path) : path_(path), in_(path, std::ios::binary)
	{
		if (!in_) fail("cannot open it to read its ELF headers");
		in_.seekg(0, std::ios::end);
		const std::streamoff end = in_.tellg();
		if (end < 0) fail("cannot read it");
		size_ = static_cast<uint64_t>(end);
	}

	uint64_t size() const { return size_; }

	/** Reads `n` bytes at `offset`; false if they are not all inside the file. */
	bool read(uint64_t offset, void* out, uint64_t n)
	{
		if (offset > size_ || n > size_ - offset) return false;
		in_.clear();
		in_.seekg(static_cast<std::streamoff>(offset));
		in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
		return in_ && static_cast<uint64_t>(in_.gcount()) == n;
	}

	/** The NUL-terminated string at `offset`, which must end before `limit`. */
	bool readString(uint64_t offset, uint64_t limit, std::string& out)
	{
		out.clear();
		char chunk[256];
		for (uint64_t at = offset; at < limit;)
		{
			const uint64_t n = std::min<uint64_t>(sizeof chunk, limit - at);
			if (!read(at, chunk, n)) return false;
			const void* nul = std::memchr(chunk, '\0', n);
			if (nul) return out.append(chunk, static_cast<const char*>(nul) - chunk), true;
			out.append(chunk, n);
			at += n;
		}
		return false;
	}

	[[noreturn]] void fail(const std::string& what) const { throw PluginError(path_ + ": " + what); }

 private:
	std::string path_;
	std::ifstream in_;
	uint64_t size_ = 0;
};

struct Elf64
{
	using Ehdr = Elf64_Ehdr;
	using Phdr = Elf64_Phdr;
	using Dyn = Elf64_Dyn;
};
struct Elf32
{
	using Ehdr = Elf32_Ehdr;
	using Phdr = Elf32_Phdr;
	using Dyn = Elf32_Dyn;
};

/** The program headers (the loader's view: section headers may be stripped). */
template <class T>
std::vector<typename T::Phdr> programHeaders(BoundedFile& f)
{
	typename T::Ehdr eh;
	if (!f.read(0, &eh, sizeof eh))
		f.fail("truncated ELF file (" + std::to_string(f.size()) + " bytes, no full ELF header)");
	if (eh.e_phnum == 0) f.fail("ELF file without program headers: not a shared library");
	if (eh.e_phentsize != sizeof(typename T::Phdr))
		f.fail("ELF program header size " + std::to_string(eh.e_phentsize) + " is not " +
		       std::to_string(sizeof(typename T::Phdr)));
	std::vector<typename T::Phdr> ph(eh.e_phnum);  // at most 65535 entries
	if (!f.read(eh.e_phoff, ph.data(), uint64_t(ph.size()) * sizeof(typename T::Phdr)))
		f.fail("truncated ELF file: program headers beyond its end");
	return ph;
}

/** The file offset of the virtual address `addr` and the end of the loaded
 *  segment's file bytes that hold it; false if no PT_LOAD segment holds it. */
template <class T>
bool fileOffsetOf(const std::vector<typename T::Phdr>& ph, uint64_t addr, uint64_t& offset, uint64_t& end)
{
	for (const auto& p : ph)
		if (p.p_type == PT_LOAD && addr >= p.p_vaddr && addr - p.p_vaddr < p.p_filesz)
		{
			offset = uint64_t(p.p_offset) + (addr - p.p_vaddr);
			end = uint64_t(p.p_offset) + p.p_filesz;
			return true;
		}
	return false;
}

template <class T>
std::vector<std::string> neededOf(BoundedFile& f)
{
	const auto ph = programHeaders<T>(f);
	const typename T::Phdr* dynamic = nullptr;
	for (const auto& p : ph)
		if (p.p_type == PT_DYNAMIC) dynamic = &p;
	if (!dynamic) return {};  // statically linked: needs nothing (dlopen says what it thinks of it)

	std::vector<typename T::Dyn> dyn(std::min<uint64_t>(dynamic->p_filesz, f.size()) /
	                                 sizeof(typename T::Dyn));
	if (!f.read(dynamic->p_offset, dyn.data(), uint64_t(dyn.size()) * sizeof(typename T::Dyn)))
		f.fail("truncated ELF file: dynamic section beyond its end");
	std::vector<uint64_t> needed;  // offsets into the string table
	uint64_t strtab = 0, strsz = 0;
	bool has_strtab = false;
	for (const auto& d : dyn)
	{
		if (d.d_tag == DT_NULL) break;
		if (d.d_tag == DT_NEEDED) needed.push_back(d.d_un.d_val);
		if (d.d_tag == DT_STRTAB) strtab = d.d_un.d_ptr, has_strtab = true;
		if (d.d_tag == DT_STRSZ) strsz = d.d_un.d_val;
	}
	if (needed.empty()) return {};
	uint64_t offset = 0, end = 0;
	if (!has_strtab || !fileOffsetOf<T>(ph, strtab, offset, end))
		f.fail("ELF dynamic section names libraries but has no string table in the file");
	if (strsz > 0 && strsz < end - offset) end = offset + strsz;
	std::vector<std::string> out;
	for (const uint64_t at : needed)
	{
		std::string name;
		if (at >= end - offset || !f.readString(offset + at, end, name))
			f.fail("truncated ELF file: a needed library's name lies outside its string table");
		out.push_back(name);
	}
	return out;
}

bool hostIsLittleEndian()
{
	const uint16_t one = 1;
	unsigned char first = 0;
	std::memcpy(&first, &one, 1);
	return first == 1;
}
}  // namespace

std::vector<std::string> elfNeededLibraries(const std::string& path)
{
	BoundedFile f(path);
	unsigned char ident[EI_NIDENT];
	if (!f.read(0, ident, sizeof ident) || std::memcmp(ident, ELFMAG, SELFMAG) != 0)
		f.fail("not an ELF shared library (no ELF header)");
	if (ident[EI_DATA] != (hostIsLittleEndian() ? ELFDATA2LSB : ELFDATA2MSB))
		f.fail("ELF file for another byte order than this machine's");
	if (ident[EI_CLASS] == ELFCLASS64) return neededOf<Elf64>(f);
	if (ident[EI_CLASS] == ELFCLASS32) return neededOf<Elf32>(f);
	f.fail("ELF file of unknown class " + std::to_string(ident[EI_CLASS]));
}

}  // namespace auvnav
