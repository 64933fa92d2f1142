// A small MEMS vehicle end to end (issue: any vehicle, any IMU grade): the
// BlueROV2-Heavy-like ROV of auvnav-sim with an ADIS16470-class IMU, a
// magnetometer with hard/soft iron and thruster disturbance, an A50-like DVL
// and a Bar30-like depth sensor, run with the shipped MEMS profile
// config/bluerov2.yaml (heading unknown at start: σ 180°).
//  - with the magnetometer: horizontal error at the end ≤ 1 % of the distance
//    travelled and inside 2σ; position NEES inside its 95 % bound ≥ 90 % of
//    the time after alignment (the first 60 s); heading inside 3σ; status
//    ok. Attitude NEES: open (a disabled test below);
//  - without any heading source (MAG withheld): the heading σ never drops
//    below 90°, the position σ covers the displacement from the start, status
//    'degraded'.
// Pool square, one seed by default, three seeds labelled slow; the 20-minute
// lawnmower at 10 m (slow): within 1 %, inside 2σ open (disabled). The noise
// sweep of the profile: each figure alone and all together ×0.3 and ×3.
#include <auvnav/so3.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>

#include "harness.h"
#include "mission.h"
#include "sensors.h"

namespace fs = std::filesystem;
using namespace auvnav;
using namespace auvnav::test;

namespace
{
constexpr double kDeg = M_PI / 180;
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/bluerov2.yaml";
constexpr double kAlignedAfterS = 60;

double chi2Quantile(int dof, double p)
{
	return boost::math::quantile(boost::math::chi_squared(dof), p);
}

struct MemsOutcome
{
	double end_error_m = 0, end_two_sigma_m = 0, distance_m = 0;
	double worst_heading_ratio = 0;  //!< max |heading err| / σ after alignment
	double nees_pos_inside = 0, nees_att_inside = 0;
	double nees_tilt_inside = 0;  //!< the attitude NEES's roll/pitch part (2 dof, NED north/east axes)
	double min_heading_sigma_deg = 1e9, end_position_sigma_m = 0;
	double worst_displacement_ratio = 0;  //!< max |p − p_start| / σ_major (displacement > 2 m)
	double worst_error_to_two_sigma = 0;  //!< max horizontal error / 2σ_major over the run
	NavStatus status = NavStatus::Ok;
	std::string reason;
};

using Overrides = std::vector<std::pair<std::string, std::string>>;

/** The simulated IMU's true orientation in the body (its residual mounting
 *  error). The filter's R_nb is the IMU's attitude (state.h: IMU = body
 *  axes); a mounting error it cannot see (0.1° here, nothing but an external
 *  attitude reference tells it) is the user's calibration, like a DVL's,
 *  so attitude errors are taken against the IMU's true attitude. */
Eigen::Matrix3d imuMounting(const std::string& mission)
{
	const auto spec = sim::MissionSpec::load(std::string(AUVNAV_SOURCE_DIR) + "/" + mission);
	return sim::Mounting::fromConfig(spec.sensors.child("imu")).R_bs_true;
}

MemsOutcome runMems(const fs::path& dir, const std::string& mission_name, bool with_magnetometer,
                    const Overrides& extra = {}, const Eigen::Matrix3d& R_b_imu = Eigen::Matrix3d::Identity())
{
	const auto truth = readTruth(dir / "ground_truth.csv");
	const double t0 = truth.front().t_unix;
	// The mission's start is the navigator's start position (position: config).
	const Eigen::Vector3d p0 = truth.front().p_n;
	std::vector<DenialWindow> denials;
	if (!with_magnetometer) denials.push_back(DenialWindow{{"MAG"}, 0.0, 1e9});
	Overrides overrides = {{"filter.initial.north_m", std::to_string(p0.x())},
	                       {"filter.initial.east_m", std::to_string(p0.y())},
	                       {"filter.initial.depth_m", std::to_string(p0.z())}};
	overrides.insert(overrides.end(), extra.begin(), extra.end());
	const auto run = runNavigator(kConfig, (dir / (mission_name + ".rawlog")).string(), overrides, denials);
	MemsOutcome o;
	o.status = run.status;
	o.reason = run.status_reason;
	const double nees2 = chi2Quantile(2, 0.95), nees3 = chi2Quantile(3, 0.95);
	int n_after = 0, pos_in = 0, att_in = 0, tilt_in = 0;
	for (const auto& r : run.rows)
	{
		const auto& tr = truthAt(truth, r.t_unix);
		const Eigen::Matrix3d R_true = tr.q_nb.toRotationMatrix() * R_b_imu;
		const double heading_err = wrapAngle(yawOf(r.R_nb) - yawOf(R_true));
		o.min_heading_sigma_deg = std::min(o.min_heading_sigma_deg, r.headingSigma() / kDeg);
		const Eigen::Vector2d e = (r.p_n - tr.p_n).head<2>();
		const double major =
		    std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(r.P_ne).eigenvalues()(1));
		o.end_error_m = e.norm();
		o.end_two_sigma_m = 2 * major;
		o.worst_error_to_two_sigma = std::max(o.worst_error_to_two_sigma, e.norm() / (2 * major));
		o.end_position_sigma_m = major;
		o.distance_m = tr.distance_m;
		const double displacement = (tr.p_n - p0).head<2>().norm();
		if (displacement > 2)
			o.worst_displacement_ratio = std::max(o.worst_displacement_ratio, displacement / major);
		if (r.t_unix - t0 < kAlignedAfterS) continue;
		++n_after;
		o.worst_heading_ratio = std::max(o.worst_heading_ratio, std::abs(heading_err) / r.headingSigma());
		pos_in += e.dot(r.P_ne.ldlt().solve(e)) <= nees2;
		const Eigen::Vector3d ea = so3::Log(r.R_nb * R_true.transpose());
		att_in += ea.dot(r.P_att.ldlt().solve(ea)) <= nees3;
		const Eigen::Vector2d et = ea.head<2>();
		tilt_in += et.dot(r.P_att.topLeftCorner<2, 2>().ldlt().solve(et)) <= nees2;
	}
	o.nees_pos_inside = n_after ? double(pos_in) / n_after : 0;
	o.nees_att_inside = n_after ? double(att_in) / n_after : 0;
	o.nees_tilt_inside = n_after ? double(tilt_in) / n_after : 0;
	return o;
}

