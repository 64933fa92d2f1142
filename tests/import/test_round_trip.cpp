// Round trips through the real programs, as a user runs them: auvnav-sim →
// auvnav-export → auvnav-import (shipped spec) → auvnav-run gives the same
// trajectory as auvnav-run on the simulator's own rawlog.
#include <auvnav/testing/scratch_dir.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace
{
const std::string kSource = AUVNAV_SOURCE_DIR;
const std::string kBin = AUVNAV_BIN_DIR;

fs::path scratch(const std::string& name)
{
	return auvnav::testing::scratchFolder("round_trip", name);
}

/** Runs `cmd` (output to `log`); its exit code. */
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

std::vector<std::vector<double>> readTum(const fs::path& p)
{
	std::vector<std::vector<double>> rows;
	std::ifstream f(p);
	std::string line;
	while (std::getline(f, line))
	{
		if (line.empty() || line[0] == '#') continue;
		std::istringstream s(line);
		std::vector<double> v;
		double x;
		while (s >> x) v.push_back(x);
		rows.push_back(v);
	}
	return rows;
}

/** Largest position difference [m] between two trajectories with the same rows. */
double maxPositionDifference(const fs::path& a, const fs::path& b)
{
	const auto ra = readTum(a), rb = readTum(b);
	EXPECT_EQ(ra.size(), rb.size());
	EXPECT_GT(ra.size(), 100u);
	double worst = 0;
	for (std::size_t i = 0; i < std::min(ra.size(), rb.size()); ++i)
	{
		EXPECT_EQ(ra[i][0], rb[i][0]) << "row " << i;
		for (int k = 1; k <= 3; ++k) worst = std::max(worst, std::abs(ra[i][k] - rb[i][k]));
	}
	return worst;
}
}  // namespace

TEST(ImportRoundTrip, SimExportImportRunGivesTheSameTrajectory)
{
	const fs::path d = scratch("csv");
	ASSERT_EQ(run(kBin + "/auvnav-sim " + kSource + "/tests/data/short_mission.yaml --seed 3 --out " +
	                  (d / "sim").string(),
	              d / "sim.log"),
	          0)
	    << slurp(d / "sim.log");
	const fs::path original = d / "sim" / "short_test.rawlog";
	ASSERT_EQ(run(kBin + "/auvnav-export " + original.string() + " --out " + (d / "csv").string(),
	              d / "export.log"),
	          0)
	    << slurp(d / "export.log");
	ASSERT_EQ(run(kBin + "/auvnav-import --spec " + kSource + "/config/import/auvnav_export.yaml --out " +
	                  (d / "imported.rawlog").string() + " " + (d / "csv").string(),
	              d / "import.log"),
	          0)
	    << slurp(d / "import.log");
	// The export's own spec reads it back too.
	ASSERT_EQ(run(kBin + "/auvnav-import --spec " + (d / "csv" / "import.yaml").string() + " --out " +
	                  (d / "imported2.rawlog").string() + " " + (d / "csv").string(),
	              d / "import2.log"),
	          0)
	    << slurp(d / "import2.log");
	const std::string report = slurp(d / "imported.import.json");
	EXPECT_THAT(report, ::testing::HasSubstr("\"completed\": true"));
	EXPECT_THAT(report, ::testing::Not(::testing::HasSubstr("\"rejected\": 1")));

	// The same rawlog, observation by observation (auvnav-info's counts), and the same run.
	const std::string run_cmd =
	    kBin + "/auvnav-run --config " + kSource + "/config/flatfish.yaml --quiet --out ";
	ASSERT_EQ(run(run_cmd + (d / "run_original").string() + " " + original.string(), d / "run1.log"), 0)
	    << slurp(d / "run1.log");
	ASSERT_EQ(
	    run(run_cmd + (d / "run_imported").string() + " " + (d / "imported.rawlog").string(), d / "run2.log"),
	    0)
	    << slurp(d / "run2.log");
	const double diff =
	    maxPositionDifference(d / "run_original" / "trajectory.tum", d / "run_imported" / "trajectory.tum");
	std::printf("CSV round trip: max position difference %.3g m\n", diff);
	EXPECT_LE(diff, 1e-9);
	EXPECT_TRUE(slurp(d / "run_original" / "states.csv") == slurp(d / "run_imported" / "states.csv"))
	    << "states.csv differ";
}

TEST(ImportRoundTrip, UsblFixesKeepTheirMeasurementTimeThroughCsv)
{
	// auvnav-sim (USBL 1 s late) → auvnav-export → auvnav-import → auvnav-run:
	// the fixes come back with their measurement time (re-filtered again) and
	// the run is the same.
	const fs::path d = scratch("usbl");
	ASSERT_EQ(run(kBin + "/auvnav-sim " + kSource + "/tests/data/short_usbl_mission.yaml --seed 2 --out " +
	                  (d / "sim").string(),
	              d / "sim.log"),
	          0)
	    << slurp(d / "sim.log");
	const fs::path original = d / "sim" / "short_usbl.rawlog";
	ASSERT_EQ(run(kBin + "/auvnav-export " + original.string() + " --out " + (d / "csv").string(),
	              d / "export.log"),
	          0)
	    << slurp(d / "export.log");
	const std::string csv = slurp(d / "csv" / "USBL.csv");
	ASSERT_THAT(csv, ::testing::StartsWith("t_s,measurement_time_s,latitude_deg,"));
	ASSERT_EQ(run(kBin + "/auvnav-import --spec " + kSource + "/config/import/auvnav_export.yaml --out " +
	                  (d / "imported.rawlog").string() + " " + (d / "csv").string(),
	              d / "import.log"),
	          0)
	    << slurp(d / "import.log");
	const std::string run_cmd =
	    kBin + "/auvnav-run --config " + kSource + "/config/flatfish.yaml --quiet --out ";
	ASSERT_EQ(run(run_cmd + (d / "run_original").string() + " " + original.string(), d / "run1.log"), 0)
	    << slurp(d / "run1.log");
	ASSERT_EQ(
	    run(run_cmd + (d / "run_imported").string() + " " + (d / "imported.rawlog").string(), d / "run2.log"),
	    0)
	    << slurp(d / "run2.log");
	const std::string summary = slurp(d / "run_imported" / "summary.json");
	const auto at = summary.find("\"label\": \"USBL\"");
	ASSERT_NE(at, std::string::npos) << summary;
	const auto delayed = summary.find("\"delayed\": ", at);
	ASSERT_NE(delayed, std::string::npos);
	EXPECT_GT(std::atoi(summary.c_str() + delayed + 11), 50) << summary.substr(at, 300);
	const double diff =
	    maxPositionDifference(d / "run_original" / "trajectory.tum", d / "run_imported" / "trajectory.tum");
	std::printf("USBL CSV round trip: max position difference %.3g m\n", diff);
	EXPECT_LE(diff, 1e-9);
}
