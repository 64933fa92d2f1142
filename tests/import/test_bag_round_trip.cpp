// Round trips through ROS bags written here with the real libraries:
// auvnav-sim → (this test) ROS 1 bag / ROS 2 .db3 → auvnav-import → auvnav-run
// gives the same trajectory as auvnav-run on the simulator's rawlog. The IMU,
// pressure and GPS travel as sensor_msgs types; the DVL, ADCP and thrusters as
// message types that exist only in this test (their definitions are stored in
// the bags, so the importer must decode them from there).
#include <auvnav/import/importer.h>
#include <auvnav/import/time_format.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/testing/scratch_dir.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <unistd.h>
#include "bag_writers.h"

namespace fs = std::filesystem;
using auvnav::import::testing::CdrWriter;
using auvnav::import::testing::Ros1BagWriter;
using auvnav::import::testing::Ros2BagWriter;

// ------------------------------------------------------------ custom types
namespace auvnav_rt
{
struct Beam
{
	double range = 0;
	uint8_t valid = 0;
};
struct DvlReport
{
	std_msgs::Header header;
	boost::array<double, 3> velocity{};
	boost::array<double, 9> velocity_covariance{};
	uint8_t bottom_lock = 0;
	double altitude = 0;
	std::vector<Beam> beams;
};
struct Cell
{
	boost::array<double, 3> velocity{};
	double correlation = 0;
	uint8_t valid = 0;
};
struct AdcpProfile
{
	std_msgs::Header header;
	double blank_distance = 0, cell_size = 0, velocity_sigma = 0;
	std::vector<Cell> cells;
};
struct Efforts
{
	std_msgs::Header header;
	std::vector<double> effort;
};

const char* const kSep = "================================================================================\n";
const std::string kRos1Header =
    std::string(kSep) + "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
const std::string kRos2Header = std::string(kSep) +
                                "MSG: std_msgs/msg/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" +
                                kSep + "MSG: builtin_interfaces/msg/Time\nint32 sec\nuint32 nanosec\n";
const std::string kDvlBody =
    "float64[3] velocity        # sensor over the seabed, sensor frame [m/s]\n"
    "float64[9] velocity_covariance\nbool bottom_lock\nfloat64 altitude\nBeam[] beams\n";
const std::string kDvlRos1 =
    "Header header\n" + kDvlBody + kRos1Header + kSep + "MSG: auvnav_rt/Beam\nfloat64 range\nbool valid\n";
const std::string kDvlRos2 = "std_msgs/Header header\n" + kDvlBody + kRos2Header + kSep +
                             "MSG: auvnav_rt/msg/Beam\nfloat64 range\nbool valid\n";
const std::string kAdcpBody =
    "float64 blank_distance\nfloat64 cell_size\nfloat64 velocity_sigma\nCell[] cells\n";
const std::string kAdcpRos1 = "Header header\n" + kAdcpBody + kRos1Header + kSep +
                              "MSG: auvnav_rt/Cell\nfloat64[3] velocity\nfloat64 correlation\nbool valid\n";
const std::string kAdcpRos2 =
    "std_msgs/Header header\n" + kAdcpBody + kRos2Header + kSep +
    "MSG: auvnav_rt/msg/Cell\nfloat64[3] velocity\nfloat64 correlation\nbool valid\n";
const std::string kEffortsRos1 = "Header header\nfloat64[] effort\n" + kRos1Header;
const std::string kEffortsRos2 = "std_msgs/Header header\nfloat64[] effort\n" + kRos2Header;
}  // namespace auvnav_rt

#define AUVNAV_RT_TRAITS(Type, Name, Def)                                         \
	namespace ros::message_traits                                                 \
	{                                                                             \
	template <>                                                                   \
	struct DataType<auvnav_rt::Type>                                              \
	{                                                                             \
		static const char* value() { return Name; }                               \
		static const char* value(const auvnav_rt::Type&) { return value(); }      \
	};                                                                            \
	template <>                                                                   \
	struct MD5Sum<auvnav_rt::Type>                                                \
	{                                                                             \
		static const char* value() { return "00000000000000000000000000000000"; } \
		static const char* value(const auvnav_rt::Type&) { return value(); }      \
	};                                                                            \
	template <>                                                                   \
	struct Definition<auvnav_rt::Type>                                            \
	{                                                                             \
		static const char* value() { return Def.c_str(); }                        \
		static const char* value(const auvnav_rt::Type&) { return value(); }      \
	};                                                                            \
	template <>                                                                   \
	struct HasHeader<auvnav_rt::Type> : TrueType                                  \
	{                                                                             \
	};                                                                            \
	}
