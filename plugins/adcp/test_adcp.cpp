// The "adcp" plugin: per-cell ADCP water velocity with the two-state linear
// current profile of Arnold & Medagoda (2018), lever arm, mounting, ADCP bias.
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "adcp.h"
#include "plugin_test_support.h"

using auvnav::obs::CObservationADCP;
using auvnav::plugins::AdcpCell;
using auvnav::plugins::AdcpModel;

namespace
{
const Eigen::Vector3d kAdcpPos(0.659, -0.141, 0.206);  // flatfish_sensors.yaml adcp.position_m
constexpr uint32_t kUses = kAttitude | kGyroBias | kVelocity | kCurrentVehicle | kCurrentFar | kAdcpBias;

Eigen::Matrix3d nominalRbs()
{
	return at::rotationYpr(-22.5 * kDeg, 0, 0);
}

/** Profile geometry; the default is the FlatFish ADCP (20 cells of 0.5 m after a 0.5 m blank). */
struct Geometry
{
	double blank_m = 0.5, cell_m = 0.5;
	int cells = 20;
	double dMax() const { return blank_m + cells * cell_m; }
	double distance(int i) const { return blank_m + (i + 0.5) * cell_m; }
};

/** The ADCP model written out independently in the navigation frame (the
 *  form of the simulator): water relative to the sensor point, rotated by
 *  R_ns = R_nb R_bs, plus the horizontal bias. */
Eigen::Vector3d trueCellVelocity(const NavState& x, const FilterContext& ctx, double d, double d_max,
                                 const Eigen::Matrix3d& R_bs = nominalRbs(),
                                 const Eigen::Vector3d& r_s = kAdcpPos)
{
	const Eigen::Vector3d w_eb_b = ctx.omega_ib_b - x.b_w - x.R_nb.transpose() * ctx.omega_ie_n;
	const Eigen::Vector3d v_s_n = x.v_n + x.R_nb * w_eb_b.cross(r_s - ctx.imu_position_b);
	const double w = d / d_max;
	const Eigen::Vector2d c = x.current_vehicle_ne + w * (x.current_far_ne - x.current_vehicle_ne);
	const Eigen::Matrix3d R_ns = x.R_nb * R_bs;
	return R_ns.transpose() * (Eigen::Vector3d(c.x(), c.y(), 0) - v_s_n) +
	       Eigen::Vector3d(x.b_adcp.x(), x.b_adcp.y(), 0);
}

CObservationADCP::Ptr emptyObs(const Geometry& g = {}, double sigma = 0.03)
{
	auto o = CObservationADCP::Create();
	o->sensorLabel = "ADCP";
	o->blank_distance_m = g.blank_m;
	o->cell_size_m = g.cell_m;
	o->velocity_sigma_mps = sigma;
	// The nominal mounting, as the simulator writes it.
	o->sensorPose = mrpt::poses::CPose3D(kAdcpPos.x(), kAdcpPos.y(), kAdcpPos.z(), -22.5 * kDeg, 0, 0);
	return o;
}

/** A profile of `truth`: every cell valid with correlation 0.95 − 0.02 i (as
 *  the simulator's mean), noise `sigma_noise` per axis; cells from
 *  `first_invalid` on are flagged invalid (cut by the seabed) and carry the
 *  bottom echo instead of the water. */
CObservationADCP::Ptr profileOf(const NavState& truth, const FilterContext& ctx, const Geometry& g = {},
                                double sigma_noise = 0, uint32_t seed = 1, int first_invalid = 1 << 30)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> n01(0.0, 1.0);
	auto o = emptyObs(g);
	for (int i = 0; i < g.cells; ++i)
	{
		auvnav::obs::AdcpCell c;
		Eigen::Vector3d v = trueCellVelocity(truth, ctx, g.distance(i), g.dMax());
		if (i >= first_invalid)
		{
			NavState ground = truth;  // seabed: no current
			ground.current_vehicle_ne.setZero();
			ground.current_far_ne.setZero();
			v = trueCellVelocity(ground, ctx, g.distance(i), g.dMax());
		}
		v += sigma_noise * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
		for (int k = 0; k < 3; ++k) c.velocity_s_mps[k] = v[k];
		c.correlation = 0.95 - 0.02 * i;
		c.valid = i < first_invalid;
		o->cells.push_back(c);
	}
	return o;
}

/** The model with its skipped measurements removed (counted), so the SDK's
 *  IsWellFormed checks exactly the measurements the filter applies.
 *  (model_checks.h predates Measurement::skipped.) */
