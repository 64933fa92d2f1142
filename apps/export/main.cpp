// auvnav-export: a rawlog to one CSV file per sensor label (layout in
// docs/import.md) plus import.yaml, the spec that imports them back.
//
// Exit codes: 0 success, 1 usage error, 2 unreadable rawlog or unwritable output.
#include <auvnav/cli.h>
#include <auvnav/import/exporter.h>

#include <iostream>
#include <string>

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Writes every observation of a rawlog as CSV, one file per sensor label (IMU, GPS GGA, DVL, ADCP, "
	    "pressure, thrusters; images as PNG files), with 17-digit numbers and 100 ns times so that "
	    "auvnav-import --spec OUT/import.yaml gives the same rawlog back. Exit code: 0 ok, 1 usage error, "
	    "2 unreadable rawlog or unwritable output.",
	    ' ', AUVNAV_VERSION);
	TCLAP::ValueArg<std::string> out("", "out", "Folder to write (created).", true, "", "DIR", cmd);
	TCLAP::UnlabeledValueArg<std::string> rawlog("RAWLOG", "Rawlog to export.", true, "", "RAWLOG", cmd);
	const auvnav::cli::ObsLibOption obs_libs(cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-export")) return *code;
	if (const auto code = obs_libs.load("auvnav-export")) return *code;
	auvnav::import::ExportReport report;
	try
	{
		auvnav::import::exportRawlog(rawlog.getValue(), out.getValue(), report);
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-export", e.what());
	}
	if (report.sensors.empty())  // an empty log: nothing to export is not a success
		return auvnav::cli::fail("auvnav-export",
		                         rawlog.getValue() + ": no observations exported (an empty rawlog?)");
	std::cout << "auvnav-export: " << rawlog.getValue() << " -> " << out.getValue() << "\n";
	for (const auto& s : report.sensors)
		std::cout << "  " << s.label << " (" << s.observation_class << "): " << s.rows << " rows in "
		          << s.file << "\n";
	for (const auto& [reason, n] : report.skipped_by_reason)
		std::cout << "  skipped " << n << " × " << reason << "\n";
	std::cout << "  import spec: " << report.spec_file << "\n";
	return auvnav::cli::kExitOk;
}
