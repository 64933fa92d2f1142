// auvnav-import: vehicle logs (CSV files, ROS 1 / ROS 2 bags) to an MRPT
// rawlog, as an import spec says (docs/import.md, config/import/). Writes
// OUT.rawlog, and OUT.import.json / OUT.import.md (per sensor: rows read,
// written, rejected with reasons, time span, rate, gaps, clock jumps).
//
// Exit codes: 0 success, 1 usage error, 2 bad spec or input (one line on
// stderr naming file, line/message and field; the partial rawlog is removed,
// the report still written).
#include <auvnav/cli.h>
#include <auvnav/import/importer.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace
{
using auvnav::cli::kExitBadInput;
using auvnav::cli::kExitOk;

std::string withoutRawlogSuffix(const std::string& out)
{
	const std::string suffix = ".rawlog";
	if (out.size() > suffix.size() && out.compare(out.size() - suffix.size(), suffix.size(), suffix) == 0)
		return out.substr(0, out.size() - suffix.size());
	return out;
}

bool writeText(const std::string& path, const std::string& text)
{
	std::ofstream f(path);
	f << text;
	return static_cast<bool>(f);
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Converts vehicle logs (CSV files with a header row, ROS 1 bags, ROS 2 .db3 bags) into an MRPT "
	    "rawlog "
	    "for auvnav-run, as the import spec says: per sensor its label, source, fields, units, axes, time "
	    "column "
	    "and offset, mounting and observation class (docs/import.md; examples in config/import/). INPUT are "
	    "the "
	    "files or folders the spec's sources are looked up in. Observations are written in time order. A "
	    "report "
	    "OUT.import.json and OUT.import.md lists per sensor rows read, written, rejected (with reasons), "
	    "time "
	    "span, rate, gaps and clock jumps. Exit code: 0 ok, 1 usage error, 2 bad spec or input.",
	    ' ', AUVNAV_VERSION);
	TCLAP::ValueArg<std::string> spec("", "spec", "Import spec (YAML).", true, "", "SPEC.yaml", cmd);
	TCLAP::ValueArg<std::string> out("", "out", "Rawlog to write (required unless --check).", false, "",
	                                 "OUT.rawlog", cmd);
	TCLAP::SwitchArg lenient(
	    "", "lenient",
	    "Count unusable rows/messages (malformed, non-numeric, non-finite) by reason and go on, "
	    "instead of stopping at the first with an error.",
	    cmd);
	TCLAP::SwitchArg check("", "check",
	                       "Only validate the spec (keys, classes, units, formats); read no input, write "
	                       "nothing (--out is not needed).",
	                       cmd);
	TCLAP::UnlabeledMultiArg<std::string> inputs("INPUT", "Files or folders holding the spec's sources.",
	                                             false, "INPUT", cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-import")) return *code;

	if (check.getValue())
	{
		try
		{
			auvnav::import::validateSpec(spec.getValue());
			std::cout << "auvnav-import: " << spec.getValue() << ": spec is valid\n";
			return kExitOk;
		}
		catch (const std::exception& e)
		{
			return auvnav::cli::fail("auvnav-import", e.what());
		}
	}

	// TCLAP takes a misspelled option (--lenent) for an input path.
	for (const auto& in : inputs.getValue())
		if (in.size() > 1 && in[0] == '-')
			return auvnav::cli::fail("auvnav-import", "unknown option '" + in + "' (see --help)",
			                         auvnav::cli::kExitUsage);
	if (!out.isSet())
		return auvnav::cli::fail("auvnav-import",
		                         "--out OUT.rawlog is required (only --check runs without it)",
		                         auvnav::cli::kExitUsage);

	for (const auto& in : inputs.getValue())
		if (!std::filesystem::exists(in)) return auvnav::cli::fail("auvnav-import", "no input '" + in + "'");

	auvnav::import::ImportOptions opt;
	opt.spec_path = spec.getValue();
	opt.out_rawlog = out.getValue();
	opt.inputs = inputs.getValue();
	opt.lenient = lenient.getValue();
	auvnav::import::ImportReport report;
	const std::string report_base = withoutRawlogSuffix(opt.out_rawlog);
	int rc = kExitOk;
	try
	{
		auvnav::import::runImport(opt, report);
	}
	catch (const std::exception& e)
	{
		report.error = auvnav::oneLineReason(e.what());
		auvnav::cli::fail("auvnav-import", e.what());
		// A rawlog cut short by an error must not pass for the whole log; a
		// file the import never opened (an input, an earlier rawlog) is kept.
		if (report.output_created) std::remove(opt.out_rawlog.c_str());
		rc = kExitBadInput;
	}
	if (rc == kExitOk && report.written == 0)
	{
		// Every row rejected (--lenient) or no rows at all: not a rawlog to pass on.
		rc = auvnav::cli::fail("auvnav-import", "no observations written (rows read: see the report)");
		if (report.output_created) std::remove(opt.out_rawlog.c_str());
	}
	if (!report.sensors.empty())
	{
		const bool ok = writeText(report_base + ".import.json", report.toJson()) &&
		                writeText(report_base + ".import.md", report.toMarkdown());
		if (!ok)
		{
			std::cerr << "auvnav-import: error: cannot write the report " << report_base
			          << ".import.{json,md}\n";
			if (rc == kExitOk) rc = kExitBadInput;
		}
	}
	if (rc == kExitOk)
	{
		std::cout << "auvnav-import: " << report.written << " observations written to " << opt.out_rawlog
		          << "\n"
		          << report.toTable() << "  report: " << report_base << ".import.md, " << report_base
		          << ".import.json\n";
		std::size_t rejected = 0;
		for (const auto& s : report.sensors) rejected += s.rejected;
		if (rejected > 0) std::cout << "  " << rejected << " records rejected: reasons in the report\n";
	}
	return rc;
}