class AppliedCellsOnly final : public MeasurementModel
{
 public:
	explicit AppliedCellsOnly(MeasurementModel& m) : m_(m) {}
	uint32_t uses() const noexcept override { return m_.uses(); }
	PrepareStatus prepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                      std::vector<Measurement>& out, std::string& why) noexcept override
	{
		const PrepareStatus st = m_.prepare(obs, ctx, out, why);
		const auto it =
		    std::remove_if(out.begin(), out.end(), [](const Measurement& m) { return m.skipped; });
		skipped = static_cast<std::size_t>(out.end() - it);
		out.erase(it, out.end());
		applied = out.size();
		return st;
	}
	bool predict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	             Eigen::Ref<Eigen::VectorXd> z_pred) const noexcept override
	{
		return m_.predict(x, m, ctx, z_pred);
	}
	void residual(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& z_pred,
	              Eigen::Ref<Eigen::VectorXd> r) const noexcept override
	{
		m_.residual(z, z_pred, r);
	}
	double gateProbability() const noexcept override { return m_.gateProbability(); }
	MeasurementStructure structure() const noexcept override { return m_.structure(); }
	bool affineSlopes(const NavState& x, const Measurement& m, const FilterContext& ctx, int from, int to,
	                  Eigen::Ref<Eigen::MatrixXd> At) const noexcept override
	{
		return m_.affineSlopes(x, m, ctx, from, to, At);
	}
	std::size_t skipped = 0, applied = 0;

 private:
	MeasurementModel& m_;
};

std::size_t countSkipped(const std::vector<Measurement>& out)
{
	return static_cast<std::size_t>(
	    std::count_if(out.begin(), out.end(), [](const Measurement& m) { return m.skipped; }));
}

/** As the navigator does: skipped cells are counted, the others updated one by one. */
struct CellUpdates
{
	PrepareStatus status = PrepareStatus::Invalid;
	std::size_t skipped = 0;
	std::vector<std::pair<int, UpdateResult>> updates;  // (cell index, result)
	int count(UpdateStatus s) const
	{
		return static_cast<int>(std::count_if(updates.begin(), updates.end(),
		                                      [s](const auto& u) { return u.second.status == s; }));
	}
};
CellUpdates applyCells(ManifoldUkf& ukf, AdcpModel& model, const CObservationADCP& o,
                       const FilterContext& ctx)
{
	CellUpdates r;
	std::vector<Measurement> out;
	std::string why;
	r.status = model.prepare(o, ctx, out, why);
	for (const auto& m : out)
	{
		if (m.skipped)
			++r.skipped;
		else
			r.updates.emplace_back(m.tag, ukf.update(model, m, ctx));
	}
	return r;
}

/** Level vehicle facing east at 1 m/s, the example of the hand computations. */
NavState eastbound()
{
	NavState x;
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);
	x.v_n = Eigen::Vector3d(0, 1, 0);
	x.current_vehicle_ne = Eigen::Vector2d(0.2, 0);
	x.current_far_ne = Eigen::Vector2d(0, 0.1);
	return x;
}
}  // namespace

// ---------------------------------------------------------------- configuration

TEST(Adcp, DefaultConfigMatchesFlatfishMounting)
{
	const AdcpModel m(pt::defaultConfig(), "ADCP");
	EXPECT_TRUE(m.position_b().isApprox(kAdcpPos, 1e-15));
	EXPECT_TRUE(m.R_bs().isApprox(nominalRbs(), 1e-15));
	EXPECT_EQ(m.uses(), kUses);
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	EXPECT_DOUBLE_EQ(m.minCorrelation(), 0.5);
	EXPECT_DOUBLE_EQ(m.extraSigma_mps(), 0.02);
	EXPECT_EQ(m.sigma_mps(), 0.0);               // from the observation
	EXPECT_TRUE(std::isinf(m.maxDistance_m()));  // no limit
	// The empty configuration gives the same defaults as the shipped file.
	const AdcpModel e(pt::configText("{}"), "ADCP");
	EXPECT_TRUE(e.R_bs().isApprox(m.R_bs(), 1e-15));
	EXPECT_TRUE(e.position_b() == m.position_b());
	EXPECT_EQ(e.minCorrelation(), m.minCorrelation());
	EXPECT_EQ(e.extraSigma_mps(), m.extraSigma_mps());
	EXPECT_EQ(e.sigma_mps(), m.sigma_mps());
	EXPECT_EQ(e.maxDistance_m(), m.maxDistance_m());
	EXPECT_EQ(e.gateProbability(), m.gateProbability());
	const AdcpModel c(
	    pt::configText("{sigma_mps: 0.1, max_distance_m: 6, min_correlation: 0.7, gate_probability: 1}"),
	    "ADCP");
	EXPECT_EQ(c.sigma_mps(), 0.1);
	EXPECT_EQ(c.maxDistance_m(), 6.0);
	EXPECT_EQ(c.minCorrelation(), 0.7);
	EXPECT_EQ(c.gateProbability(), 1.0);
}

TEST(Adcp, RejectsBadConfigNamingTheKey)
{
	for (const char* yaml :
	     {"position_m: [1, 2]", "orientation_ypr_deg: [a, 0, 0]", "sigma_mps: 0", "extra_sigma_mps: -0.1",
	      "min_correlation: 1.5", "max_distance_m: -2", "max_distance_m: 0", "use_observation_pose: perhaps",
	      "gate_probability: 0", "position_m: [200, 0, 0]"})
		EXPECT_TRUE(pt::ConstructorRefuses<AdcpModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("min_correlation: -1", "min_correlation"));
	EXPECT_TRUE(pt::ModuleRefuses("sigma_mps: -1", "sigma_mps"));
}

TEST(Adcp, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("adcp", pt::defaultConfigText(), kUses));
}

// ---------------------------------------------------------------- contract

