// The importer's parts (units, times, CSV) and runImport end to end on small
// CSV files written here: every class, axes, units, time ordering, the
// report, and every bad-input case with its message.
#include <auvnav/import/csv_source.h>
#include <auvnav/import/exporter.h>
#include <auvnav/import/importer.h>
#include <auvnav/import/time_format.h>
#include <auvnav/import/units.h>
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
#include <mrpt/obs/CObservationImage.h>

#include <opencv2/core.hpp>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace auvnav::import;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace
{
fs::path scratch(const std::string& name)
{
	return auvnav::testing::scratchFolder("import_test", name);
}

void write(const fs::path& p, const std::string& text)
{
	std::ofstream f(p);
	f << text;
}

std::vector<mrpt::obs::CObservation::Ptr> readAll(const std::string& rawlog)
{
	auvnav::io::RawlogReader r(rawlog);
	std::vector<mrpt::obs::CObservation::Ptr> out;
	while (auto o = r.next()) out.push_back(o);
	return out;
}

/** Runs an import of `spec_text` over folder `dir`; returns the error text ("" if none). */
std::string importError(const fs::path& dir, const std::string& spec_text, ImportReport& report,
                        bool lenient = false)
{
	write(dir / "spec.yaml", spec_text);
	ImportOptions opt;
	opt.spec_path = (dir / "spec.yaml").string();
	opt.inputs = {dir.string()};
	opt.out_rawlog = (dir / "out.rawlog").string();
	opt.lenient = lenient;
	try
	{
		runImport(opt, report);
	}
	catch (const ImportError& e)
	{
		return e.what();
	}
	return "";
}

const char* kImuSpec = R"(
sensors:
  - label: IMU
    class: imu
    source: {csv: imu.csv}
    time: {field: t, format: s}
    angular_velocity: {fields: [gx, gy, gz], unit: deg/s}
    linear_acceleration: {fields: [ax, ay, az], unit: g}
    axes: [x, -y, -z]
)";
}  // namespace

// ---------------------------------------------------------------- units

TEST(ImportUnits, ConvertsToSi)
{
	EXPECT_DOUBLE_EQ(unitFor("deg/s", UnitKind::AngularRate, "q").toSi(180), M_PI);
	EXPECT_DOUBLE_EQ(unitFor("g", UnitKind::Acceleration, "q").toSi(1), 9.80665);
	EXPECT_DOUBLE_EQ(unitFor("mm/s", UnitKind::Velocity, "q").toSi(250), 0.25);
	EXPECT_DOUBLE_EQ(unitFor("kPa", UnitKind::Pressure, "q").toSi(101.325), 101325);
	EXPECT_DOUBLE_EQ(unitFor("bar", UnitKind::Pressure, "q").toSi(1), 1e5);
	EXPECT_DOUBLE_EQ(unitFor("dbar", UnitKind::Pressure, "q").toSi(1), 1e4);
	EXPECT_NEAR(unitFor("psi", UnitKind::Pressure, "q").toSi(14.6959488), 101325, 1e-3);
	EXPECT_DOUBLE_EQ(unitFor("uT", UnitKind::MagneticField, "q").toSi(46), 46e-6);
	EXPECT_DOUBLE_EQ(unitFor("Gauss", UnitKind::MagneticField, "q").toSi(0.46), 46e-6);
	EXPECT_DOUBLE_EQ(unitFor("T", UnitKind::MagneticField, "q").toSi(1), 1);
	EXPECT_DOUBLE_EQ(unitFor("K", UnitKind::Temperature, "q").toSi(273.15), 0);
	EXPECT_DOUBLE_EQ(unitFor("m", UnitKind::Length, "q").toSi(3), 3);
}

TEST(ImportUnits, RefusesUnknownAndWrongKind)
{
	try
	{
		unitFor("deg", UnitKind::AngularRate, "s.yaml: sensors[0].angular_velocity");
		FAIL();
	}
	catch (const ImportError& e)
	{
		EXPECT_THAT(e.what(), HasSubstr("s.yaml: sensors[0].angular_velocity: unit 'deg' is an angle"));
		EXPECT_THAT(e.what(), HasSubstr("rad/s, deg/s, deg/h"));
	}
	try
	{
		unitFor("furlong/s", UnitKind::Velocity, "q");
		FAIL();
	}
	catch (const ImportError& e)
	{
		EXPECT_THAT(e.what(), HasSubstr("unknown unit 'furlong/s'"));
	}
}