AUVNAV_RT_TRAITS(DvlReport, "auvnav_rt/DvlReport", auvnav_rt::kDvlRos1)
AUVNAV_RT_TRAITS(AdcpProfile, "auvnav_rt/AdcpProfile", auvnav_rt::kAdcpRos1)
AUVNAV_RT_TRAITS(Efforts, "auvnav_rt/Efforts", auvnav_rt::kEffortsRos1)

namespace ros::serialization
{
template <>
struct Serializer<auvnav_rt::Beam>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& s, T m)
	{
		s.next(m.range);
		s.next(m.valid);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
template <>
struct Serializer<auvnav_rt::DvlReport>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& s, T m)
	{
		s.next(m.header);
		s.next(m.velocity);
		s.next(m.velocity_covariance);
		s.next(m.bottom_lock);
		s.next(m.altitude);
		s.next(m.beams);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
template <>
struct Serializer<auvnav_rt::Cell>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& s, T m)
	{
		s.next(m.velocity);
		s.next(m.correlation);
		s.next(m.valid);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
template <>
struct Serializer<auvnav_rt::AdcpProfile>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& s, T m)
	{
		s.next(m.header);
		s.next(m.blank_distance);
		s.next(m.cell_size);
		s.next(m.velocity_sigma);
		s.next(m.cells);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
template <>
struct Serializer<auvnav_rt::Efforts>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& s, T m)
	{
		s.next(m.header);
		s.next(m.effort);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
}  // namespace ros::serialization

