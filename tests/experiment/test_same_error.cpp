// auvnav-experiment and auvnav-eval measure the same error on the same run
// (issue 14: one ground-truth reader and one interpolation rule for both).
//
// A one-seed denial experiment on the 2-minute test mission keeps its rawlog;
// auvnav-run repeats the experiment's run on it (same navigator file, the same
// denial, a state row per prediction) and auvnav-eval takes the error at the
// experiment's instant (--at initialization_s + denial_s). Both must be the
// same number: runs.csv prints 6 significant digits.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace
{
const std::string kRepo = AUVNAV_SOURCE_DIR;

std::string slurp(const fs::path& p)
{
	std::ifstream f(p);
	std::stringstream ss;
	ss << f.rdbuf();
	return ss.str();
}

/** Runs `cmd` with its output in `log`; the exit code (-1: did not exit). */
int run(const std::string& cmd, const fs::path& log)
{
	const int rc = std::system((cmd + " > " + log.string() + " 2>&1").c_str());
	return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}
}  // namespace

TEST(ExperimentAndEval, MeasureTheSameErrorOnTheSameRun)
{
	const fs::path w = fs::path(AUVNAV_TEST_WORK_DIR) / "same_error";
	fs::remove_all(w);
	fs::create_directories(w);
	// The end of the denial falls between two 10 Hz truth rows (and between two
	// IMU samples): the nearest truth row would be 35 ms, ~2 cm, off.
	const double init_s = 50, denial_s = 40.035;
	{
		std::ofstream ex(w / "experiment.yaml");
		ex << "mission: " << kRepo << "/tests/data/short_mission.yaml\n"
		   << "navigator: " << kRepo << "/config/flatfish.yaml\n"
		   << "seeds: [3]\ninitialization_s: " << init_s << "\ndenial_s: " << std::to_string(denial_s) << "\n"
		   << "configurations:\n  - {name: \"Inertial + pressure + ADCP + model\", deny: [GPS, DVL]}\n";
	}
	ASSERT_EQ(run(std::string(AUVNAV_EXPERIMENT_EXE) + " " + (w / "experiment.yaml").string() +
	                  " --keep-rawlogs --out " + (w / "exp").string(),
	              w / "experiment.log"),
	          0)
	    << slurp(w / "experiment.log");
	// runs.csv: seed,"configuration",error_m,two_sigma_m,inside_2sigma
	std::smatch m;
	const std::string runs = slurp(w / "exp" / "runs.csv");
	ASSERT_TRUE(std::regex_search(runs, m, std::regex("\n3,\"[^\"]*\",([-+.0-9eE]+),"))) << runs;
	const double experiment_error = std::stod(m[1]);

	const fs::path seed = w / "exp" / "seed_3";
	const std::string deny = " --deny GPS:" + std::to_string(init_s) + ":" +
	                         std::to_string(init_s + denial_s) + " --deny DVL:" + std::to_string(init_s) +
	                         ":" + std::to_string(init_s + denial_s);
	ASSERT_EQ(run(std::string(AUVNAV_RUN_EXE) + " --quiet --config " + kRepo + "/config/flatfish.yaml" +
	                  deny + " --set outputs.rate_hz=1000 --out " + (w / "run").string() + " " +
	                  (seed / "short_test.rawlog").string(),
	              w / "run.log"),
	          0)
	    << slurp(w / "run.log");
	ASSERT_EQ(run(std::string(AUVNAV_EVAL_EXE) + " --run " + (w / "run").string() + " --truth " +
	                  (seed / "ground_truth.csv").string() + " --at " + std::to_string(init_s + denial_s) +
	                  " --out " + (w / "eval").string(),
	              w / "eval.log"),
	          0)
	    << slurp(w / "eval.log");
	const std::string md = slurp(w / "eval" / "eval.md");
	ASSERT_TRUE(std::regex_search(
	    md, m, std::regex("Horizontal error at [.0-9]+ s after the truth's start: ([.0-9]+) m")))
	    << md;
	const double eval_error = std::stod(m[1]);
	std::printf("error after the denial: auvnav-experiment %.6g m, auvnav-eval %.6g m\n", experiment_error,
	            eval_error);
	EXPECT_GT(experiment_error, 0.0);
	EXPECT_NEAR(eval_error, experiment_error, 1e-5 * std::max(1.0, experiment_error));
}