void memsSeeds(const std::string& mission, const std::string& name, const std::vector<unsigned>& seeds,
               bool check_heading, bool check_attitude_nees = false, bool check_sigma = true)
{
	std::printf(
	    "%s, config/bluerov2.yaml: seed | end error [m] | distance [m] | %% | 2 sigma [m] | worst |heading "
	    "err|/sigma | NEES pos / att (tilt) inside 95%% | status\n",
	    name.c_str());
	for (unsigned s : seeds)
	{
		const auto dir = simulate(mission, s);
		const MemsOutcome o = runMems(dir.path(), name, true, {}, imuMounting(mission));
		std::printf("  %u | %.2f | %.0f | %.2f %% | %.2f | %.2f | %.0f %% / %.0f %% (%.0f %%) | %s %s\n", s,
		            o.end_error_m, o.distance_m, 100 * o.end_error_m / o.distance_m, o.end_two_sigma_m,
		            o.worst_heading_ratio, 100 * o.nees_pos_inside, 100 * o.nees_att_inside,
		            100 * o.nees_tilt_inside, navStatusName(o.status), o.reason.c_str());
		EXPECT_LE(o.end_error_m, 0.01 * o.distance_m) << name << " seed " << s;
		if (check_sigma)
		{
			EXPECT_LE(o.end_error_m, o.end_two_sigma_m) << name << " seed " << s;
			EXPECT_GE(o.nees_pos_inside, 0.9) << name << " seed " << s;
		}
		EXPECT_EQ(o.status, NavStatus::Ok) << name << " seed " << s << ": " << o.reason;
		if (check_heading)
		{
			EXPECT_LE(o.worst_heading_ratio, 3.0) << name << " seed " << s;
		}
		if (check_attitude_nees)
		{
			EXPECT_GE(o.nees_att_inside, 0.9) << name << " seed " << s;
		}
	}
}
}  // namespace

TEST(MemsVehicle, PoolSquareWithMagnetometerDvlDepth)
{
	memsSeeds("config/missions/bluerov2_pool_square.yaml", "bluerov2_pool_square", {1}, true);
}

TEST(MemsVehicle, NoHeadingSourceKeepsTheHeadingUnknown)
{
	const auto dir = simulate("config/missions/bluerov2_pool_square.yaml", 1);
	const MemsOutcome o = runMems(dir.path(), "bluerov2_pool_square", false);
	std::printf(
	    "no heading source: min heading sigma %.1f deg, worst displacement from the start / position sigma "
	    "%.2f, "
	    "status %s (%s)\n",
	    o.min_heading_sigma_deg, o.worst_displacement_ratio, navStatusName(o.status), o.reason.c_str());
	EXPECT_GE(o.min_heading_sigma_deg, 90.0);
	EXPECT_EQ(o.status, NavStatus::Degraded) << o.reason;
}

