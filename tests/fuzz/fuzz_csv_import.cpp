// libFuzzer harness: the CSV importer (auvnav::import::runImport) on an
// arbitrary CSV file, through a fixed import spec.
//
// Input: byte 0 picks the variant: bit 0 lenient mode, bits 1-2 the time
// format of column t (s, ms, ns, iso8601); the rest is log.csv. Two sensors
// (an IMU and a pressure sensor) read the same file, so rows go through the
// reorder buffer of both. runImport must finish or throw ImportError; the
// rawlog it writes must read back (RawlogReader) without a refusal.
#include <auvnav/import/importer.h>
#include <auvnav/import/record.h>
#include <auvnav/io/rawlog.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "fuzz_support.h"

namespace fs = std::filesystem;
using namespace auvnav::import;

namespace
{
const char* kFormats[] = {"s", "ms", "ns", "iso8601"};

/** A scratch folder for this process (tmpfs when there is one). */
fs::path scratch()
{
	const fs::path base = fs::exists("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
	const fs::path dir = base / ("auvnav_fuzz_csv_" + std::to_string(::getpid()));
	fs::create_directories(dir);
	// Removed at exit (libFuzzer exits through exit() after a run and after
	// a finding), so that repeated runs leave nothing behind in /dev/shm.
	static const fs::path to_remove = dir;
	std::atexit(
	    []
	    {
		    std::error_code ec;
		    fs::remove_all(to_remove, ec);
	    });
	for (const char* f : kFormats)
	{
		std::ofstream spec(dir / (std::string("spec_") + f + ".yaml"));
		spec << "sensors:\n"
		        "  - label: IMU\n    class: imu\n    source: {csv: log.csv}\n"
		        "    time: {field: t, format: "
		     << f
		     << "}\n"
		        "    angular_velocity: {fields: [gx, gy, gz], unit: rad/s}\n"
		        "  - label: P\n    class: pressure\n    source: {csv: log.csv}\n"
		        "    time: {field: t, format: "
		     << f
		     << "}\n"
		        "    pressure: {field: p, unit: Pa}\n    pressure_reference: absolute\n";
	}
	return dir;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size)
{
	static const fs::path dir = scratch();
	if (size < 1) return 0;
	{
		std::ofstream csv(dir / "log.csv", std::ios::binary | std::ios::trunc);
		csv.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
	}
	ImportOptions opt;
	opt.spec_path = (dir / (std::string("spec_") + kFormats[(data[0] >> 1) & 3] + ".yaml")).string();
	opt.inputs = {dir.string()};
	opt.out_rawlog = (dir / "out.rawlog").string();
	opt.lenient = data[0] & 1;
	ImportReport report;
	try
	{
		runImport(opt, report);
	}
	catch (const ImportError&)
	{
		return 0;  // refused with a reason: an expected outcome
	}
	(void)report.toJson(), (void)report.toMarkdown(), (void)report.toTable();
	// What the importer wrote must read back whole.
	try
	{
		auvnav::io::RawlogReader reader(opt.out_rawlog);
		while (reader.next())
		{
		}
	}
	catch (const auvnav::io::RawlogError& e)
	{
		std::fprintf(stderr, "the importer wrote a rawlog it cannot read back: %s\n", e.what());
		std::abort();
	}
	return 0;
}
