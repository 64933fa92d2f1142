// auvnav-calibrate-mag: hard- and soft-iron calibration of a magnetometer
// from a rotation segment of a rawlog (mag_fit.h), written as the
// magnetometer plugin's YAML keys.
//
// Exit codes: 0 success, 1 usage error, 2 unreadable rawlog, no readings
// under the label or unwritable output, 3 calibration refused (too few
// readings, not enough rotation, no ellipsoid, implausible result).
#include <auvnav/io/rawlog.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>

#include "mag_fit.h"

namespace
{
constexpr int kExitOk = 0;
constexpr int kExitUsage = 1;
constexpr int kExitInput = 2;
constexpr int kExitRefused = 3;

bool askedForHelpOrVersion(int argc, char** argv)
{
	for (int i = 1; i < argc; ++i)
	{
		const std::string a = argv[i];
		if (a == "-h" || a == "--help" || a == "--version") return true;
	}
	return false;
}

std::string join(const std::vector<std::string>& v)
{
	std::string s;
	for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
	return s.empty() ? "none" : s;
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Fits a magnetometer's hard-iron offset and soft-iron matrix (raw = hard_iron + soft_iron * field) "
	    "to the "
	    "readings of one sensor label (CObservationIMU IMU_MAG_X/Y/Z in gauss) taken while the vehicle or "
	    "sensor "
	    "turns through many orientations: an ellipsoid fit refined on the geometric residuals. Prints the "
	    "fit "
	    "residual and the coverage of orientations, and writes hard_iron_ut and soft_iron for the "
	    "magnetometer "
	    "plugin's configuration. Refuses (exit 3) a segment with too few readings or too little rotation: "
	    "turn "
	    "through roll and pitch as well as yaw. Exit code: 0 ok, 1 usage error, 2 unreadable rawlog / no "
	    "readings / "
	    "unwritable output, 3 calibration refused.",
	    ' ', AUVNAV_VERSION);
	TCLAP::ValueArg<std::string> out("", "out",
	                                 "YAML file to write (the plugin keys hard_iron_ut, soft_iron).", true,
	                                 "", "mag.yaml", cmd);
	TCLAP::ValueArg<std::string> label(
	    "", "label", "Sensor label of the magnetometer readings. Default: MAG.", false, "MAG", "LABEL", cmd);
	TCLAP::ValueArg<double> from(
	    "", "from", "Start of the rotation segment [s] after the label's first reading. Default: 0.", false,
	    0.0, "S", cmd);
	TCLAP::ValueArg<double> to(
	    "", "to", "End of the rotation segment [s] after the label's first reading. Default: the end.", false,
	    std::numeric_limits<double>::infinity(), "S", cmd);
	TCLAP::ValueArg<double> field(
	    "", "field-ut",
	    "Earth field strength at the site [uT] (the plugin's field_ut); the soft-iron matrix "
	    "is scaled so that the calibrated norm equals it. Default: not given, soft_iron gets "
	    "determinant 1 and the calibrated norm is reported.",
	    false, 0.0, "F", cmd);
	TCLAP::ValueArg<int> min_samples("", "min-samples", "Fewest readings accepted. Default: 100.", false, 100,
	                                 "N", cmd);
	TCLAP::ValueArg<double> min_spread(
	    "", "min-spread",
	    "Least rotation accepted: sqrt(smallest / largest eigenvalue) of the readings' "
	    "covariance, 1 for every orientation, ~0 for a turn about one axis. Default: 0.25.",
	    false, 0.25, "X", cmd);
	TCLAP::UnlabeledValueArg<std::string> rawlog("RAWLOG", "Rawlog with the rotation segment.", true, "",
	                                             "RAWLOG", cmd);
	if (!cmd.parse(argc, argv)) return askedForHelpOrVersion(argc, argv) ? kExitOk : kExitUsage;

