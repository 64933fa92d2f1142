// auvnav-smooth: the RTS smoother's backward pass over a run recorded with
// auvnav-run --smooth (also an interrupted one: what was recorded). README.
#include <auvnav/cli.h>

#include <cstdio>

#include "smooth_outputs.h"

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Smooths a run recorded with auvnav-run --smooth (unscented Rauch-Tung-Striebel, backward over "
	    "RUN_DIR/smoother/stretches.bin): writes RUN_DIR/smoothed_trajectory.tum, "
	    "RUN_DIR/smoothed_states.csv "
	    "and RUN_DIR/smoother.json.",
	    ' ', "0.1.0");
	TCLAP::UnlabeledValueArg<std::string> run("run_dir", "auvnav-run output folder", true, "", "RUN_DIR",
	                                          cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-smooth")) return *code;
	try
	{
		const auto r = auvnav::run::smoothRun(run.getValue());
		if (r.rows == 0)
			return auvnav::cli::fail("auvnav-smooth",
			                         run.getValue() + ": no estimate recorded (the filter never started)",
			                         auvnav::cli::kExitNoResult);
		std::printf(
		    "auvnav-smooth: %zu estimates (%zu smoothed, %zu segment ends, %zu kept filtered, %zu covariance "
		    "repairs)%s in %.2f s\n",
		    r.rows, r.smoothed, r.segment_ends, r.kept, r.repairs,
		    r.partial_tail ? "; the last record was cut short and is left out" : "", r.wall_s);
		return auvnav::cli::kExitOk;
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-smooth", e.what());
	}
}