// Worst displacement / position σ 0.59 (seed 1). It was 3.76 while the gyro
// bias state decayed to zero (σ 15°/h, τ 300 s): the unlearnt turn-on bias
// (~0.1°/s) bent the path beyond the σ; config/bluerov2.yaml now keeps it.
TEST(MemsVehicle, NoHeadingSourcePositionSigmaCoversTheDisplacement)
{
	const auto dir = simulate("config/missions/bluerov2_pool_square.yaml", 1);
	const MemsOutcome o = runMems(dir.path(), "bluerov2_pool_square", false);
	// With the heading unknown, where the vehicle is lies anywhere on a circle
	// of its displacement d around the start (σ per axis d/√2): the position σ
	// must cover at least half of d at every moment.
	EXPECT_LE(o.worst_displacement_ratio, 2.0);
}

// The magnetometer's correlated heading errors (the simulated unit's
// misalignment, ~1.4°, and thruster currents, several degrees) are a state of
// the magnetometer plugin (heading_bias, Gauss–Markov σ 4°, τ 120 s,
// config/bluerov2.yaml), so the heading σ stays as large as what the
// magnetometer can tell. Attitude errors against the IMU's true attitude
// (imuMounting). Measured, seeds 1-3: worst heading error 0.86 / 0.62 / 0.59σ,
// attitude NEES inside 96 / 98 / 100 % (tilt alone 91 / 96 / 100 %), end error
// 0.10 / 0.23 / 0.05 m of 82 m. Before: without the bias state the heading
// ratio was 2.44 / 1.94 / 2.07 and the NEES against the body's attitude
// 43 / 35 / 17 % — mostly the IMU's 0.1° mounting error, which nothing in
// the pool can reveal (95 % against the IMU's attitude, seed 1). A floor on
// the heading σ instead of the state (R grown so that an update never takes
// the heading variance below the bias's) was tried and was worse: the gyro
// bias was no longer learned (heading RMS 3.9° against 1.8°).
TEST(MemsVehicle, PoolSquareHeadingConsistentWithItsSigma)
{
	memsSeeds("config/missions/bluerov2_pool_square.yaml", "bluerov2_pool_square", {1}, true, true);
}

TEST(MemsVehicleSlow, ThreeSeedsPoolSquare)
{
	memsSeeds("config/missions/bluerov2_pool_square.yaml", "bluerov2_pool_square", {1, 2, 3}, true, true);
}

// The 20-minute lawnmower at 10 m. Measured (seeds 1-3): end error 1.26 /
// 1.67 / 1.40 m of 520 m (0.24 / 0.32 / 0.27 %), status ok.
TEST(MemsVehicleSlow, ThreeSeedsLawnmowerWithinOnePercent)
{
	memsSeeds("config/missions/bluerov2_lawnmower.yaml", "bluerov2_lawnmower", {1, 2, 3}, false, false,
	          false);
}

// With the heading-bias state (above). Measured, seeds 1-3: end error
// 0.61 / 1.35 / 0.26 m of 520 m against a 2σ of 4.04-4.07 m, position NEES
// inside 100 %, attitude NEES 95 / 96 / 97 %, worst heading error
// 1.51 / 1.45 / 1.75σ. Before the state: 2σ 1.19-1.20 m, position NEES
// 65-75 %, heading error up to 8.8σ. (A position NEES of 100 % says the σ is
// now on the generous side.)
TEST(MemsVehicleSlow, ThreeSeedsLawnmowerInsideTwoSigma)
{
	memsSeeds("config/missions/bluerov2_lawnmower.yaml", "bluerov2_lawnmower", {1, 2, 3}, true, true);
}

// A velocity error the filter is not told of: the DVL reads 5 % high on the
// lawnmower. The back-and-forth legs cancel most of it, so the position stays
// inside the filter's 2σ; the run must then say ok only while that holds,
// i.e. never 'ok' with a position outside its 2σ. Measured (seed 1): worst
// error 0.91 of 2σ, end error 2.25 m of 520 m (2σ 4.21 m), status ok.
TEST(MemsVehicle, UndisclosedDvlScaleErrorIsNeverOkWithAWrongPosition)
{
	const auto dir = simulate("config/missions/bluerov2_lawnmower.yaml", 1,
	                          {{"dvl.scale_factor_error", "0.05"}}, "_dvl_scale_5pct");
	const MemsOutcome o = runMems(dir.path(), "bluerov2_lawnmower", true, {},
	                              imuMounting("config/missions/bluerov2_lawnmower.yaml"));
	std::printf(
	    "DVL 5 %% high, lawnmower seed 1: end error %.2f m (2 sigma %.2f m), worst error / 2 sigma %.2f, "
	    "status %s (%s)\n",
	    o.end_error_m, o.end_two_sigma_m, o.worst_error_to_two_sigma, navStatusName(o.status),
	    o.reason.c_str());
	if (o.status == NavStatus::Ok)
	{
		EXPECT_LE(o.worst_error_to_two_sigma, 1.0);
	}
	EXPECT_NE(o.status, NavStatus::NotInitialized);
}