TEST(Adcp, WellFormedOnRealisticObservationsAndRandomStates)
{
	pt::FlatfishContext tc;
	for (const char* cfg : {"{}", "use_observation_pose: true", "{sigma_mps: 0.04, max_distance_m: 7}"})
	{
		AdcpModel model(pt::configText(cfg), "ADCP");
		AppliedCellsOnly applied(model);
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			tc.ctx().omega_ib_b = Eigen::Vector3d(0.02, -0.01, 0.1 * std::sin(seed));
			// The profile of another random state (a wrong filter state is
			// the normal case), noisy, the far cells cut by the seabed.
			const auto o =
			    profileOf(at::RandomNavState(seed + 50), tc.ctx(), Geometry{}, 0.03, seed, 12 + seed % 8);
			EXPECT_TRUE(pt::IsWellFormedAndUsed(applied, *o, tc.ctx(), at::RandomNavState(seed), seed))
			    << cfg << ", seed " << seed;
			EXPECT_EQ(applied.applied + applied.skipped, o->cells.size());
			EXPECT_GE(applied.applied, 10u);
		}
	}
}

// ---------------------------------------------------------------- the profile interpolation

TEST(Adcp, FarWeightIsDistanceOverProfileEnd)
{
	using auvnav::plugins::adcpCellCurrent;
	using auvnav::plugins::adcpFarWeight;
	EXPECT_EQ(adcpFarWeight(0.0, 10.5), 0.0);
	EXPECT_EQ(adcpFarWeight(10.5, 10.5), 1.0);
	EXPECT_EQ(adcpFarWeight(5.25, 10.5), 0.5);
	EXPECT_TRUE(std::isnan(adcpFarWeight(1.0, 0.0)));
	const Eigen::Vector2d cv(0.2, -0.07), cf(-0.05, 0.13);
	EXPECT_EQ(adcpCellCurrent(cv, cf, 0.0), Eigen::Vector3d(0.2, -0.07, 0));   // exactly current_vehicle
	EXPECT_EQ(adcpCellCurrent(cv, cf, 1.0), Eigen::Vector3d(-0.05, 0.13, 0));  // exactly current_far
	const Eigen::Vector3d mid = adcpCellCurrent(cv, cf, 0.5);
	EXPECT_NEAR(mid.x(), 0.075, 1e-16);
	EXPECT_NEAR(mid.y(), 0.03, 1e-16);
	EXPECT_EQ(mid.z(), 0.0);
}

TEST(Adcp, DistancesComeFromTheObservationGeometry)
{
	at::TestContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	// FlatFish: d_i = 0.5 + (i + 0.5) 0.5, d_max = 0.5 + 20 · 0.5 = 10.5.
	auto out = pt::prepareAll(model, *profileOf(NavState{}, tc.ctx()), tc.ctx());
	ASSERT_EQ(out.size(), 20u);
	for (int i = 0; i < 20; ++i)
	{
		EXPECT_EQ(out[i].tag, i);
		EXPECT_DOUBLE_EQ(out[i].payload<AdcpCell>().distance_m, 0.75 + 0.5 * i);
		EXPECT_DOUBLE_EQ(out[i].payload<AdcpCell>().max_distance_m, 10.5);
	}
	// Another instrument setting: d_max follows the observation, not a fixed cell count.
	out = pt::prepareAll(model, *profileOf(NavState{}, tc.ctx(), Geometry{1.0, 2.0, 7}), tc.ctx());
	ASSERT_EQ(out.size(), 7u);
	EXPECT_DOUBLE_EQ(out[0].payload<AdcpCell>().distance_m, 2.0);
	EXPECT_DOUBLE_EQ(out[6].payload<AdcpCell>().distance_m, 14.0);
	for (const auto& m : out) EXPECT_DOUBLE_EQ(m.payload<AdcpCell>().max_distance_m, 15.0);
	// Invalid cells still count in d_max (the profile's extent is the instrument's).
	auto o = profileOf(NavState{}, tc.ctx(), Geometry{1.0, 2.0, 7}, 0, 1, 3);
	out = pt::prepareAll(model, *o, tc.ctx());
	EXPECT_DOUBLE_EQ(out[2].payload<AdcpCell>().max_distance_m, 15.0);
}

TEST(Adcp, NavigatorFixedFarDistanceOverridesTheGeometry)
{
	// The navigator owns what current_far_ne means when it moves the currents
	// along the profile with depth (ProcessModel::current_far_distance_m).
	at::TestContext tc;
	tc.ctx().current_far_distance_m = 6.0;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	const auto out = pt::prepareAll(model, *profileOf(NavState{}, tc.ctx()), tc.ctx());
	ASSERT_EQ(out.size(), 20u);
	for (const auto& m : out) EXPECT_DOUBLE_EQ(m.payload<AdcpCell>().max_distance_m, 6.0);
	EXPECT_DOUBLE_EQ(out[0].payload<AdcpCell>().distance_m, 0.75);  // distances still from the observation
	// A cell beyond that distance extrapolates the same linear profile.
	NavState x;
	x.current_vehicle_ne = Eigen::Vector2d(0.1, 0.0);
	x.current_far_ne = Eigen::Vector2d(0.0, 0.0);
	EXPECT_NEAR(
	    plugins::adcpCellCurrent(x.current_vehicle_ne, x.current_far_ne, plugins::adcpFarWeight(9.0, 6.0))
	        .x(),
	    -0.05, 1e-15);
}

