// auvnav-sim: simulate an AUV mission (the vehicle and sensor files the
// mission names: FlatFish-like, BlueROV2-Heavy-like) into an MRPT rawlog with
// ground truth. See README.md and config/missions/.
#include <auvnav/cli.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "mission.h"

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Simulates an AUV mission (6-DOF vehicle from the mission's vehicle file, e.g. FlatFish-like "
	    "or BlueROV2-Heavy-like; autopilot; IMU, DVL, ADCP, pressure, GPS, magnetometer, thruster "
	    "commands as its sensors file configures them) and writes DIR/<mission>.rawlog (MRPT rawlog; load "
	    "libauvnav_obs.so in MRPT tools to read DVL/ADCP/pressure/thruster observations), "
	    "DIR/ground_truth.tum and DIR/ground_truth.csv. The same seed gives byte-identical files.",
	    ' ', "0.1.0");
	TCLAP::UnlabeledValueArg<std::string> mission("mission", "Mission YAML (see config/missions/)", true, "",
	                                              "MISSION.yaml", cmd);
	TCLAP::ValueArg<unsigned> seed("s", "seed", "Random seed (default 1)", false, 1, "N", cmd);
	TCLAP::ValueArg<std::string> out("o", "out", "Output directory (created)", true, "", "DIR", cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-sim")) return *code;
	try
	{
		const auto t0 = std::chrono::steady_clock::now();
		const auto spec = auvnav::sim::MissionSpec::load(mission.getValue());
		std::cout << "auvnav-sim: mission '" << spec.name << "', seed " << seed.getValue() << "\n";
		const auto s = auvnav::sim::runMission(spec, seed.getValue(), out.getValue());
		const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
		std::printf("  simulated %.1f s (%.1f min) in %.1f s wall time%s\n", s.duration_s, s.duration_s / 60,
		            wall, s.plan_completed ? "" : "  [plan NOT completed: max_duration_s reached]");
		std::printf("  distance travelled %.1f m (%.1f m submerged), max depth %.2f m\n", s.distance_m,
		            s.submerged_distance_m, s.max_depth_m);
		for (const auto& [label, n] : s.observations)
			std::printf("  %-10s %8zu observations\n", label.c_str(), n);
		if (s.dvl_total)
			std::printf("  DVL bottom lock %.1f%% of pings\n", 100.0 * s.dvl_locked / s.dvl_total);
		if (s.adcp_profiles)
			std::printf("  ADCP %.2f valid cells per profile\n",
			            double(s.adcp_valid_cells) / s.adcp_profiles);
		std::printf("  GPS gross outliers injected: %zu\n", s.gps_outliers);
		if (s.stamp_duplicates || s.stamp_out_of_order)
			std::printf("  logger stamps injected: %zu duplicated, %zu out of order\n", s.stamp_duplicates,
			            s.stamp_out_of_order);
		std::printf("  wrote %s (%.1f MB), ground_truth.tum, ground_truth.csv\n", s.rawlog_path.c_str(),
		            std::filesystem::file_size(s.rawlog_path) / 1e6);
		if (s.plan_completed) return auvnav::cli::kExitOk;
		std::cerr
		    << "auvnav-sim: plan not completed: the mission's max_duration_s ended it (outputs written)\n";
		return auvnav::cli::kExitNoResult;
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-sim", e.what());
	}
}