namespace
{
/** One noise figure of config/bluerov2.yaml: its key, its value there, and
 *  whether it is a variance-like density (scaled by k², the others by k). */
struct NoiseKey
{
	const char* key;
	double value;
	bool squared;
};

// Every noise figure the MEMS profile tunes (values as in config/bluerov2.yaml).
const std::vector<NoiseKey> kMemsNoise = {
    {"filter.process_noise.gyro_arw_deg_per_sqrt_h", 0.5, false},
    {"filter.process_noise.gyro_bias_deg_per_h.sigma", 500, false},
    {"filter.process_noise.accel_bias_mg.sigma", 0.5, false},
    {"filter.process_noise.jerk_psd", 1.0e-2, true},
    {"filter.process_noise.velocity_psd", 1.0e-4, true},
    {"sensors.IMU.config.vrw_mg_per_sqrt_hz", 0.1, false},
    {"sensors.IMU.config.extra_sigma_mps2", 0.05, false},
    {"sensors.DVL.config.sigma_mps", 0.01, false},
    {"sensors.PRESSURE.config.sigma_pa", 30, false},
    {"sensors.MAG.config.heading_sigma_deg", 6.0, false},
};

Overrides scaled(const std::vector<NoiseKey>& keys, double k)
{
	Overrides o;
	for (const auto& n : keys) o.emplace_back(n.key, std::to_string(n.value * (n.squared ? k * k : k)));
	return o;
}

/** The sweep of issue 13 on one simulated pool square: `keys` scaled
 *  together by each factor. Converged: the end error ≤ 1 % of the distance
 *  travelled and the monitor neither 'diverged' nor 'not_initialized'. */
void noiseSweep(const fs::path& dir, const std::vector<std::vector<NoiseKey>>& sets,
                const std::vector<double>& factors)
{
	std::printf(
	    "noise sweep, pool square: keys | factor | end error [m] | %% of distance | 2 sigma [m] | status\n");
	for (double k : factors)
		for (const auto& keys : sets)
		{
			const MemsOutcome r = runMems(dir, "bluerov2_pool_square", true, scaled(keys, k));
			const std::string what = keys.size() == 1 ? keys[0].key : "all";
			std::printf("  %s | x%.1f | %.2f | %.2f %% | %.2f | %s %s\n", what.c_str(), k, r.end_error_m,
			            100 * r.end_error_m / r.distance_m, r.end_two_sigma_m, navStatusName(r.status),
			            r.reason.c_str());
			EXPECT_LE(r.end_error_m, 0.01 * r.distance_m) << what << " x" << k;
			EXPECT_NE(r.status, NavStatus::Diverged) << what << " x" << k << ": " << r.reason;
			EXPECT_NE(r.status, NavStatus::NotInitialized) << what << " x" << k;
		}
}

std::vector<std::vector<NoiseKey>> eachKey()
{
	std::vector<std::vector<NoiseKey>> sets;
	for (const auto& n : kMemsNoise) sets.push_back({n});
	return sets;
}
}  // namespace

// Measured (seed 1): every figure alone x0.3 and x3 converges, 0.18-0.41 m of
// 82 m; status ok except gyro bias x0.3 and magnetometer sigma x0.3
// ('degraded': windowed NIS 1.75 / 2.44).
TEST(MemsVehicleSlow, NoiseSweepEachFigureAlone)
{
	const auto dir = simulate("config/missions/bluerov2_pool_square.yaml", 1);
	noiseSweep(dir.path(), eachKey(), {0.3, 3.0});
}

// All figures x3 together: 0.34 m of 82 m, status ok (seed 1).
TEST(MemsVehicle, NoiseSweepAllTimesThree)
{
	const auto dir = simulate("config/missions/bluerov2_pool_square.yaml", 1);
	noiseSweep(dir.path(), {kMemsNoise}, {3.0});
}

// All figures x0.3 together: 0.18 m of 82 m, 'degraded' (DVL NIS 2.05 per
// dimension over 30 s: the filter told its sensors are better than they
// are). Before aids were re-acquired by widening the state's covariance
// (Recovery::State) it ended 'diverged': the magnetometer rejected for good.
TEST(MemsVehicle, NoiseSweepAllTimesZeroPointThree)
{
	const auto dir = simulate("config/missions/bluerov2_pool_square.yaml", 1);
	noiseSweep(dir.path(), {kMemsNoise}, {0.3});
}