TEST(Adcp, CellsAtTheEndsSeeExactlyTheTwoCurrentStates)
{
	at::TestContext tc;
	tc.ctx().omega_ie_n.setZero();
	AdcpModel model(pt::defaultConfig(), "ADCP");
	const NavState x = eastbound();
	// Same state with a uniform current equal to the vehicle, the far and the mean current.
	NavState uni_v = x, uni_f = x, uni_mid = x;
	uni_v.current_far_ne = x.current_vehicle_ne;
	uni_f.current_vehicle_ne = x.current_far_ne;
	uni_mid.current_vehicle_ne = uni_mid.current_far_ne = 0.5 * (x.current_vehicle_ne + x.current_far_ne);

	// Blank 0, three 1 m cells: the middle cell's centre is at 1.5 m = d_max / 2.
	const auto out = pt::prepareAll(model, *profileOf(NavState{}, tc.ctx(), Geometry{0.0, 1.0, 3}), tc.ctx());
	ASSERT_EQ(out.size(), 3u);
	EXPECT_DOUBLE_EQ(out[1].payload<AdcpCell>().distance_m, 1.5);
	EXPECT_DOUBLE_EQ(out[1].payload<AdcpCell>().max_distance_m, 3.0);
	EXPECT_TRUE(at::Predict(model, out[1], tc.ctx(), x)
	                .isApprox(at::Predict(model, out[1], tc.ctx(), uni_mid), 1e-15));

	// A cell centred at the transducer (d = 0) and one at the far end (d = d_max):
	// no real geometry has them, so the carried distance is set directly.
	Measurement at_0 = out[1], at_end = out[1];
	at_0.payload<AdcpCell>().distance_m = 0.0;
	at_end.payload<AdcpCell>().distance_m = at_end.payload<AdcpCell>().max_distance_m;
	EXPECT_EQ(at::Predict(model, at_0, tc.ctx(), x), at::Predict(model, at_0, tc.ctx(), uni_v));
	EXPECT_EQ(at::Predict(model, at_end, tc.ctx(), x), at::Predict(model, at_end, tc.ctx(), uni_f));
	// ... and the far current has no effect at d = 0, the vehicle current none at d_max.
	NavState other = x;
	other.current_far_ne = Eigen::Vector2d(5, -5);
	EXPECT_EQ(at::Predict(model, at_0, tc.ctx(), x), at::Predict(model, at_0, tc.ctx(), other));
	other = x;
	other.current_vehicle_ne = Eigen::Vector2d(5, -5);
	EXPECT_EQ(at::Predict(model, at_end, tc.ctx(), x), at::Predict(model, at_end, tc.ctx(), other));
}

// ---------------------------------------------------------------- h by hand

TEST(Adcp, HandComputedLevelHeading90Through22_5DegreeMount)
{
	// Level, facing east (body x = east, body y = south), v_n = (0, 1, 0),
	// current_vehicle = (0.2, 0), current_far = (0, 0.1), no rotation, no bias.
	pt::FlatfishContext tc;
	tc.ctx().omega_ie_n.setZero();
	AdcpModel model(pt::defaultConfig(), "ADCP");
	const NavState x = eastbound();
	const auto out = pt::prepareAll(model, *profileOf(NavState{}, tc.ctx(), Geometry{0.0, 1.0, 3}), tc.ctx());
	ASSERT_EQ(out.size(), 3u);
	const double c = std::cos(22.5 * kDeg), s = std::sin(22.5 * kDeg);  // 0.92388, 0.38268
	// Sensor frame = body yawed −22.5°: z_s = Rz(+22.5°) z_b.
	auto toSensor = [&](double bx, double by) { return Eigen::Vector2d(c * bx - s * by, s * bx + c * by); };

	// Middle cell, w = 0.5: c = (0.1, 0.05); c − v = (0.1, −0.95) N/E → body (−0.95, −0.1).
	Eigen::VectorXd h = at::Predict(model, out[1], tc.ctx(), x);
	EXPECT_NEAR(h[0], -0.8394172, 1e-7);
	EXPECT_NEAR(h[1], -0.4559372, 1e-7);
	EXPECT_NEAR(h[2], 0.0, 1e-15);
	EXPECT_NEAR(h[0], toSensor(-0.95, -0.1).x(), 1e-15);
	EXPECT_NEAR(h[1], toSensor(-0.95, -0.1).y(), 1e-15);

	// First cell, d = 0.5 of 3 m, w = 1/6: c = (1/6, 1/60); c − v → body (1/60 − 1, −1/6).
	h = at::Predict(model, out[0], tc.ctx(), x);
	EXPECT_NEAR(h[0], toSensor(1.0 / 60 - 1, -1.0 / 6).x(), 1e-15);
	EXPECT_NEAR(h[1], toSensor(1.0 / 60 - 1, -1.0 / 6).y(), 1e-15);
	EXPECT_NEAR(h[0], -0.8447010, 1e-7);
	EXPECT_NEAR(h[1], -0.5302853, 1e-7);

	// At d = 0: water (0.2, 0) − v → body (−1, −0.2); at d_max: (0, 0.1) − v → body (−0.9, 0).
	Measurement m = out[1];
	m.payload<AdcpCell>().distance_m = 0;
	h = at::Predict(model, m, tc.ctx(), x);
	EXPECT_NEAR(h[0], -c + 0.2 * s, 1e-15);
	EXPECT_NEAR(h[1], -s - 0.2 * c, 1e-15);
	m.payload<AdcpCell>().distance_m = m.payload<AdcpCell>().max_distance_m;
	h = at::Predict(model, m, tc.ctx(), x);
	EXPECT_NEAR(h[0], -0.9 * c, 1e-15);
	EXPECT_NEAR(h[1], -0.9 * s, 1e-15);
	EXPECT_NEAR(h[2], 0.0, 1e-15);

	// Sinking at 0.1 m/s: the water rises past the sensor, z_s = −0.1.
	NavState sinking = x;
	sinking.v_n.z() = 0.1;
	EXPECT_NEAR(at::Predict(model, out[1], tc.ctx(), sinking)[2], -0.1, 1e-15);
}