// ---------------------------------------------------------------- times

TEST(ImportTime, ParsesExactly)
{
	std::string why;
	EXPECT_EQ(*parseTime("1453606148.457768", TimeFormat::Seconds, why), 1453606148457768000LL);
	EXPECT_EQ(*parseTime("1453606148457.768", TimeFormat::Milliseconds, why), 1453606148457768000LL);
	EXPECT_EQ(*parseTime("1453606148457768", TimeFormat::Microseconds, why), 1453606148457768000LL);
	EXPECT_EQ(*parseTime("1453606148457768123", TimeFormat::Nanoseconds, why), 1453606148457768123LL);
	EXPECT_EQ(*parseTime("1.453606148457768e9", TimeFormat::Seconds, why), 1453606148457768000LL);
	EXPECT_EQ(*parseTime("-0.5", TimeFormat::Seconds, why), -500000000LL);
	EXPECT_EQ(*parseTime("2016-01-24T03:29:08.457768Z", TimeFormat::Iso8601, why), 1453606148457768000LL);
	EXPECT_EQ(*parseTime("2016-01-23T22:29:08.457768-05:00", TimeFormat::Iso8601, why),
	          1453606148457768000LL);
	EXPECT_EQ(*parseTime("1970-01-01 00:00:01", TimeFormat::Iso8601, why), 1000000000LL);
	EXPECT_FALSE(parseTime("12:00", TimeFormat::Seconds, why));
	EXPECT_FALSE(parseTime("", TimeFormat::Seconds, why));
	EXPECT_FALSE(parseTime("1e30", TimeFormat::Seconds, why));
	EXPECT_EQ(why, "out of range");
	EXPECT_FALSE(parseTime("2016-13-01T00:00:00Z", TimeFormat::Iso8601, why));
}

TEST(ImportTime, SevenDecimalsRoundTripOnTheMrptGrid)
{
	std::string why;
	for (TimeNs t : {1492693200123456700LL, 0LL, -250000000LL, 1700000000000000100LL})
	{
		EXPECT_EQ(*parseTime(formatSeconds7(t), TimeFormat::Seconds, why), t) << formatSeconds7(t);
		EXPECT_EQ(fromMrptTime(toMrptTime(t)), t);
	}
	EXPECT_EQ(formatSeconds7(-250000000LL), "-0.2500000");
	// MRPT's own conversion agrees at the second.
	EXPECT_EQ(mrpt::Clock::toDouble(toMrptTime(1453606148000000000LL)), 1453606148.0);
}

// ---------------------------------------------------------------- CSV

TEST(ImportCsv, ReadsHeaderQuotesAndFlagsBadRows)
{
	const auto dir = scratch("csv");
	write(dir / "a.csv", "\xEF\xBB\xBF# comment\nt,name, v \r\n1,\"a,b\",2\n\n2,,3\n3,x\n");
	CsvSource src((dir / "a.csv").string());
	EXPECT_EQ(src.header(), (std::vector<std::string>{"t", "name", "v"}));
	Record r;
	ASSERT_TRUE(src.next(r));
	EXPECT_TRUE(r.defect.empty());
	EXPECT_EQ(r.values[1].text, "a,b");
	EXPECT_THAT(r.where, HasSubstr("a.csv:3"));
	ASSERT_TRUE(src.next(r));
	EXPECT_EQ(r.values[1].kind, Value::Kind::Missing);
	ASSERT_TRUE(src.next(r));
	EXPECT_EQ(r.defect, "2 cells, the header has 3");
	EXPECT_THAT(r.where, HasSubstr("a.csv:6"));
	EXPECT_FALSE(src.next(r));
	EXPECT_THROW(CsvSource((dir / "none.csv").string()), ImportError);
	write(dir / "dup.csv", "t,t\n");
	try
	{
		CsvSource s((dir / "dup.csv").string());
		FAIL();
	}
	catch (const ImportError& e)
	{
		EXPECT_THAT(e.what(), HasSubstr("column 't' appears twice"));
	}
}