namespace
{
const std::string kSource = AUVNAV_SOURCE_DIR;
const std::string kBin = AUVNAV_BIN_DIR;

std::vector<uint8_t> cdr(const auvnav_rt::DvlReport& m)
{
	CdrWriter w;
	w.header(m.header);
	w.fixedArray(m.velocity);
	w.fixedArray(m.velocity_covariance);
	w.put<uint8_t>(m.bottom_lock);
	w.put<double>(m.altitude);
	w.sequenceLength(static_cast<uint32_t>(m.beams.size()));
	for (const auto& b : m.beams)
	{
		w.put<double>(b.range);
		w.put<uint8_t>(b.valid);
	}
	return w.bytes();
}
std::vector<uint8_t> cdr(const auvnav_rt::AdcpProfile& m)
{
	CdrWriter w;
	w.header(m.header);
	w.put<double>(m.blank_distance);
	w.put<double>(m.cell_size);
	w.put<double>(m.velocity_sigma);
	w.sequenceLength(static_cast<uint32_t>(m.cells.size()));
	for (const auto& c : m.cells)
	{
		w.fixedArray(c.velocity);
		w.put<double>(c.correlation);
		w.put<uint8_t>(c.valid);
	}
	return w.bytes();
}
std::vector<uint8_t> cdr(const auvnav_rt::Efforts& m)
{
	CdrWriter w;
	w.header(m.header);
	w.sequenceLength(static_cast<uint32_t>(m.effort.size()));
	for (double e : m.effort) w.put<double>(e);
	return w.bytes();
}

/** Receives every message of the rawlog, converted; writes to one bag kind. */
struct BagSink
{
	virtual ~BagSink() = default;
	virtual void imu(int64_t t, const sensor_msgs::Imu& m) = 0;
	virtual void pressure(int64_t t, const sensor_msgs::FluidPressure& m) = 0;
	virtual void gps(int64_t t, const sensor_msgs::NavSatFix& m) = 0;
	virtual void dvl(int64_t t, const auvnav_rt::DvlReport& m) = 0;
	virtual void adcp(int64_t t, const auvnav_rt::AdcpProfile& m) = 0;
	virtual void thrusters(int64_t t, const auvnav_rt::Efforts& m) = 0;
};

struct Ros1Sink final : BagSink
{
	explicit Ros1Sink(const std::string& p) : bag(p) {}
	Ros1BagWriter bag;
	void imu(int64_t t, const sensor_msgs::Imu& m) override { bag.write("/imu", t, m); }
	void pressure(int64_t t, const sensor_msgs::FluidPressure& m) override { bag.write("/pressure", t, m); }
	void gps(int64_t t, const sensor_msgs::NavSatFix& m) override { bag.write("/fix", t, m); }
	void dvl(int64_t t, const auvnav_rt::DvlReport& m) override { bag.write("/dvl", t, m); }
	void adcp(int64_t t, const auvnav_rt::AdcpProfile& m) override { bag.write("/adcp", t, m); }
	void thrusters(int64_t t, const auvnav_rt::Efforts& m) override { bag.write("/thrusters", t, m); }
};

struct Ros2Sink final : BagSink
{
	explicit Ros2Sink(const std::string& p) : bag(p)
	{
		bag.addTopic("/imu", "sensor_msgs/msg/Imu");
		bag.addTopic("/pressure", "sensor_msgs/msg/FluidPressure");
		bag.addTopic("/fix", "sensor_msgs/msg/NavSatFix");
		bag.addTopic("/dvl", "auvnav_rt/msg/DvlReport", auvnav_rt::kDvlRos2);
		bag.addTopic("/adcp", "auvnav_rt/msg/AdcpProfile", auvnav_rt::kAdcpRos2);
		bag.addTopic("/thrusters", "auvnav_rt/msg/Efforts", auvnav_rt::kEffortsRos2);
	}
	Ros2BagWriter bag;
	void imu(int64_t t, const sensor_msgs::Imu& m) override
	{
		bag.write("/imu", t, auvnav::import::testing::toRos2Cdr(m));
	}
	void pressure(int64_t t, const sensor_msgs::FluidPressure& m) override
	{
		bag.write("/pressure", t, auvnav::import::testing::toRos2Cdr(m));
	}
	void gps(int64_t t, const sensor_msgs::NavSatFix& m) override
	{
		bag.write("/fix", t, auvnav::import::testing::toRos2Cdr(m));
	}
	void dvl(int64_t t, const auvnav_rt::DvlReport& m) override { bag.write("/dvl", t, cdr(m)); }
	void adcp(int64_t t, const auvnav_rt::AdcpProfile& m) override { bag.write("/adcp", t, cdr(m)); }
	void thrusters(int64_t t, const auvnav_rt::Efforts& m) override { bag.write("/thrusters", t, cdr(m)); }
};

/** Every observation of the rawlog as a bag message stamped with its time. */
void rawlogToBag(const std::string& rawlog, BagSink& sink)
{
	using namespace mrpt::obs;
	auvnav::io::RawlogReader in(rawlog);
	while (auto o = in.next())
	{
		const int64_t t = auvnav::import::fromMrptTime(o->timestamp);
		std_msgs::Header h;
		h.stamp = auvnav::import::testing::toRosTime(t);
		if (const auto* imu = dynamic_cast<const CObservationIMU*>(o.get()))
		{
			sensor_msgs::Imu m;
			m.header = h;
			m.orientation_covariance[0] = -1;  // no orientation (REP 145)
			m.angular_velocity.x = imu->get(IMU_WX);
			m.angular_velocity.y = imu->get(IMU_WY);
			m.angular_velocity.z = imu->get(IMU_WZ);
			m.linear_acceleration.x = imu->get(IMU_X_ACC);
			m.linear_acceleration.y = imu->get(IMU_Y_ACC);
			m.linear_acceleration.z = imu->get(IMU_Z_ACC);
			sink.imu(t, m);
		}
		else if (const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(o.get()))
		{
			sensor_msgs::FluidPressure m;
			m.header = h;
			m.fluid_pressure = p->pressure_pa;
			sink.pressure(t, m);
		}
		else if (auto* g = dynamic_cast<CObservationGPS*>(o.get()))
		{
			const auto& f = g->getMsgByClass<gnss::Message_NMEA_GGA>().fields;
			sensor_msgs::NavSatFix m;
			m.header = h;
			m.status.status = f.fix_quality > 0 ? 0 : -1;
			m.latitude = f.latitude_degrees;
			m.longitude = f.longitude_degrees;
			m.altitude = f.altitude_meters + f.geoidal_distance;  // NavSatFix: above the ellipsoid
			sink.gps(t, m);
		}
		else if (const auto* d = dynamic_cast<const auvnav::obs::CObservationDVL*>(o.get()))
		{
			auvnav_rt::DvlReport m;
			m.header = h;
			for (int k = 0; k < 3; ++k) m.velocity[k] = d->velocity_s_mps[k];
			for (int k = 0; k < 9; ++k) m.velocity_covariance[k] = d->velocity_cov[k];
			m.bottom_lock = d->bottom_lock;
			m.altitude = d->altitude_m;
			for (const auto& b : d->beams) m.beams.push_back({b.range_m, static_cast<uint8_t>(b.valid)});
			sink.dvl(t, m);
		}
		else if (const auto* a = dynamic_cast<const auvnav::obs::CObservationADCP*>(o.get()))
		{
			auvnav_rt::AdcpProfile m;
			m.header = h;
			m.blank_distance = a->blank_distance_m;
			m.cell_size = a->cell_size_m;
			m.velocity_sigma = a->velocity_sigma_mps;
			for (const auto& c : a->cells)
			{
				auvnav_rt::Cell cell;
				for (int k = 0; k < 3; ++k) cell.velocity[k] = c.velocity_s_mps[k];
				cell.correlation = c.correlation;
				cell.valid = c.valid;
				m.cells.push_back(cell);
			}
			sink.adcp(t, m);
		}
		else if (const auto* th = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get()))
		{
			auvnav_rt::Efforts m;
			m.header = h;
			m.effort = th->effort;
			sink.thrusters(t, m);
		}
	}
}

