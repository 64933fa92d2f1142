// make_compass_rawlog OUT.rawlog [SECONDS] [HEADING_DEG] [LATITUDE_DEG]
//
// A small synthetic rawlog with the example's own observation class: a vehicle
// at rest at the surface with heading HEADING_DEG, seen by a perfect IMU at
// 100 Hz (label IMU: Earth rate and normal gravity at LATITUDE_DEG), a pressure
// sensor at 5 Hz (PRESSURE, 0.3 m below the centre of gravity, which floats
// 0.25 m deep) and the compass at 10 Hz (COMPASS: compass_example::
// CObservationCompass, zero declination). Built against the installed auvnav
// package (auvnav::nav for the Earth model and RawlogWriter, auvnav::obs for
// the pressure class) and libcompass_obs (the compass class): what a driver
// or converter that records your sensor into a rawlog looks like.
#include <auvnav/earth.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationPressure.h>
#include <mrpt/obs/CObservationIMU.h>

#include "CObservationCompass.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char** argv)
{
	if (argc < 2)
	{
		std::fprintf(stderr, "usage: %s OUT.rawlog [SECONDS] [HEADING_DEG] [LATITUDE_DEG]\n", argv[0]);
		return 1;
	}
	const double kDeg = M_PI / 180;
	const std::string out = argv[1];
	const double seconds = argc > 2 ? std::atof(argv[2]) : 20.0;
	const double heading = (argc > 3 ? std::atof(argv[3]) : 20.0) * kDeg;
	const double lat = (argc > 4 ? std::atof(argv[4]) : -12.975) * kDeg;
	try
	{
		const double g = auvnav::earth::normalGravity(lat, 0.0);
		const Eigen::Vector3d w_ie_n = auvnav::earth::earthRateNed(lat);
		const Eigen::Matrix3d R_nb = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
		const Eigen::Vector3d w_b = R_nb.transpose() * w_ie_n;
		const Eigen::Vector3d f_b = R_nb.transpose() * Eigen::Vector3d(0, 0, -g);
		const double sensor_depth_m = 0.25 + 0.3;
		const double t0 = 1492693200.0;

		auvnav::io::RawlogWriter writer(out);
		const long steps = std::lround(seconds * 100);
		for (long k = 0; k < steps; ++k)  // 10 ms ticks
		{
			const auto stamp = mrpt::Clock::fromDouble(t0 + 0.01 * k);
			auto imu = mrpt::obs::CObservationIMU::Create();
			imu->sensorLabel = "IMU";
			imu->timestamp = stamp;
			using namespace mrpt::obs;
			imu->set(IMU_WX, w_b.x());
			imu->set(IMU_WY, w_b.y());
			imu->set(IMU_WZ, w_b.z());
			imu->set(IMU_X_ACC, f_b.x());
			imu->set(IMU_Y_ACC, f_b.y());
			imu->set(IMU_Z_ACC, f_b.z());
			writer.write(*imu);
			if (k % 20 == 10)
			{
				auto p = auvnav::obs::CObservationPressure::Create();
				p->sensorLabel = "PRESSURE";
				p->timestamp = stamp;
				p->pressure_pa = 101325 + 1025 * g * sensor_depth_m;
				p->temperature_c = 27;
				p->sensorPose = mrpt::poses::CPose3D(0, 0, 0.3, 0, 0, 0);
				writer.write(*p);
			}
			if (k % 10 == 5)
			{
				auto c = compass_example::CObservationCompass::Create();
				c->sensorLabel = "COMPASS";
				c->timestamp = stamp;
				c->heading_rad = heading;
				writer.write(*c);
			}
		}
		std::printf("%s: %zu observations, %.1f s, heading %.1f deg\n", out.c_str(), writer.count(), seconds,
		            heading / kDeg);
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "make_compass_rawlog: error: %s\n", e.what());
		return 2;
	}
	return 0;
}