TEST(Adcp, AdcpBiasAppearsInSensorXYOnly)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, 0.02, -0.05);
	AdcpModel model(pt::defaultConfig(), "ADCP");
	NavState x = at::RandomNavState(3);
	x.b_adcp.setZero();
	const auto out = pt::prepareAll(model, *profileOf(x, tc.ctx()), tc.ctx());
	NavState biased = x;
	biased.b_adcp = Eigen::Vector2d(0.1, -0.2);
	for (const auto& m : out)
	{
		const Eigen::VectorXd d =
		    at::Predict(model, m, tc.ctx(), biased) - at::Predict(model, m, tc.ctx(), x);
		EXPECT_NEAR(d[0], 0.1, 1e-14);
		EXPECT_NEAR(d[1], -0.2, 1e-14);
		EXPECT_EQ(d[2], 0.0);
	}
}

TEST(Adcp, LeverArmAndEarthRate)
{
	// At rest on the rotating Earth in still water, the gyro reads R_nbᵀ ω_ie + b_w:
	// the sensor does not move relative to the water, every cell sees 0.
	pt::FlatfishContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	NavState x;
	x.R_nb = at::rotationYpr(40 * kDeg, 5 * kDeg, -3 * kDeg);
	x.b_w = Eigen::Vector3d(0.01, -0.02, 0.03);
	tc.ctx().omega_ib_b = x.R_nb.transpose() * tc.ctx().omega_ie_n + x.b_w;
	const auto out = pt::prepareAll(model, *profileOf(x, tc.ctx()), tc.ctx());
	for (const auto& m : out) EXPECT_LT(at::Predict(model, m, tc.ctx(), x).norm(), 1e-15);

	// Turning to starboard at 0.1 rad/s around a resting IMU point: the sensor
	// moves with ω × (r_adcp − r_imu) and sees the water move the other way.
	pt::FlatfishContext tc2;
	tc2.ctx().omega_ie_n.setZero();
	tc2.ctx().omega_ib_b = Eigen::Vector3d(0, 0, 0.1);
	const NavState level;
	const auto out2 = pt::prepareAll(model, *profileOf(level, tc2.ctx()), tc2.ctx());
	const Eigen::VectorXd h = at::Predict(model, out2[0], tc2.ctx(), level);
	// ω × (0.36476, −0.141, 0.23463) = (0.0141, 0.036476, 0) body; negated, into the sensor frame.
	const double c = std::cos(22.5 * kDeg), s = std::sin(22.5 * kDeg);
	EXPECT_NEAR(h[0], -(c * 0.0141 - s * 0.036476), 1e-12);
	EXPECT_NEAR(h[1], -(s * 0.0141 + c * 0.036476), 1e-12);
	EXPECT_NEAR(h[2], 0.0, 1e-12);
}