/** The spec for these bags; `kind` is ros1 or ros2. Sensors in the
 *  simulator's order for equal stamps. */
std::string bagSpec(const std::string& kind, const std::string& bag)
{
	const std::string src = "source: {" + kind + ": '" + bag + "', topic: ";
	return "reorder_window_s: 1.0\nsensors:\n"
	       "  - {label: THRUSTERS, class: thrusters, " +
	       src +
	       "/thrusters}, time: {field: header.stamp},\n"
	       "     effort: {count: {field: 'effort[]'}, field: 'effort[{i}]', unit: N}}\n"
	       "  - {label: IMU, class: imu, " +
	       src +
	       "/imu}, time: {field: header.stamp}}\n"
	       "  - label: DVL\n    class: dvl\n    " +
	       src +
	       "/dvl}\n    time: {field: header.stamp}\n"
	       "    frame: instrument\n    sign: vehicle_over_bottom\n"
	       "    velocity: {fields: ['velocity[0]', 'velocity[1]', 'velocity[2]'], unit: m/s}\n"
	       "    velocity_covariance: {fields: ['velocity_covariance[0]', 'velocity_covariance[1]', "
	       "'velocity_covariance[2]',"
	       " 'velocity_covariance[3]', 'velocity_covariance[4]', 'velocity_covariance[5]', "
	       "'velocity_covariance[6]',"
	       " 'velocity_covariance[7]', 'velocity_covariance[8]'], unit: 'm^2/s^2'}\n"
	       "    bottom_lock: {field: bottom_lock}\n    altitude: {field: altitude, unit: m}\n"
	       "    beams: {count: {field: 'beams[]'}, range: {field: 'beams[{i}].range', unit: m}, valid: "
	       "{field: 'beams[{i}].valid'}}\n"
	       "  - label: ADCP\n    class: adcp\n    " +
	       src +
	       "/adcp}\n    time: {field: header.stamp}\n"
	       "    blank_distance: {field: blank_distance, unit: m}\n    cell_size: {field: cell_size, unit: "
	       "m}\n"
	       "    velocity_sigma: {field: velocity_sigma, unit: m/s}\n"
	       "    cells: {count: {field: 'cells[]'}, velocity: {fields: ['cells[{i}].velocity[0]', "
	       "'cells[{i}].velocity[1]',"
	       " 'cells[{i}].velocity[2]'], unit: m/s}, correlation: {field: 'cells[{i}].correlation'}, valid: "
	       "{field: 'cells[{i}].valid'}}\n"
	       "  - {label: PRESSURE, class: pressure, " +
	       src +
	       "/pressure}, time: {field: header.stamp}, pressure_reference: absolute}\n"
	       "  - {label: GPS, class: gps, " +
	       src + "/fix}, time: {field: header.stamp}, altitude_reference: ellipsoid}\n";
}