// ---------------------------------------------------------------- classes

TEST(Import, ImuUnitsAxesAndOrder)
{
	const auto dir = scratch("imu");
	write(dir / "imu.csv", "t,gx,gy,gz,ax,ay,az\n10.0,1,2,3,0,0,1\n10.01,180,0,0,0.5,0,0\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, kImuSpec, rep), "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 2u);
	const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(obs[0].get());
	ASSERT_NE(imu, nullptr);
	EXPECT_EQ(imu->sensorLabel, "IMU");
	using namespace mrpt::obs;
	EXPECT_NEAR(imu->get(IMU_WX), 1 * M_PI / 180, 1e-15);
	EXPECT_NEAR(imu->get(IMU_WY), -2 * M_PI / 180, 1e-15);
	EXPECT_NEAR(imu->get(IMU_WZ), -3 * M_PI / 180, 1e-15);
	EXPECT_NEAR(imu->get(IMU_Z_ACC), -9.80665, 1e-12);
	EXPECT_FALSE(imu->has(IMU_MAG_X));
	EXPECT_EQ(fromMrptTime(obs[1]->timestamp), 10010000000LL);
	EXPECT_EQ(rep.sensors[0].written, 2u);
	EXPECT_NEAR(rep.sensors[0].median_rate_hz, 100, 1e-6);
}