TEST(Adcp, SimulatorConventionsTranscribed)
{
	// apps/sim/sensors.cpp AdcpSim::sample, transcribed (the plugin cannot link
	// the simulator): vehicle state at the CG, gyro as ImuSim, a current that
	// is linear in depth below the sensor, cells along the sensor z axis.
	pt::FlatfishContext tc;
	const Eigen::Quaterniond q_nb(at::rotationYpr(130 * kDeg, 0, 0));  // level: cells straight down
	Eigen::Matrix<double, 6, 1> nu_b;
	nu_b << 0.9, -0.1, 0.05, 0.0, 0.0, 0.08;  // [v_b; ω_b] over ground
	const Eigen::Vector3d p_n(10, -20, 6);
	const Eigen::Vector3d gyro_bias(2e-4, -1e-4, 3e-4);
	const Eigen::Vector2d adcp_bias(0.012, -0.007);
	const Geometry g;
	const double d_max = g.dMax();
	const Eigen::Vector2d c_top(0.15, 0.05), c_bottom(0.05, -0.03);  // at the sensor depth and d_max below
	const Eigen::Matrix3d R_nb = q_nb.toRotationMatrix();
	// pointOnVehicle(x, mount.position_b)
	const Eigen::Vector3d w_b = nu_b.tail<3>();
	const Eigen::Vector3d s_v_n = R_nb * (nu_b.head<3>() + w_b.cross(kAdcpPos));
	const Eigen::Vector3d s_p_n = p_n + R_nb * kAdcpPos;
	const Eigen::Matrix3d R_ns = R_nb * nominalRbs();  // R_bs_true = nominal (no misalignment here)
	const Eigen::Vector3d axis_n = R_ns.col(2);
	auto current = [&](double depth)
	{
		const double w = (depth - s_p_n.z()) / d_max;
		const Eigen::Vector2d c = c_top + w * (c_bottom - c_top);
		return Eigen::Vector3d(c.x(), c.y(), 0.0);
	};
	auto o = emptyObs(g);
	const Eigen::Vector3d bias_s(adcp_bias.x(), adcp_bias.y(), 0.0);
	for (int i = 0; i < g.cells; ++i)
	{
		auvnav::obs::AdcpCell cell;
		const double d = o->cellDistance(i);
		const Eigen::Vector3d p_cell = s_p_n + d * axis_n;
		const Eigen::Vector3d rel_n = current(p_cell.z()) - s_v_n;
		const Eigen::Vector3d v_s = R_ns.transpose() * rel_n + bias_s;
		for (int k = 0; k < 3; ++k) cell.velocity_s_mps[k] = v_s[k];
		cell.correlation = 0.95 - 0.02 * i;
		cell.valid = true;
		o->cells.push_back(cell);
	}
	// The filter's view of the same instant: IMU point velocity, raw gyro sample.
	NavState x;
	x.R_nb = R_nb;
	x.b_w = gyro_bias;
	x.v_n = R_nb * (nu_b.head<3>() + w_b.cross(kImuPos));
	x.p_n = p_n + R_nb * kImuPos;
	x.current_vehicle_ne = c_top;
	x.current_far_ne = c_bottom;
	x.b_adcp = adcp_bias;
	tc.ctx().omega_ib_b = w_b + R_nb.transpose() * tc.ctx().omega_ie_n + gyro_bias;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	const auto out = pt::prepareAll(model, *o, tc.ctx());
	ASSERT_EQ(out.size(), 20u);
	for (const auto& m : out)
	{
		ASSERT_FALSE(m.skipped);
		const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
		EXPECT_LT((h - m.z).cwiseAbs().maxCoeff(), 1e-14)
		    << "cell " << m.tag << ": h " << h.transpose() << ", z " << m.z.transpose();
	}
}

// ---------------------------------------------------------------- cells that are not applied

TEST(Adcp, InvalidCellsAreSkippedAndCounted)
{
	at::TestContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	auto o = profileOf(eastbound(), tc.ctx(), Geometry{0.5, 0.5, 10});
	o->cells[1].valid = false;
	o->cells[2].correlation = 0.3;
	o->cells[3].velocity_s_mps[1] = std::nan("");  // valid, but NaN
	o->cells[4].velocity_s_mps[2] = HUGE_VAL;
	o->cells[5].valid = false;  // invalid and NaN: counted as invalid
	o->cells[5].velocity_s_mps[0] = std::nan("");
	o->cells[6].correlation = std::nan("");
	o->cells[7].correlation = 0.5;  // exactly at the threshold: used
	auto out = pt::prepareAll(model, *o, tc.ctx());
	ASSERT_EQ(out.size(), 10u);  // every cell accounted for
	EXPECT_EQ(countSkipped(out), 6u);
	const char* expected[10] = {"cell",
	                            AdcpModel::kSkipInvalid,
	                            AdcpModel::kSkipCorrelation,
	                            AdcpModel::kSkipNonFinite,
	                            AdcpModel::kSkipNonFinite,
	                            AdcpModel::kSkipInvalid,
	                            AdcpModel::kSkipCorrelation,
	                            "cell",
	                            "cell",
	                            "cell"};
	for (int i = 0; i < 10; ++i)
	{
		EXPECT_EQ(out[i].tag, i);
		EXPECT_EQ(out[i].label, expected[i]) << "cell " << i;
		EXPECT_EQ(out[i].skipped, std::string(expected[i]) != "cell") << "cell " << i;
		if (out[i].skipped)
			EXPECT_EQ(out[i].z.size(), 0);
		else
			EXPECT_TRUE(out[i].z.allFinite() && out[i].z.size() == 3);
	}

	// A stricter threshold and a range limit (cell centres at 0.75 + 0.5 i).
	AdcpModel strict(pt::configText("{min_correlation: 0.78, max_distance_m: 4.0}"), "ADCP");
	auto clean = profileOf(eastbound(), tc.ctx(), Geometry{0.5, 0.5, 10});  // correlations 0.95 − 0.02 i
	out = pt::prepareAll(strict, *clean, tc.ctx());
	ASSERT_EQ(out.size(), 10u);
	// Cells 0..6 are within 4 m (cell 6 at 3.75 m), 7..9 beyond; cell 9 (0.77) is also
	// below 0.78 and reported as low correlation (checked first).
	for (int i = 0; i < 7; ++i) EXPECT_FALSE(out[i].skipped) << i;
	EXPECT_EQ(out[7].label, AdcpModel::kSkipDistance);
	EXPECT_EQ(out[8].label, AdcpModel::kSkipDistance);
	EXPECT_EQ(out[9].label, AdcpModel::kSkipCorrelation);
	EXPECT_EQ(countSkipped(out), 3u);

	// All cells unusable: still Ok, every cell counted as skipped, nothing to update.
	for (auto& c : clean->cells) c.valid = false;
	out = pt::prepareAll(model, *clean, tc.ctx());
	EXPECT_EQ(out.size(), 10u);
	EXPECT_EQ(countSkipped(out), 10u);
}