	if (!(from.getValue() >= 0) || !(to.getValue() > from.getValue()))
	{
		std::cerr << "auvnav-calibrate-mag: error: need 0 <= --from < --to\n";
		return kExitUsage;
	}
	if (field.isSet() && !(field.getValue() >= 1 && field.getValue() <= 100))
	{
		std::cerr << "auvnav-calibrate-mag: error: --field-ut " << field.getValue()
		          << " is not an Earth field in uT (expected 1 .. 100; 1 G = 100 uT)\n";
		return kExitUsage;
	}
	if (min_samples.getValue() < 10 || !(min_spread.getValue() >= 0 && min_spread.getValue() <= 1))
	{
		std::cerr << "auvnav-calibrate-mag: error: need --min-samples >= 10 and --min-spread in [0, 1]\n";
		return kExitUsage;
	}

	auvnav::magcal::Samples s;
	try
	{
		s = auvnav::magcal::readSamples(rawlog.getValue(), label.getValue(), from.getValue(), to.getValue());
	}
	catch (const std::exception& e)
	{
		std::cerr << "auvnav-calibrate-mag: error: " << e.what() << "\n";
		return kExitInput;
	}
	if (s.raw_ut.empty())
	{
		std::cerr << "auvnav-calibrate-mag: error: no magnetometer readings (CObservationIMU with "
		             "IMU_MAG_X/Y/Z) labelled '"
		          << label.getValue() << "' in " << rawlog.getValue() << " between " << from.getValue()
		          << " and " << to.getValue() << " s (labels in the log: " << join(s.labels) << ")\n";
		return kExitInput;
	}
	std::cout << "auvnav-calibrate-mag: " << rawlog.getValue() << ", label " << label.getValue() << ": "
	          << s.raw_ut.size() << " readings from " << s.t_from_s << " to " << s.t_to_s << " s";
	if (s.unusable) std::cout << " (" << s.unusable << " unusable: missing or non-finite fields)";
	std::cout << "\n";

	auvnav::magcal::FitOptions opt;
	opt.field_ut = field.isSet() ? field.getValue() : 0.0;
	opt.min_samples = static_cast<std::size_t>(min_samples.getValue());
	opt.min_spread = min_spread.getValue();
	auvnav::magcal::FitResult r;
	try
	{
		r = auvnav::magcal::fit(s.raw_ut, opt);
	}
	catch (const auvnav::magcal::MagCalibrationError& e)
	{
		std::cerr << "auvnav-calibrate-mag: refused: " << e.what() << "\n";
		return kExitRefused;
	}
	std::printf("  hard iron   [%.3f, %.3f, %.3f] uT (1-sigma %.3f, %.3f, %.3f)\n", r.hard_iron_ut[0],
	            r.hard_iron_ut[1], r.hard_iron_ut[2], r.hard_iron_sigma_ut[0], r.hard_iron_sigma_ut[1],
	            r.hard_iron_sigma_ut[2]);
	for (int i = 0; i < 3; ++i)
		std::printf("  %s [%.6f, %.6f, %.6f]\n", i == 0 ? "soft iron" : "         ", r.soft_iron(i, 0),
		            r.soft_iron(i, 1), r.soft_iron(i, 2));
	std::printf("  calibrated norm %.3f uT%s\n", r.field_ut,
	            field.isSet() ? " (--field-ut)" : " (soft iron with determinant 1)");
	std::printf("  fit residual rms %.3f uT, max %.3f uT (%d iterations)\n", r.rms_residual_ut,
	            r.max_residual_ut, r.iterations);
	std::printf("  coverage %d/%d directions, spread %.3f\n", r.directions_covered, r.kDirections, r.spread);
	if (r.directions_covered < 8)
		std::cout << "  warning: fewer than 8 of 12 directions covered: the calibration extrapolates to "
		             "orientations "
		             "not seen\n";

	std::string source = "from " + rawlog.getValue() + ", label " + label.getValue() + ", " +
	                     std::to_string(s.t_from_s) + " .. " + std::to_string(s.t_to_s) +
	                     " s after its first reading";
	std::ofstream f(out.getValue());
	f << auvnav::magcal::pluginYaml(r, source);
	f.close();
	if (!f)
	{
		std::cerr << "auvnav-calibrate-mag: error: cannot write " << out.getValue() << "\n";
		return kExitInput;
	}
	std::cout << "  wrote " << out.getValue() << "\n";
	return kExitOk;
}