TEST(Import, MagnetometerInGaussAsMrptDocuments)
{
	const auto dir = scratch("mag");
	write(dir / "mag.csv", "t,mx,my,mz\n1,15.5,13.4,-40.8\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, R"(
sensors:
  - {label: MAG, class: imu, source: {csv: mag.csv}, time: {field: t, format: s},
     magnetic_field: {fields: [mx, my, mz], unit: uT}, axes: [x, -y, -z]}
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(obs.at(0).get());
	ASSERT_NE(imu, nullptr);
	EXPECT_NEAR(imu->get(mrpt::obs::IMU_MAG_X), 0.155, 1e-12);
	EXPECT_NEAR(imu->get(mrpt::obs::IMU_MAG_Y), -0.134, 1e-12);
	EXPECT_NEAR(imu->get(mrpt::obs::IMU_MAG_Z), 0.408, 1e-12);
	EXPECT_FALSE(imu->has(mrpt::obs::IMU_WX));
}

TEST(Import, DvlPd0EarthWithRangesAndFrameMap)
{
	const auto dir = scratch("dvl");
	write(dir / "dvl.csv",
	      "t,r1,r2,r3,r4,v1,v2,v3,coord\n"
	      "1,3.3,3.5,3.4,3.4,0.022,-0.029,-0.003,3\n"
	      "2,3.3,,3.4,3.4,nan,nan,nan,3\n"
	      "3,3.3,3.5,3.4,3.4,-32768,-32768,-32768,1\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, R"(
sensors:
  - label: DVL
    class: dvl
    source: {csv: dvl.csv}
    time: {field: t, format: s}
    frame: {field: coord, map: {0: beam, 1: instrument, 2: vehicle, 3: earth_enu}}
    sign: bottom_over_instrument
    velocity: {fields: [v1, v2, v3], unit: m/s, invalid: [-32768]}
    beams: {count: 4, range: {field: 'r{n}', unit: m}, range_is: vertical}
    beam_inclination: {value: 30, unit: deg}
    mounting: {position_m: [0, 0, 0.15], orientation_ypr_deg: [45, 0, 0]}
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 3u);
	using auvnav::obs::CObservationDVL;
	const auto* d0 = dynamic_cast<const CObservationDVL*>(obs[0].get());
	ASSERT_NE(d0, nullptr);
	EXPECT_EQ(d0->frame, auvnav::obs::DvlFrame::EarthEnu);
	EXPECT_EQ(d0->sign, auvnav::obs::DvlSign::BottomOverInstrument);
	EXPECT_TRUE(d0->bottom_lock);
	EXPECT_DOUBLE_EQ(d0->velocity_s_mps[0], 0.022);  // earth frames are not axis-mapped
	EXPECT_NEAR(d0->altitude_m, (3.3 + 3.5 + 3.4 + 3.4) / 4, 1e-12);
	ASSERT_EQ(d0->beams.size(), 4u);
	EXPECT_NEAR(d0->sensorPose.z(), 0.15, 1e-12);
	const auto* d1 = dynamic_cast<const CObservationDVL*>(obs[1].get());
	EXPECT_FALSE(d1->bottom_lock);  // NaN velocity: no lock, not an error
	EXPECT_FALSE(d1->beams[1].valid);
	EXPECT_NEAR(d1->altitude_m, (3.3 + 3.4 + 3.4) / 3, 1e-12);
	const auto* d2 = dynamic_cast<const CObservationDVL*>(obs[2].get());
	EXPECT_EQ(d2->frame, auvnav::obs::DvlFrame::Instrument);
	EXPECT_FALSE(d2->bottom_lock);  // PD0 -32768: invalid
}

TEST(Import, PressureUnitsGaugeAndDepth)
{
	const auto dir = scratch("pressure");
	write(dir / "p.csv", "t,p_kpa,depth,temp\n1,10.0,1.0,12.5\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, R"(
sensors:
  - {label: P1, class: pressure, source: {csv: p.csv}, time: {field: t, format: s},
     pressure: {field: p_kpa, unit: kPa}, pressure_reference: gauge, atmospheric_pressure_pa: 101325,
     temperature: {field: temp, unit: degC}}
  - {label: P2, class: pressure, source: {csv: p.csv}, time: {field: t, format: s},
     depth: {field: depth, unit: m}, atmospheric_pressure_pa: 101325, density_kg_m3: 1000, gravity_mps2: 9.81}
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 2u);
	for (const auto& o : obs)
	{
		const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(o.get());
		ASSERT_NE(p, nullptr);
		if (p->sensorLabel == "P1")
		{
			EXPECT_DOUBLE_EQ(p->pressure_pa, 111325);
			EXPECT_DOUBLE_EQ(p->temperature_c, 12.5);
		}
		else
			EXPECT_DOUBLE_EQ(p->pressure_pa, 101325 + 9810);
	}
	// A depth without its density is refused: no silent sea-water guess.
	ImportReport rep2;
	EXPECT_THAT(importError(dir, R"(
sensors:
  - {label: P, class: pressure, source: {csv: p.csv}, time: {field: t, format: s},
     depth: {field: depth, unit: m}, atmospheric_pressure_pa: 101325}
)",
	                        rep2),
	            HasSubstr("sensors[0].density_kg_m3"));
	EXPECT_THAT(importError(dir, R"(
sensors:
  - {label: P, class: pressure, source: {csv: p.csv}, time: {field: t, format: s},
     pressure: {field: p_kpa, unit: kPa}}
)",
	                        rep2),
	            HasSubstr("pressure_reference: required"));
}

TEST(Import, GpsFromDegrees)
{
	const auto dir = scratch("gps");
	write(dir / "gps.csv", "t,lat,lon,alt,q\n1,-12.975,-38.43,1.5,1\n2,-12.975,-38.43,1.5,0\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, R"(
sensors:
  - {label: GPS, class: gps, source: {csv: gps.csv}, time: {field: t, format: s},
     latitude: {field: lat, unit: deg}, longitude: {field: lon, unit: deg},
     altitude: {field: alt, unit: m}, altitude_reference: msl, fix_quality: {field: q}}
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 2u);
	auto* g = dynamic_cast<mrpt::obs::CObservationGPS*>(obs[0].get());
	ASSERT_NE(g, nullptr);
	ASSERT_TRUE(g->has_GGA_datum());
	const auto& f = g->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields;
	// MRPT's GGA fields are packed: copied out, since EXPECT_EQ binds
	// references (a misaligned double reference is undefined behaviour).
	const double lat_deg = f.latitude_degrees, lon_deg = f.longitude_degrees;
	const int quality = f.fix_quality;
	EXPECT_EQ(lat_deg, -12.975);  // bit-exact: degrees kept as read
	EXPECT_EQ(lon_deg, -38.43);
	EXPECT_EQ(quality, 1);
	const int quality_1 = dynamic_cast<mrpt::obs::CObservationGPS*>(obs[1].get())
	                          ->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>()
	                          .fields.fix_quality;
	EXPECT_EQ(quality_1, 0);
}

TEST(Import, AdcpAndThrusterArrays)
{
	const auto dir = scratch("arrays");
	write(dir / "adcp.csv", "t,n,c0x,c0y,c0z,c1x,c1y,c1z,ok0,ok1\n1,2,0.1,0.2,0.3,1,2,3,1,0\n");
	write(dir / "thr.csv", "t,e0,e1,e2\n1,10,-5,2.5\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, R"(
sensors:
  - label: ADCP
    class: adcp
    source: {csv: adcp.csv}
    time: {field: t, format: s}
    blank_distance: {value: 0.5, unit: m}
    cell_size: {value: 50, unit: cm}
    cells: {count: {field: n}, velocity: {fields: ['c{i}x', 'c{i}y', 'c{i}z'], unit: m/s}, valid: {field: 'ok{i}'}}
  - label: THR
    class: thrusters
    source: {csv: thr.csv}
    time: {field: t, format: s}
    effort: {count: 3, field: 'e{i}', unit: N}
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 2u);
	const auto* a = dynamic_cast<const auvnav::obs::CObservationADCP*>(obs[0].get());
	ASSERT_NE(a, nullptr);
	ASSERT_EQ(a->cells.size(), 2u);
	EXPECT_DOUBLE_EQ(a->cell_size_m, 0.5);
	EXPECT_DOUBLE_EQ(a->cells[1].velocity_s_mps[2], 3);
	EXPECT_TRUE(a->cells[0].valid);
	EXPECT_FALSE(a->cells[1].valid);
	const auto* t = dynamic_cast<const auvnav::obs::CObservationThrusters*>(obs[1].get());
	ASSERT_NE(t, nullptr);
	EXPECT_EQ(t->effort, (std::vector<double>{10, -5, 2.5}));
}

// ---------------------------------------------------------------- time handling

TEST(Import, InterleavedJitteredSourcesComeOutInTimeOrder)
{
	const auto dir = scratch("order");
	// imu: 100 Hz with a repeated stamp, one 30 ms step back (inside the
	// window), a 0.3 s gap; mag: 50 Hz, interleaving.
	std::string imu = "t,gx,gy,gz,ax,ay,az\n";
	for (int i = 0; i < 100; ++i)
	{
		double t = 100 + 0.01 * i;
		if (i == 10) t = 100 + 0.01 * 9;   // repeated stamp
		if (i == 20) t = 100 + 0.01 * 17;  // 30 ms back
		if (i >= 50) t += 0.3;             // gap
		imu += std::to_string(t) + ",0,0,0,0,0,1\n";
	}
	std::string mag = "t,mx,my,mz\n";
	for (int i = 0; i < 50; ++i) mag += std::to_string(100.005 + 0.02 * i) + ",1,2,3\n";
	write(dir / "imu.csv", imu);
	write(dir / "mag.csv", mag);
	ImportReport rep;
	ASSERT_EQ(importError(dir, std::string(kImuSpec) + R"(
  - {label: MAG, class: imu, source: {csv: mag.csv}, time: {field: t, format: s},
     magnetic_field: {fields: [mx, my, mz], unit: uT}}
reorder_window_s: 0.1
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 150u);
	for (std::size_t i = 1; i < obs.size(); ++i) ASSERT_LE(obs[i - 1]->timestamp, obs[i]->timestamp) << i;
	const SensorReport& s = rep.sensors[0];
	EXPECT_EQ(s.rows_read, 100u);
	EXPECT_EQ(s.written, 100u);
	EXPECT_EQ(s.repeated_stamps, 1u);
	EXPECT_EQ(s.backward_stamps, 1u);
	EXPECT_EQ(s.reordered, 1u);
	EXPECT_EQ(s.gaps, 1u);
	EXPECT_NEAR(s.largest_gap_s, 0.31, 1e-6);
	EXPECT_EQ(s.clock_jumps, 0u);
	EXPECT_NEAR(rep.sensors[1].median_rate_hz, 50, 1e-6);
	EXPECT_THAT(rep.toJson(), HasSubstr("\"repeated_stamps\": 1"));
	EXPECT_THAT(rep.toMarkdown(), HasSubstr("| IMU | mrpt::obs::CObservationIMU |"));
}

TEST(Import, ClockJumpsAreReportedNotFollowedBlindly)
{
	const auto dir = scratch("jumps");
	std::string imu = "t,gx,gy,gz,ax,ay,az\n";
	for (int i = 0; i < 30; ++i)
	{
		double t = 1000 + 0.01 * i;
		if (i >= 10) t += 3600;  // +1 h
		if (i >= 20) t -= 7200;  // then 1 h before the start
		imu += std::to_string(t) + ",0,0,0,0,0,1\n";
	}
	write(dir / "imu.csv", imu);
	ImportReport rep;
	ASSERT_EQ(importError(dir, kImuSpec, rep), "");
	const SensorReport& s = rep.sensors[0];
	EXPECT_EQ(s.clock_jumps, 2u);
	EXPECT_EQ(s.written, 20u);
	EXPECT_EQ(s.rejected, 10u);
	EXPECT_EQ(s.rejected_by_reason.begin()->first,
	          "behind the reorder window (older than data already written)");
	ASSERT_EQ(s.clock_jump_notes.size(), 2u);
	EXPECT_THAT(s.clock_jump_notes[0], HasSubstr("+3600.010 s"));
	EXPECT_THAT(s.clock_jump_notes[1], HasSubstr("-7199.990 s"));
}

// ---------------------------------------------------------------- bad input

TEST(ImportBadInput, MalformedRowNamesFileAndLine)
{
	const auto dir = scratch("bad_row");
	write(dir / "imu.csv", "t,gx,gy,gz,ax,ay,az\n1,0,0,0,0,0,1\n1.01,0,0,0\n1.02,0,0,0,0,0,1\n");
	ImportReport rep;
	const std::string err = importError(dir, kImuSpec, rep);
	EXPECT_THAT(err, HasSubstr("imu.csv:3: 4 cells, the header has 7"));
	EXPECT_THAT(err, HasSubstr("--lenient"));
	ImportReport lenient;
	ASSERT_EQ(importError(dir, kImuSpec, lenient, true), "");
	EXPECT_EQ(lenient.sensors[0].written, 2u);
	EXPECT_EQ(lenient.sensors[0].rejected, 1u);
	EXPECT_EQ(lenient.sensors[0].first_rejected_where.at("4 cells, the header has 7"),
	          (dir / "imu.csv").string() + ":3");
}

TEST(ImportBadInput, AFailedImportLeavesNoRawlog)
{
	// The rawlog is written as OUT.partial and renamed only when complete: an
	// import that stops half-way leaves neither, and an earlier OUT is kept.
	const auto dir = scratch("no_partial");
	std::string rows = "t,gx,gy,gz,ax,ay,az\n";
	for (int i = 0; i < 5000; ++i) rows += std::to_string(1 + 0.01 * i) + ",0,0,0,0,0,1\n";
	write(dir / "imu.csv", rows + "99,0,0,0\n");
	write(dir / "out.rawlog", "an earlier import");
	ImportReport rep;
	EXPECT_THAT(importError(dir, kImuSpec, rep), HasSubstr("4 cells, the header has 7"));
	EXPECT_FALSE(rep.output_created);
	EXPECT_FALSE(fs::exists(dir / "out.rawlog.partial"));
	EXPECT_EQ(fs::file_size(dir / "out.rawlog"), 17u);
	write(dir / "imu.csv", rows);
	ASSERT_EQ(importError(dir, kImuSpec, rep), "");
	EXPECT_TRUE(rep.output_created);
	EXPECT_FALSE(fs::exists(dir / "out.rawlog.partial"));
	EXPECT_EQ(readAll((dir / "out.rawlog").string()).size(), 5000u);
}

TEST(ImportBadInput, NonNumericAndNonFiniteFields)
{
	const auto dir = scratch("bad_number");
	write(dir / "imu.csv",
	      "t,gx,gy,gz,ax,ay,az\n1,0,0,0,0,0,1\n1.01,0,abc,0,0,0,1\n1.02,0,0,inf,0,0,1\n1.03,0,0,0,0,0,1\n");
	ImportReport rep;
	EXPECT_THAT(importError(dir, kImuSpec, rep), HasSubstr("imu.csv:3: field 'gy': 'abc' is not a number"));
	ImportReport lenient;
	ASSERT_EQ(importError(dir, kImuSpec, lenient, true), "");
	EXPECT_EQ(lenient.sensors[0].written, 2u);
	EXPECT_EQ(lenient.sensors[0].rejected_by_reason.at("non-finite angular_velocity"), 1u);
	write(dir / "imu.csv", "t,gx,gy,gz,ax,ay,az\n1,0,0,0,0,0,1\nnoon,0,0,0,0,0,1\n");
	EXPECT_THAT(importError(dir, kImuSpec, rep), HasSubstr("imu.csv:3: time field 't': 'noon' not a number"));
}

TEST(ImportBadInput, MissingColumnIsAnErrorEvenWhenLenient)
{
	const auto dir = scratch("missing_column");
	write(dir / "imu.csv", "t,gx,gy,gz,ax,ay\n1,0,0,0,0,0\n");
	ImportReport rep;
	EXPECT_THAT(importError(dir, kImuSpec, rep, true), HasSubstr("imu.csv:2: no field 'az'"));
}

TEST(ImportBadInput, SpecErrorsNameTheKey)
{
	const auto dir = scratch("bad_spec");
	write(dir / "imu.csv", "t,gx,gy,gz,ax,ay,az\n1,0,0,0,0,0,1\n");
	ImportReport rep;
	auto spec = [&](const std::string& s) { return importError(dir, s, rep); };
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: imu.csv}, time: {field: t, format: s},
     angular_velocity: {fields: [gx, gy, gz], unit: deg}}
)"),
	            HasSubstr("sensors[0].angular_velocity.unit: unit 'deg' is an angle"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: imu.csv}, time: {field: t, format: s},
     angular_velocity: {fields: [gx, gy, gz], unit: rpm/s}}
)"),
	            HasSubstr("unknown unit 'rpm/s'"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: imu.csv}, time: {field: t, format: s},
     angular_velocty: {fields: [gx, gy, gz], unit: rad/s}}
)"),
	            HasSubstr("sensors[0].angular_velocty: unknown key"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: imu.csv}, time: {field: t},
     angular_velocity: {fields: [gx, gy, gz], unit: rad/s}}
)"),
	            HasSubstr("sensors[0].time.format: required for a CSV time column"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: imu.csv}, time: {field: t, format: hours},
     angular_velocity: {fields: [gx, gy, gz], unit: rad/s}}
)"),
	            HasSubstr("unknown time format 'hours'"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: sonar, source: {csv: imu.csv}, time: {field: t, format: s}}
)"),
	            HasSubstr("unknown observation class 'sonar'"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: nothere.csv}, time: {field: t, format: s},
     angular_velocity: {fields: [gx, gy, gz], unit: rad/s}}
)"),
	            HasSubstr("no input matches 'nothere.csv'"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: IMU, class: imu, source: {csv: imu.csv}, time: {field: t, format: s},
     angular_velocity: {fields: [gx, gy, gz], unit: rad/s}, axes: [x, y, w]}
)"),
	            HasSubstr("sensors[0].axes: 'w' is not one of"));
	EXPECT_THAT(spec(R"(
sensors:
  - {label: DVL, class: dvl, source: {csv: imu.csv}, time: {field: t, format: s},
     velocity: {fields: [gx, gy, gz], unit: m/s}}
)"),
	            HasSubstr("sensors[0].frame: required"));
	EXPECT_FALSE(fs::exists(dir / "out.rawlog") && fs::file_size(dir / "out.rawlog") > 100);
}

