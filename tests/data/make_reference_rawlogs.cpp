// Writes the reference rawlog for the *current* serialization version of the
// auvnav observation classes: one object of each class with the fixed values
// documented in tests/data/README.md.
//
//   auvnav_make_reference_rawlogs tests/data/obs_v<N>.rawlog
//
// Never run by the build or by CTest. A committed reference file is frozen: it
// proves that files recorded with that version stay readable, so this program
// refuses to overwrite an existing file. When a class gets a new serialization
// version, bump the file name in the README and generate a new file; the old
// one and its test stay.
//
// The values are duplicated on purpose in tests/obs/test_reference_rawlogs.cpp:
// the test must keep checking what the old file holds even if this program
// changes later.
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>

#include <cstdint>
#include <exception>
#include <filesystem>
#include <iostream>

using namespace auvnav::obs;

namespace
{
// 2023-11-14T22:13:20.1234567Z in MRPT ticks (100 ns since 1601-01-01), plus
// `offset_100ns`. Integer ticks keep the value exact (no double rounding).
mrpt::Clock::time_point referenceTime(int64_t offset_100ns)
{
	constexpr int64_t kT0Ticks = 133444736001234567;
	return mrpt::Clock::time_point(mrpt::Clock::duration(kT0Ticks + offset_100ns));
}

constexpr int64_t kQuarterSecond_100ns = 2500000;

CObservationDVL referenceDvl()
{
	CObservationDVL d;
	d.sensorLabel = "DVL";
	d.timestamp = referenceTime(0);
	d.sensorPose = mrpt::poses::CPose3D(0.75, -0.05, 0.32, 0.7853981633974483, 0.0, 0.0);
	d.velocity_s_mps = {1.25, -0.375, 0.0625};
	d.velocity_cov = {1e-4, 1e-5, -2e-6, 1e-5, 2e-4, 3e-6, -2e-6, 3e-6, 4e-4};
	d.bottom_lock = true;
	d.altitude_m = 12.75;
	d.beam_inclination_rad = 0.5235987755982988;
	d.beams = {{14.5, true, 0.625, 0.7853981633974483},
	           {14.25, true, -0.5, 2.356194490192345},
	           {15.125, true, 0.125, -2.356194490192345},
	           {0.0, false, 0.0, -0.7853981633974483}};
	// Version 1: coordinates and sign as reported (a Teledyne RDI in earth mode).
	d.frame = DvlFrame::EarthEnu;
	d.sign = DvlSign::BottomOverInstrument;
	d.beam_velocity_sigma_mps = 0.0075;
	return d;
}

CObservationADCP referenceAdcp()
{
	CObservationADCP a;
	a.sensorLabel = "ADCP";
	a.timestamp = referenceTime(kQuarterSecond_100ns);
	a.sensorPose = mrpt::poses::CPose3D(-0.5, 0.1, -0.2, -0.1, 0.05, 3.0);
	a.blank_distance_m = 0.5;
	a.cell_size_m = 1.25;
	a.velocity_sigma_mps = 0.02;
	a.cells = {{{0.1, -0.2, 0.05}, 0.95, true},
	           {{0.15, -0.25, -0.01}, 0.8, true},
	           {{-0.3, 0.4, 0.02}, 0.55, true},
	           {{0.0, 0.0, 0.0}, 0.1, false}};
	return a;
}

CObservationPressure referencePressure()
{
	CObservationPressure p;
	p.sensorLabel = "DEPTH";
	p.timestamp = referenceTime(2 * kQuarterSecond_100ns);
	p.sensorPose = mrpt::poses::CPose3D(1.2, -0.05, 0.1, 0.0, 0.0, 0.0);
	p.pressure_pa = 151650.25;
	p.temperature_c = 11.5;
	return p;
}

CObservationThrusters referenceThrusters()
{
	CObservationThrusters t;
	t.sensorLabel = "THRUSTERS";
	t.timestamp = referenceTime(3 * kQuarterSecond_100ns);
	t.unit = EffortUnit::Speed_rpm;
	t.effort = {1200.5, -1180.25, 300.0, 0.0, -45.5, 610.0};
	return t;
}
}  // namespace

int main(int argc, char** argv)
{
	if (argc != 2)
	{
		std::cerr << "usage: " << argv[0] << " OUTPUT.rawlog\n"
		          << "Writes the reference rawlog of the current observation versions.\n";
		return 1;
	}
	const std::filesystem::path out_path = argv[1];
	if (std::filesystem::exists(out_path))
	{
		std::cerr << out_path << " exists; reference rawlogs are never regenerated "
		          << "(see tests/data/README.md)\n";
		return 1;
	}
	try
	{
		// Maximum compression: the file is committed to the repository.
		auvnav::io::RawlogWriter writer(out_path.string(), 9);
		writer.write(referenceDvl());
		writer.write(referenceAdcp());
		writer.write(referencePressure());
		writer.write(referenceThrusters());
		std::cout << "wrote " << writer.count() << " observations to " << out_path << "\n";
	}
	catch (const std::exception& e)
	{
		std::cerr << "error: " << e.what() << "\n";
		return 1;
	}
	return 0;
}