TEST(Adcp, MalformedObservationIsInvalid)
{
	at::TestContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	AdcpModel obs_pose(pt::configText("use_observation_pose: true"), "ADCP");
	const auto good = profileOf(eastbound(), tc.ctx());
	std::vector<Measurement> out;
	std::string why;
	for (double bad : {0.0, -0.5, std::nan(""), HUGE_VAL})
	{
		auto o = profileOf(eastbound(), tc.ctx());
		o->cell_size_m = bad;
		out.assign(3, Measurement{});
		EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid) << "cell size " << bad;
		EXPECT_TRUE(out.empty());
		EXPECT_NE(why.find("cell size"), std::string::npos) << why;
	}
	for (double bad : {-0.1, std::nan(""), HUGE_VAL})
	{
		auto o = profileOf(eastbound(), tc.ctx());
		o->blank_distance_m = bad;
		EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid) << "blank " << bad;
		EXPECT_NE(why.find("blank"), std::string::npos) << why;
	}
	// A sensor pose that is not finite matters only when it is used.
	auto o = profileOf(eastbound(), tc.ctx());
	o->sensorPose = mrpt::poses::CPose3D(NAN, 0, 0, 0, 0, 0);
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Ok);
	EXPECT_EQ(obs_pose.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_EQ(obs_pose.prepare(*good, tc.ctx(), out, why), PrepareStatus::Ok);
	// Wrong class.
	EXPECT_TRUE(pt::RefusesOtherClass<obs::CObservationDVL>(model, tc.ctx(), "CObservationADCP"));
	// No cells at all: nothing to apply, not an error.
	auto empty = emptyObs();
	EXPECT_EQ(model.prepare(*empty, tc.ctx(), out, why), PrepareStatus::Skip);
	EXPECT_TRUE(out.empty());
}

TEST(Adcp, NoiseFromObservationOrConfigPlusRepresentationError)
{
	at::TestContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	auto o = profileOf(eastbound(), tc.ctx(), Geometry{0.5, 0.5, 4});
	const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
	o->velocity_sigma_mps = 0.03;  // the observation's own σ
	for (const auto& m : pt::prepareAll(model, *o, tc.ctx()))
		EXPECT_TRUE(m.R.isApprox((0.03 * 0.03 + 0.02 * 0.02) * I, 1e-15));
	EXPECT_DOUBLE_EQ(pt::prepareAll(model, *o, tc.ctx())[0].R(0, 0), 0.0013);
	for (double unusable : {0.0, -0.1, std::nan(""), HUGE_VAL})
	{
		o->velocity_sigma_mps = unusable;  // default 0.05
		for (const auto& m : pt::prepareAll(model, *o, tc.ctx()))
			EXPECT_TRUE(m.R.isApprox((0.05 * 0.05 + 0.02 * 0.02) * I, 1e-15)) << unusable << "\n" << m.R;
	}
	o->velocity_sigma_mps = 0.03;
	AdcpModel configured(pt::configText("{sigma_mps: 0.1, extra_sigma_mps: 0}"), "ADCP");
	for (const auto& m : pt::prepareAll(configured, *o, tc.ctx())) EXPECT_TRUE(m.R.isApprox(0.01 * I, 1e-15));
	AdcpModel no_extra(pt::configText("extra_sigma_mps: 0"), "ADCP");
	for (const auto& m : pt::prepareAll(no_extra, *o, tc.ctx())) EXPECT_TRUE(m.R.isApprox(0.0009 * I, 1e-15));
}

// ---------------------------------------------------------------- with the filter

namespace
{
/** A state after DVL aiding: velocity known to 1 cm/s, currents unknown. */
Covariance covarianceAfterDvl(double current_sigma = 0.2)
{
	Covariance P = at::TypicalCovariance();
	P.block<3, 3>(idx::att, idx::att) = std::pow(0.5 * kDeg, 2) * Eigen::Matrix3d::Identity();
	P.block<3, 3>(idx::vel, idx::vel) = 0.01 * 0.01 * Eigen::Matrix3d::Identity();
	P.block<4, 4>(idx::current_vehicle, idx::current_vehicle) =
	    current_sigma * current_sigma * Eigen::Matrix4d::Identity();
	P.block<2, 2>(idx::adcp_bias, idx::adcp_bias) = 0.01 * 0.01 * Eigen::Matrix2d::Identity();
	return P;
}

NavState cruising()
{
	NavState x;
	x.R_nb = at::rotationYpr(30 * kDeg, 2 * kDeg, -1 * kDeg);
	x.v_n = Eigen::Vector3d(0.8, 0.45, 0.05);
	x.p_n = Eigen::Vector3d(50, 20, 8);
	x.b_adcp = Eigen::Vector2d(0.004, -0.003);
	return x;
}
}  // namespace