int run(const std::string& cmd, const fs::path& log)
{
	const int rc = std::system((cmd + " > " + log.string() + " 2>&1").c_str());
	return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string slurp(const fs::path& p)
{
	std::ifstream f(p);
	std::stringstream s;
	s << f.rdbuf();
	return s.str();
}

/** Simulates the short mission and runs the navigator on it, in a folder of
 *  its own per bag kind (CTest runs the two tests as parallel processes). */
auvnav::testing::ScratchDir simulated(const std::string& kind)
{
	auvnav::testing::ScratchDir d("bag_round_trip_" + kind);
	EXPECT_EQ(run(kBin + "/auvnav-sim " + kSource + "/tests/data/short_mission.yaml --seed 5 --out " +
	                  (d / "sim").string(),
	              d / "sim.log"),
	          0);
	EXPECT_EQ(run(kBin + "/auvnav-run --config " + kSource + "/config/flatfish.yaml --quiet --out " +
	                  (d / "run_original").string() + " " + (d / "sim" / "short_test.rawlog").string(),
	              d / "run_original.log"),
	          0);
	return d;
}

void checkBagRoundTrip(const std::string& kind)
{
	const auvnav::testing::ScratchDir d = simulated(kind);
	const std::string bag_name = kind == "ros1" ? "mission.bag" : "mission.db3";
	{
		std::unique_ptr<BagSink> sink;
		if (kind == "ros1")
			sink = std::make_unique<Ros1Sink>((d / bag_name).string());
		else
			sink = std::make_unique<Ros2Sink>((d / bag_name).string());
		rawlogToBag((d / "sim" / "short_test.rawlog").string(), *sink);
	}
	std::ofstream(d / (kind + ".yaml")) << bagSpec(kind, bag_name);
	const std::string out = (d / (kind + ".rawlog")).string();
	ASSERT_EQ(run(kBin + "/auvnav-import --spec " + (d / (kind + ".yaml")).string() + " --out " + out + " " +
	                  (d / bag_name).string(),
	              d / (kind + "_import.log")),
	          0)
	    << slurp(d / (kind + "_import.log"));
	ASSERT_EQ(run(kBin + "/auvnav-run --config " + kSource + "/config/flatfish.yaml --quiet --out " +
	                  (d / ("run_" + kind)).string() + " " + out,
	              d / ("run_" + kind + ".log")),
	          0)
	    << slurp(d / ("run_" + kind + ".log"));
	const std::string a = slurp(d / "run_original" / "trajectory.tum");
	const std::string b = slurp(d / ("run_" + kind) / "trajectory.tum");
	EXPECT_GT(a.size(), 10000u);
	EXPECT_TRUE(a == b) << "trajectories differ (" << kind << ")";
	EXPECT_TRUE(slurp(d / "run_original" / "states.csv") == slurp(d / ("run_" + kind) / "states.csv"));
}
}  // namespace

TEST(ImportBagRoundTrip, Ros1BagGivesTheSameTrajectory)
{
	checkBagRoundTrip("ros1");
}
TEST(ImportBagRoundTrip, Ros2BagGivesTheSameTrajectory)
{
	checkBagRoundTrip("ros2");
}

// ---------------------------------------------------------------- bad bag input

namespace
{
std::string importError(const fs::path& dir, const std::string& spec, const std::string& input)
{
	std::ofstream(dir / "spec.yaml") << spec;
	auvnav::import::ImportOptions opt;
	opt.spec_path = (dir / "spec.yaml").string();
	opt.inputs = {input};
	opt.out_rawlog = (dir / "out.rawlog").string();
	auvnav::import::ImportReport rep;
	try
	{
		auvnav::import::runImport(opt, rep);
	}
	catch (const auvnav::import::ImportError& e)
	{
		return e.what();
	}
	return "";
}

auvnav::testing::ScratchDir smallBags(const std::string& name)
{
	auvnav::testing::ScratchDir d(name);
	{
		Ros1BagWriter bag((d / "small.bag").string());
		Ros2BagWriter db((d / "small.db3").string());
		db.addTopic("/imu", "sensor_msgs/msg/Imu");
		for (int i = 0; i < 2000; ++i)
		{
			sensor_msgs::Imu m;
			m.header.stamp = auvnav::import::testing::toRosTime(1000000000000LL + i * 10000000LL);
			m.linear_acceleration.z = -9.8;
			bag.write("/imu", 1000000000000LL + i * 10000000LL, m);
			db.write("/imu", 1000000000000LL + i * 10000000LL, auvnav::import::testing::toRos2Cdr(m));
		}
	}
	return d;
}
}  // namespace

