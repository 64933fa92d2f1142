// make_custom_rawlog OUT.rawlog: 2 s of a stationary IMU at 100 Hz (label IMU)
// and a CObservationTestTag at 10 Hz (label TAG), for the --obs-lib tests.
#include <auvnav/io/rawlog.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cstdio>
#include <exception>

#include "CObservationTestTag.h"

int main(int argc, char** argv)
{
	if (argc != 2)
	{
		std::fprintf(stderr, "usage: %s OUT.rawlog\n", argv[0]);
		return 1;
	}
	try
	{
		auvnav::io::RawlogWriter writer(argv[1]);
		const double t0 = 1492693200.0;
		for (int k = 0; k < 200; ++k)
		{
			const auto stamp = mrpt::Clock::fromDouble(t0 + 0.01 * k);
			auto imu = mrpt::obs::CObservationIMU::Create();
			imu->sensorLabel = "IMU";
			imu->timestamp = stamp;
			using namespace mrpt::obs;
			for (const auto idx : {IMU_WX, IMU_WY, IMU_WZ, IMU_X_ACC, IMU_Y_ACC}) imu->set(idx, 0.0);
			imu->set(IMU_Z_ACC, -9.78);  // at rest, level
			writer.write(*imu);
			if (k % 10 == 5)
			{
				auto tag = auvnav_test::CObservationTestTag::Create();
				tag->sensorLabel = "TAG";
				tag->timestamp = stamp;
				tag->value = k;
				writer.write(*tag);
			}
		}
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "make_custom_rawlog: error: %s\n", e.what());
		return 2;
	}
	return 0;
}
