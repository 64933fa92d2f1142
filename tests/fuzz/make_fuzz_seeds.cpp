// Writes the seed corpus of the fuzz harnesses (tests/fuzz/corpus/<harness>/)
// from real objects: the observation classes as the writers serialise them,
// small rawlogs of both layouts (plain and gzip), observations for each
// plugin. Usage: make_fuzz_seeds <corpus dir>. Run by hand when a format
// changes; the output is committed (config and CSV seeds are copied by hand
// from config/ and the import tests).
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include "fuzz_support.h"

namespace fs = std::filesystem;
using namespace auvnav::obs;
using auvnav::fuzz::Bytes;
using auvnav::fuzz::writeObject;

namespace
{
const mrpt::Clock::time_point kT0 = mrpt::Clock::fromDouble(1700000000.25);

void save(const fs::path& p, const Bytes& b)
{
	fs::create_directories(p.parent_path());
	std::ofstream(p, std::ios::binary)
	    .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

/** The class's data only: version byte then body (the observation harness's input). */
Bytes body(const mrpt::serialization::CSerializable& o)
{
	const Bytes all = writeObject(o);
	const std::size_t name_len = all[0] & 0x7F;
	return Bytes(all.begin() + 1 + std::ptrdiff_t(name_len), all.end() - 1);
}

Bytes prefixed(uint8_t first, const Bytes& rest)
{
	Bytes b{first};
	b.insert(b.end(), rest.begin(), rest.end());
	return b;
}

Bytes fileBytes(const fs::path& p)
{
	std::ifstream f(p, std::ios::binary);
	return Bytes(std::istreambuf_iterator<char>(f), {});
}

CObservationDVL dvl(DvlFrame frame)
{
	CObservationDVL d;
	d.sensorLabel = "DVL";
	d.timestamp = kT0;
	d.sensorPose = mrpt::poses::CPose3D(0.659, -0.141, 0.206, -0.3927, 0, 0);
	d.velocity_s_mps = {1.0, 0.1, -0.02};
	d.velocity_cov = {1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4};
	d.bottom_lock = true;
	d.altitude_m = 10;
	d.beam_inclination_rad = 0.5236;
	d.frame = frame;
	d.beam_velocity_sigma_mps = frame == DvlFrame::Beam ? 0.01 : 0;
	for (int i = 0; i < 4; ++i) d.beams.push_back({11.5, true, 0.4 - 0.2 * i, 0.7854 + 1.5708 * i});
	return d;
}

CObservationADCP adcp()
{
	CObservationADCP a;
	a.sensorLabel = "ADCP";
	a.timestamp = kT0;
	a.sensorPose = mrpt::poses::CPose3D(0.5, 0, 0.3, 0, 0, 0);
	a.blank_distance_m = 0.5, a.cell_size_m = 1, a.velocity_sigma_mps = 0.02;
	a.cells = {{{0.1, -0.2, 0.0}, 0.9, true}, {{0.12, -0.18, 0.01}, 0.8, true}, {{0, 0, 0}, 0.1, false}};
	return a;
}

CObservationPressure pressure()
{
	CObservationPressure p;
	p.sensorLabel = "PRESSURE";
	p.timestamp = kT0;
	p.sensorPose = mrpt::poses::CPose3D(1.2, 0, 0.1, 0, 0, 0);
	p.pressure_pa = 151325, p.temperature_c = 10;
	return p;
}

CObservationThrusters thrusters()
{
	CObservationThrusters t;
	t.sensorLabel = "THRUSTERS";
	t.timestamp = kT0;
	t.unit = EffortUnit::Force_N;
	t.effort = {10, -10, 5, 5, 0, 0};
	return t;
}

CObservationUSBL usbl(UsblFrame frame)
{
	CObservationUSBL u;
	u.sensorLabel = "USBL";
	u.timestamp = kT0;
	u.measurement_time = kT0;
	u.sensorPose = mrpt::poses::CPose3D(0.4, 0, -0.3, 0, 0, 0);
	u.frame = frame;
	u.position = frame == UsblFrame::Geodetic ? std::array<double, 3>{53.1001, 8.8002, 20}
	                                          : std::array<double, 3>{11, -4, 20};
	u.covariance_ned_m2 = {4, 0, 0, 0, 4, 0, 0, 0, 1};
	u.slant_range_m = 25, u.transponder_id = 3;
	return u;
}

mrpt::obs::CObservationIMU imu()
{
	mrpt::obs::CObservationIMU m;
	m.sensorLabel = "IMU";
	m.timestamp = kT0;
	using namespace mrpt::obs;
	for (auto [i, v] : {std::pair{IMU_X_ACC, 0.01},
	                    {IMU_Y_ACC, -0.02},
	                    {IMU_Z_ACC, -9.81},
	                    {IMU_WX, 0.001},
	                    {IMU_WY, 0.0},
	                    {IMU_WZ, 0.01},
	                    {IMU_MAG_X, 0.2},
	                    {IMU_MAG_Y, 0.01},
	                    {IMU_MAG_Z, 0.45},
	                    {IMU_YAW, 0.3},
	                    {IMU_PITCH, 0.01},
	                    {IMU_ROLL, -0.02}})
		m.set(i, v);
	return m;
}

mrpt::obs::CObservationGPS gps()
{
	mrpt::obs::CObservationGPS g;
	g.sensorLabel = "GPS";
	g.timestamp = kT0;
	mrpt::obs::gnss::Message_NMEA_GGA gga;
	gga.fields.latitude_degrees = 53.1001;
	gga.fields.longitude_degrees = 8.8002;
	gga.fields.altitude_meters = 0.5;
	gga.fields.fix_quality = 1;
	gga.fields.satellitesUsed = 9;
	gga.fields.HDOP = 0.9;
	g.setMsg(gga);
	return g;
}

void writeRawlogs(const fs::path& dir)
{
	const std::vector<mrpt::obs::CObservation::Ptr> obs = {
	    std::make_shared<mrpt::obs::CObservationIMU>(imu()),
	    std::make_shared<CObservationDVL>(dvl(DvlFrame::Instrument)),
	    std::make_shared<CObservationPressure>(pressure()),
	    std::make_shared<CObservationADCP>(adcp()),
	    std::make_shared<CObservationThrusters>(thrusters()),
	    std::make_shared<CObservationUSBL>(usbl(UsblFrame::LocalNed)),
	    std::make_shared<mrpt::obs::CObservationGPS>(gps())};
	// Observation-only layout, as the objects' bytes: byte 0 even = the file as is.
	Bytes plain;
	for (const auto& o : obs)
	{
		const Bytes b = writeObject(*o);
		plain.insert(plain.end(), b.begin(), b.end());
	}
	save(dir / "plain_observations", prefixed(0, plain));
	// The same objects, gzip-compressed by the harness (byte 0 odd).
	save(dir / "gz_by_harness", prefixed(1, plain));
	// A gzip rawlog as RawlogWriter writes it, handed over as is.
	const fs::path tmp = fs::temp_directory_path() / "auvnav_seed.rawlog";
	{
		auvnav::io::RawlogWriter w(tmp.string());
		for (const auto& o : obs) w.write(*o);
	}
	save(dir / "gz_rawlog_writer", prefixed(0, fileBytes(tmp)));
	fs::remove(tmp);
	// The classic layout: CActionCollection / CSensoryFrame pairs.
	mrpt::obs::CSensoryFrame sf;
	sf.insert(obs[1]);
	sf.insert(obs[2]);
	mrpt::obs::CActionCollection acts;
	Bytes pairs = writeObject(acts);
	const Bytes sfb = writeObject(sf);
	pairs.insert(pairs.end(), sfb.begin(), sfb.end());
	save(dir / "sensory_frames", prefixed(0, pairs));
}
}  // namespace

int main(int argc, char** argv)
{
	if (argc != 2)
	{
		std::cerr << "usage: make_fuzz_seeds <corpus dir>\n";
		return 1;
	}
	const fs::path root = argv[1];
	save(root / "obs_dvl" / "v1_instrument", body(dvl(DvlFrame::Instrument)));
	save(root / "obs_dvl" / "v1_beam", body(dvl(DvlFrame::Beam)));
	{
		// Version 0 (no frame, sign, beam velocity): version byte 0, the
		// head of version 1, the beam count and per beam range + valid.
		const Bytes v1 = body(dvl(DvlFrame::Instrument));
		const std::size_t head = v1.size() - (4 * 25 + 4 + 8 + 2);  // beams, count, sigma, sign, frame
		Bytes v0(v1.begin(), v1.begin() + std::ptrdiff_t(head));
		v0[0] = 0;
		const uint32_t n = 4;
		v0.insert(v0.end(), reinterpret_cast<const uint8_t*>(&n), reinterpret_cast<const uint8_t*>(&n) + 4);
		for (int i = 0; i < 4; ++i)
		{
			const double r = 11.5;
			v0.insert(v0.end(), reinterpret_cast<const uint8_t*>(&r),
			          reinterpret_cast<const uint8_t*>(&r) + 8);
			v0.push_back(1);
		}
		save(root / "obs_dvl" / "v0", v0);
	}
	save(root / "obs_adcp" / "v0", body(adcp()));
	save(root / "obs_pressure" / "v0", body(pressure()));
	save(root / "obs_thrusters" / "v0", body(thrusters()));
	save(root / "obs_usbl" / "v0_local_ned", body(usbl(UsblFrame::LocalNed)));
	save(root / "obs_usbl" / "v0_geodetic", body(usbl(UsblFrame::Geodetic)));
	writeRawlogs(root / "rawlog");
	// Plugin index (fuzz_plugin_prepare.cpp's order) + the object it reads.
	const fs::path pp = root / "plugin_prepare";
	save(pp / "0_adcp", prefixed(0, writeObject(adcp())));
	save(pp / "1_ahrs", prefixed(1, writeObject(imu())));
	save(pp / "2_dvl", prefixed(2, writeObject(dvl(DvlFrame::Instrument))));
	save(pp / "2_dvl_beam", prefixed(2, writeObject(dvl(DvlFrame::Beam))));
	save(pp / "3_gps", prefixed(3, writeObject(gps())));
	save(pp / "4_inertial", prefixed(4, writeObject(imu())));
	save(pp / "5_magnetometer", prefixed(5, writeObject(imu())));
	save(pp / "6_model_aiding", prefixed(6, writeObject(thrusters())));
	save(pp / "7_pressure", prefixed(7, writeObject(pressure())));
	save(pp / "9_usbl", prefixed(9, writeObject(usbl(UsblFrame::LocalNed))));
	std::cout << "seeds written under " << root << "\n";
	return 0;
}