TEST(ImportBagBadInput, TopicNotInTheBagNamesTheTopicsItHas)
{
	const auto d = smallBags("bag_bad_topic");
	for (const std::string kind : {"ros1", "ros2"})
	{
		const std::string bag = kind == "ros1" ? "small.bag" : "small.db3";
		const std::string err = importError(d.path(),
		                                    "sensors:\n  - {label: IMU, class: imu, source: {" + kind + ": " +
		                                        bag + ", topic: /imu/data}, time: {field: header.stamp}}\n",
		                                    (d / bag).string());
		EXPECT_THAT(err, ::testing::HasSubstr(bag)) << kind;
		EXPECT_THAT(err, ::testing::HasSubstr("/imu/data")) << kind;
		EXPECT_THAT(err, ::testing::HasSubstr("/imu (sensor_msgs")) << kind << ": " << err;
		// The right topic imports.
		EXPECT_EQ(importError(d.path(),
		                      "sensors:\n  - {label: IMU, class: imu, source: {" + kind + ": " + bag +
		                          ", topic: /imu}, time: {field: header.stamp}}\n",
		                      (d / bag).string()),
		          "")
		    << kind;
	}
}

TEST(ImportBag, OptionalSensorWithoutItsTopicIsAbsent)
{
	// A vehicle without GPS or magnetometer: the shipped ROS spec imports
	// its bag and says which optional topics were not there.
	auvnav::testing::ScratchDir d("bag_no_gps");
	{
		Ros1BagWriter bag((d / "vehicle.bag").string());
		for (int i = 0; i < 500; ++i)
		{
			const auvnav::import::TimeNs t = 1000000000000LL + i * 10000000LL;
			sensor_msgs::Imu imu;
			imu.header.stamp = auvnav::import::testing::toRosTime(t);
			imu.linear_acceleration.z = -9.8;
			bag.write("/imu/data", t, imu);
			if (i % 10 != 0) continue;
			sensor_msgs::FluidPressure p;
			p.header.stamp = imu.header.stamp;
			p.fluid_pressure = 150000;
			bag.write("/pressure", t, p);
			geometry_msgs::TwistWithCovarianceStamped v;
			v.header.stamp = imu.header.stamp;
			bag.write("/dvl/twist", t, v);
		}
	}
	auvnav::import::ImportOptions opt;
	opt.spec_path = kSource + "/config/import/ros_standard.yaml";
	opt.inputs = {d.path().string()};
	opt.out_rawlog = (d / "out.rawlog").string();
	auvnav::import::ImportReport rep;
	ASSERT_NO_THROW(auvnav::import::runImport(opt, rep));
	EXPECT_EQ(rep.written, 500u + 50u + 50u);
	std::map<std::string, std::string> source;
	for (const auto& s : rep.sensors) source[s.label] = s.source;
	EXPECT_THAT(source["GPS"], ::testing::HasSubstr("optional, topic /gps/fix not in"));
	EXPECT_THAT(source["MAG"], ::testing::HasSubstr("optional, topic /imu/mag not in"));
	EXPECT_THAT(rep.toMarkdown(), ::testing::HasSubstr("topic /gps/fix not in"));
	// A required sensor's missing topic still stops the import.
	std::ofstream(d / "no_dvl_optional.yaml")
	    << "sensors:\n  - {label: DVL, class: dvl, source: {ros1: '*.bag', "
	       "topic: /dvl/data}, time: {field: header.stamp}}\n";
	opt.spec_path = (d / "no_dvl_optional.yaml").string();
	EXPECT_THROW(auvnav::import::runImport(opt, rep), auvnav::import::ImportError);
}

TEST(ImportBagBadInput, TruncatedBagIsAClearError)
{
	const auto d = smallBags("bag_truncated");
	for (const std::string bag : {"small.bag", "small.db3"})
	{
		const std::string cut = "cut_" + bag;
		fs::copy_file(d / bag, d / cut, fs::copy_options::overwrite_existing);
		fs::resize_file(d / cut, fs::file_size(d / bag) / 2);
		const std::string kind = bag == "small.bag" ? "ros1" : "ros2";
		const std::string err = importError(d.path(),
		                                    "sensors:\n  - {label: IMU, class: imu, source: {" + kind + ": " +
		                                        cut + ", topic: /imu}, time: {field: header.stamp}}\n",
		                                    (d / cut).string());
		EXPECT_THAT(err, ::testing::HasSubstr(cut)) << err;
		EXPECT_THAT(err, ::testing::HasSubstr("truncated"));
		std::printf("%s: %s\n", cut.c_str(), err.c_str());
	}
}