// ---------------------------------------------------------------- export

TEST(ImportExport, ShippedSpecIsTheExportLayout)
{
	std::ifstream f(std::string(AUVNAV_TEST_DATA_DIR) + "/../../config/import/auvnav_export.yaml");
	std::stringstream s;
	s << f.rdbuf();
	EXPECT_EQ(s.str(), exportSpecText(simulatorLabels(), {{"THRUSTERS", "N"}}, true))
	    << "regenerate config/import/auvnav_export.yaml from exportSpecText(simulatorLabels(), ..., true)";
}

TEST(ImportExport, SpecTextReadsTheLayoutBack)
{
	const auto dir = scratch("export_spec");
	write(dir / "spec.yaml", exportSpecText({{"IMU", "imu"},
	                                         {"DVL", "dvl"},
	                                         {"PRESSURE", "pressure"},
	                                         {"GPS", "gps"},
	                                         {"ADCP", "adcp"},
	                                         {"THRUSTERS", "thrusters"},
	                                         {"SONAR", "image"}},
	                                        {{"THRUSTERS", "N"}}));
	EXPECT_NO_THROW(validateSpec((dir / "spec.yaml").string()));
}

TEST(Import, IsoTimesAndPerSensorOffset)
{
	const auto dir = scratch("iso");
	write(dir / "p.csv", "when,p\n2016-01-24T03:29:08.5Z,101325\n2016-01-24T03:29:09.5Z,101400\n");
	ImportReport rep;
	ASSERT_EQ(importError(dir, R"(
sensors:
  - {label: P, class: pressure, source: {csv: p.csv}, time: {field: when, format: iso8601, offset_s: -0.25},
     pressure: {field: p, unit: Pa}, pressure_reference: absolute}
)",
	                      rep),
	          "");
	const auto obs = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(obs.size(), 2u);
	EXPECT_EQ(fromMrptTime(obs[0]->timestamp), 1453606148250000000LL);
	EXPECT_EQ(fromMrptTime(obs[1]->timestamp), 1453606149250000000LL);
}