TEST(Adcp, UpdatePullsCurrentsTowardTruth)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, -0.02, 0.05);
	AdcpModel model(pt::defaultConfig(), "ADCP");
	const Eigen::Vector2d truth_c(0.3, -0.1);
	for (const Eigen::Vector2d& truth_far : {Eigen::Vector2d(0.3, -0.1), Eigen::Vector2d(0.1, 0.05)})
	{
		NavState truth = cruising();
		truth.current_vehicle_ne = truth_c;
		truth.current_far_ne = truth_far;
		NavState x0 = truth;  // currents start at 0 with σ 0.2
		x0.current_vehicle_ne.setZero();
		x0.current_far_ne.setZero();
		ManifoldUkf ukf = pt::filterAt(x0, covarianceAfterDvl(0.2));
		const auto res = applyCells(ukf, model, *profileOf(truth, tc.ctx()), tc.ctx());
		ASSERT_EQ(res.status, PrepareStatus::Ok);
		EXPECT_EQ(res.skipped, 0u);
		ASSERT_EQ(res.updates.size(), 20u);
		EXPECT_EQ(res.count(UpdateStatus::Accepted), 20);
		const double ev0 = truth_c.norm(), ef0 = truth_far.norm();
		const double ev = (ukf.state().current_vehicle_ne - truth_c).norm();
		const double ef = (ukf.state().current_far_ne - truth_far).norm();
		EXPECT_LT(ev, 0.15 * ev0) << "current_vehicle " << ukf.state().current_vehicle_ne.transpose();
		EXPECT_LT(ef, 0.15 * ef0 + 0.01) << "current_far " << ukf.state().current_far_ne.transpose();
		// Both current blocks became much more certain.
		EXPECT_LT((ukf.covariance().block<2, 2>(idx::current_vehicle, idx::current_vehicle).trace()),
		          0.1 * 0.08);
		EXPECT_LT((ukf.covariance().block<2, 2>(idx::current_far, idx::current_far).trace()), 0.1 * 0.08);
		EXPECT_EQ(ukf.choleskyRepairs(), 0u);
	}
}

TEST(Adcp, GrossOutlierCellRejectedByTheGateOthersAccepted)
{
	pt::FlatfishContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	NavState truth = cruising();
	truth.current_vehicle_ne = Eigen::Vector2d(0.3, -0.1);
	truth.current_far_ne = Eigen::Vector2d(0.2, 0.0);
	auto o = profileOf(truth, tc.ctx(), Geometry{}, 0.03, 11);
	o->cells[7].velocity_s_mps[0] += 2.0;  // 2 m/s off
	NavState x0 = truth;
	x0.current_vehicle_ne.setZero();
	x0.current_far_ne.setZero();
	ManifoldUkf ukf = pt::filterAt(x0, covarianceAfterDvl(0.2));
	const auto res = applyCells(ukf, model, *o, tc.ctx());
	ASSERT_EQ(res.updates.size(), 20u);
	for (const auto& [cell, r] : res.updates)
		EXPECT_EQ(r.status, cell == 7 ? UpdateStatus::Rejected : UpdateStatus::Accepted)
		    << "cell " << cell << " NIS " << r.nis;
	EXPECT_EQ(res.count(UpdateStatus::Rejected), 1);
	EXPECT_EQ(res.count(UpdateStatus::Accepted), 19);
	EXPECT_GT(res.updates[7].second.nis, ManifoldUkf::chiSquareQuantile(3, 0.999));
	EXPECT_EQ(res.updates[7].second.dim, 3);
	// The outlier did not spoil the estimate.
	EXPECT_LT((ukf.state().current_vehicle_ne - truth.current_vehicle_ne).norm(), 0.06);

	// Without the gate the same cell is applied.
	AdcpModel ungated(pt::configText("gate_probability: 1"), "ADCP");
	ManifoldUkf ukf2 = pt::filterAt(x0, covarianceAfterDvl(0.2));
	const auto res2 = applyCells(ukf2, ungated, *o, tc.ctx());
	EXPECT_EQ(res2.count(UpdateStatus::Accepted), 20);
}

TEST(Adcp, SkippedCellsNeverChangeTheState)
{
	at::TestContext tc;
	AdcpModel model(pt::defaultConfig(), "ADCP");
	auto o = profileOf(eastbound(), tc.ctx(), Geometry{0.5, 0.5, 6});
	for (auto& c : o->cells) c.valid = false;
	o->cells[2].velocity_s_mps[0] = NAN;
	ManifoldUkf ukf = pt::filterAt(cruising(), covarianceAfterDvl());
	const NavState before = ukf.state();
	const Covariance P_before = ukf.covariance();
	const auto res = applyCells(ukf, model, *o, tc.ctx());
	EXPECT_EQ(res.status, PrepareStatus::Ok);
	EXPECT_EQ(res.skipped, 6u);
	EXPECT_TRUE(res.updates.empty());
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), before));
	EXPECT_TRUE(ukf.covariance() == P_before);
}
