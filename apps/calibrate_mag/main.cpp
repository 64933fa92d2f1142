// auvnav-calibrate-mag: hard- and soft-iron calibration of a magnetometer
// from a rotation segment of a rawlog (mag_fit.h), written as the
// magnetometer plugin's YAML keys.
//
// With --level, a horizontal-only fit for a vehicle that turns about the
// vertical (level_fit.h).
//
// Exit codes: 0 success, 1 usage error, 2 unreadable rawlog, no readings
// under the label or unwritable output, 3 calibration refused (too few
// readings, not enough rotation or heading coverage, no ellipsoid/ellipse,
// implausible result).
#include <auvnav/cli.h>
#include <auvnav/io/rawlog.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>

#include "level_fit.h"
#include "mag_fit.h"

namespace
{
using auvnav::cli::kExitOk;
using auvnav::cli::kExitUsage;
constexpr int kExitInput = auvnav::cli::kExitBadInput;
constexpr int kExitRefused = auvnav::cli::kExitNoResult;  // a fit the readings do not support

std::string join(const std::vector<std::string>& v)
{
	std::string s;
	for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
	return s.empty() ? "none" : s;
}

std::string num(double v)
{
	char b[32];
	std::snprintf(b, sizeof b, "%g", v);
	return b;
}

int writeYaml(const std::string& path, const std::string& text)
{
	std::ofstream f(path);
	f << text;
	f.close();
	if (!f)
	{
		std::cerr << "auvnav-calibrate-mag: error: cannot write " << path << "\n";
		return kExitInput;
	}
	std::cout << "  wrote " << path << "\n";
	return kExitOk;
}

void printFit(const auvnav::magcal::FitResult& r, bool field_given)
{
	std::printf("  hard iron   [%.3f, %.3f, %.3f] uT (1-sigma %.3f, %.3f, %.3f)\n", r.hard_iron_ut[0],
	            r.hard_iron_ut[1], r.hard_iron_ut[2], r.hard_iron_sigma_ut[0], r.hard_iron_sigma_ut[1],
	            r.hard_iron_sigma_ut[2]);
	for (int i = 0; i < 3; ++i)
		std::printf("  %s [%.6f, %.6f, %.6f]\n", i == 0 ? "soft iron" : "         ", r.soft_iron(i, 0),
		            r.soft_iron(i, 1), r.soft_iron(i, 2));
	std::printf("  calibrated norm %.3f uT%s\n", r.field_ut,
	            field_given ? " (--field-ut)" : " (soft iron with determinant 1)");
	std::printf("  fit residual rms %.3f uT, max %.3f uT (%d iterations)\n", r.rms_residual_ut,
	            r.max_residual_ut, r.iterations);
	std::printf("  coverage %d/%d directions, spread %.3f\n", r.directions_covered, r.kDirections, r.spread);
	if (r.directions_covered < 8)
		std::cout << "  warning: fewer than 8 of 12 directions covered: the calibration extrapolates to "
		             "orientations not seen\n";
}

void printLevelFit(const auvnav::magcal::LevelFitResult& r, bool field_given)
{
	std::printf(
	    "  hard iron   [%.3f, %.3f, %.3f] uT (1-sigma x/y %.3f, %.3f; z NOT DETERMINED by a level "
	    "turn, set by --hard-iron-z)\n",
	    r.hard_iron_ut[0], r.hard_iron_ut[1], r.hard_iron_ut[2], r.hard_iron_sigma_ut[0],
	    r.hard_iron_sigma_ut[1]);
	for (int i = 0; i < 3; ++i)
		std::printf("  %s [%.6f, %.6f, %.6f]%s\n", i == 0 ? "soft iron" : "         ", r.soft_iron(i, 0),
		            r.soft_iron(i, 1), r.soft_iron(i, 2), i == 2 ? "  (z row/column not determined)" : "");
	std::printf(
	    "  horizontal field %.3f uT%s; vertical %.3f +- %.3f uT, |B| %.3f uT, dip %.2f deg\n",
	    r.horizontal_field_ut,
	    field_given ? " (--field-ut x cos(--inclination-deg))" : " (2x2 soft iron with determinant 1)",
	    r.vertical_field_ut, r.vertical_field_sd_ut, std::hypot(r.horizontal_field_ut, r.vertical_field_ut),
	    std::atan2(r.vertical_field_ut, r.horizontal_field_ut) * 180 / M_PI);
	std::printf("  fit residual rms %.3f uT (%.2f deg of heading), max %.3f uT (%d iterations)\n",
	            r.rms_residual_ut, r.rms_residual_deg, r.max_residual_ut, r.iterations);
	std::printf("  heading coverage %.0f deg, tilt up to %.1f deg\n", r.heading_coverage_deg, r.max_tilt_deg);
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
	    "unwritable output, 3 calibration refused. "
	    "A vehicle that only turns about the vertical (most AUVs, every ROV) cannot give the 3-D fit: "
	    "--level fits the horizontal calibration instead (hard iron x/y and a 2x2 soft iron, each reading "
	    "levelled with the roll/pitch of the accelerometer readings labelled --accel-label), leaves the "
	    "vertical offset at --hard-iron-z and says it is not determined; it needs a turn covering "
	    "--min-heading-coverage-deg of heading. --level is not chosen automatically because its result "
	    "means something else (the vertical is not calibrated).",
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
	TCLAP::SwitchArg level(
	    "", "level",
	    "Level-turn fit: horizontal hard iron and 2x2 soft iron only (the vertical offset is not determined "
	    "by a turn about the vertical). The readings are levelled with the accelerometer (--accel-label).",
	    cmd);
	TCLAP::ValueArg<std::string> accel_label(
	    "", "accel-label",
	    "With --level: label of the IMU records whose accelerometer gives roll/pitch ('none': assume the "
	    "vehicle level). Default: IMU; if the log has none under it, the vehicle is assumed level.",
	    false, "IMU", "LABEL", cmd);
	TCLAP::ValueArg<double> tilt_window(
	    "", "tilt-window-s",
	    "With --level: the accelerometer is averaged over this window around each reading (vibration, "
	    "manoeuvring accelerations). Default: 1.",
	    false, 1.0, "S", cmd);
	TCLAP::ValueArg<double> hard_iron_z(
	    "", "hard-iron-z",
	    "With --level: the vertical hard-iron offset [uT] to write (not determined by a level turn; e.g. "
	    "from a bench calibration). Default: 0.",
	    false, 0.0, "UT", cmd);
	TCLAP::ValueArg<double> inclination(
	    "", "inclination-deg",
	    "With --level and --field-ut: the field's inclination (dip) [deg]; the calibrated horizontal field "
	    "is then field_ut * cos(inclination). Without both: 2x2 soft iron with determinant 1.",
	    false, 0.0, "DEG", cmd);
	TCLAP::ValueArg<double> min_coverage(
	    "", "min-heading-coverage-deg",
	    "With --level: least heading coverage accepted (360 minus the largest gap between the readings' "
	    "azimuths) [deg]. Default: 270.",
	    false, 270.0, "DEG", cmd);
	TCLAP::ValueArg<double> max_residual_deg(
	    "", "max-residual-deg",
	    "With --level: largest rms residual accepted, as heading degrees (rms / horizontal field). "
	    "Default: 10.",
	    false, 10.0, "DEG", cmd);
	TCLAP::UnlabeledValueArg<std::string> rawlog("RAWLOG", "Rawlog with the rotation segment.", true, "",
	                                             "RAWLOG", cmd);
	const auvnav::cli::ObsLibOption obs_libs(cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-calibrate-mag")) return *code;
	if (const auto code = obs_libs.load("auvnav-calibrate-mag")) return *code;

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

	if (level.getValue() && (!(tilt_window.getValue() > 0) || !std::isfinite(hard_iron_z.getValue()) ||
	                         !(min_coverage.getValue() >= 0 && min_coverage.getValue() <= 360) ||
	                         !(max_residual_deg.getValue() > 0) || (field.isSet() != inclination.isSet()) ||
	                         !(std::abs(inclination.getValue()) < 90)))
	{
		std::cerr << "auvnav-calibrate-mag: error: --level needs --tilt-window-s > 0, "
		             "--min-heading-coverage-deg in [0, 360], --max-residual-deg > 0, and --field-ut with "
		             "--inclination-deg "
		             "(|dip| < 90) or neither\n";
		return kExitUsage;
	}
	const bool levelling = level.getValue() && accel_label.getValue() != "none";

	auvnav::magcal::Samples s;
	try
	{
		s = auvnav::magcal::readSamples(rawlog.getValue(), label.getValue(), from.getValue(), to.getValue(),
		                                levelling ? accel_label.getValue() : "");
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-calibrate-mag", e.what());
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
	const std::string source = "from " + rawlog.getValue() + ", label " + label.getValue() + ", " +
	                           std::to_string(s.t_from_s) + " .. " + std::to_string(s.t_to_s) +
	                           " s after its first reading";

	if (level.getValue())
	{
		std::vector<Eigen::Vector3d> down_s =
		    auvnav::magcal::downFromAccel(s.t_s, s.accel, s.R_b_mag, tilt_window.getValue());
		std::string tilt_source;
		if (!down_s.empty())
			tilt_source = "levelled with the accelerometer of '" + accel_label.getValue() + "' (" +
			              std::to_string(s.accel.size()) + " readings, mean over " +
			              num(tilt_window.getValue()) + " s)";
		else
		{
			tilt_source = levelling ? "no accelerometer readings labelled '" + accel_label.getValue() +
			                              "': the vehicle is ASSUMED LEVEL (tilt not corrected)"
			                        : "--accel-label none: the vehicle is ASSUMED LEVEL (tilt not corrected)";
			down_s.assign(s.raw_ut.size(), s.R_b_mag.transpose() * Eigen::Vector3d::UnitZ());
		}
		std::cout << "  level turn: " << tilt_source << "\n";
		auvnav::magcal::LevelFitOptions lopt;
		lopt.horizontal_field_ut =
		    field.isSet() ? field.getValue() * std::cos(inclination.getValue() * M_PI / 180) : 0.0;
		lopt.hard_iron_z_ut = hard_iron_z.getValue();
		lopt.min_heading_coverage_deg = min_coverage.getValue();
		lopt.max_rms_residual_deg = max_residual_deg.getValue();
		lopt.min_samples = static_cast<std::size_t>(min_samples.getValue());
		auvnav::magcal::LevelFitResult r;
		try
		{
			r = auvnav::magcal::fitLevel(s.raw_ut, down_s, lopt);
		}
		catch (const auvnav::magcal::MagCalibrationError& e)
		{
			std::cerr << "auvnav-calibrate-mag: refused: " << e.what() << "\n";
			return kExitRefused;
		}
		printLevelFit(r, field.isSet());
		return writeYaml(out.getValue(), auvnav::magcal::pluginYamlLevel(r, source + "\n" + tilt_source));
	}

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
		const std::string why = e.what();
		std::cerr << "auvnav-calibrate-mag: refused: " << why << "\n";
		if (why.find("does not rotate enough") != std::string::npos)
			std::cerr << "  (a vehicle that only turns about the vertical: --level fits the horizontal "
			             "calibration)\n";
		return kExitRefused;
	}
	printFit(r, field.isSet());
	return writeYaml(out.getValue(), auvnav::magcal::pluginYaml(r, source));
}