TEST(ImportExport, ImagesRoundTripAsPng)
{
	const auto dir = scratch("images");
	{
		auvnav::io::RawlogWriter w((dir / "in.rawlog").string());
		for (int k = 0; k < 2; ++k)
		{
			auto o = mrpt::obs::CObservationImage::Create();
			o->sensorLabel = "SONAR";
			o->timestamp = toMrptTime(1000000000000LL + k * 500000000LL);
			cv::Mat img(40, 32, CV_8UC1);
			for (int r = 0; r < img.rows; ++r)
				for (int c = 0; c < img.cols; ++c)
					img.at<uchar>(r, c) = static_cast<uchar>((r * 7 + c * 3 + k) % 251);
			o->image = mrpt::img::CImage(img, mrpt::img::DEEP_COPY);
			o->cameraParams.ncols = 32;
			o->cameraParams.nrows = 40;
			o->cameraParams.fx(110.5);
			o->cameraParams.fy(20.25);
			o->cameraParams.cx(15.5);
			o->cameraParams.cy(-3.0);
			o->cameraParams.cameraName = "polar, sonar";
			o->cameraPose = mrpt::poses::CPose3D(1, 0, 0.5, 0, 0, 0);
			w.write(*o);
		}
	}
	ExportReport ex;
	exportRawlog((dir / "in.rawlog").string(), (dir / "csv").string(), ex);
	ASSERT_EQ(ex.sensors.size(), 1u);
	EXPECT_EQ(ex.sensors[0].rows, 2u);
	EXPECT_TRUE(fs::exists(dir / "csv" / "SONAR" / "000001.png"));
	ImportOptions opt;
	opt.spec_path = (dir / "csv" / "import.yaml").string();
	opt.inputs = {(dir / "csv").string()};
	opt.out_rawlog = (dir / "out.rawlog").string();
	ImportReport rep;
	runImport(opt, rep);
	const auto a = readAll((dir / "in.rawlog").string());
	const auto b = readAll((dir / "out.rawlog").string());
	ASSERT_EQ(a.size(), b.size());
	for (std::size_t i = 0; i < a.size(); ++i)
	{
		const auto* x = dynamic_cast<const mrpt::obs::CObservationImage*>(a[i].get());
		const auto* y = dynamic_cast<const mrpt::obs::CObservationImage*>(b[i].get());
		ASSERT_NE(y, nullptr);
		EXPECT_EQ(x->timestamp, y->timestamp);
		EXPECT_EQ(y->cameraParams.cameraName, "polar, sonar");
		EXPECT_EQ(y->cameraParams.fx(), 110.5);
		EXPECT_EQ(y->cameraParams.cy(), -3.0);
		EXPECT_NEAR(y->cameraPose.z(), 0.5, 1e-15);
		const cv::Mat mx = x->image.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
		const cv::Mat my = y->image.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
		ASSERT_EQ(my.type(), CV_8UC1);
		EXPECT_EQ(cv::countNonZero(mx != my), 0);
	}
}
