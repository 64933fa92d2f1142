#pragma once
/** @file plugin_test_support.h
 *  Test-only helpers of the core plugins' tests (not part of the SDK): the
 *  plugin's default configuration file, a minimal dlopen of the built MODULE
 *  to check its entry point, and the steps and numbers the tests share
 *  (preparing, checking and applying observations; the FlatFish IMU lever
 *  arm). Loading for real is the host's job (plugin_host.h); this only
 *  checks that the module is what the host expects.
 *
 *  Included by test sources only, it also gives them their common names
 *  (end of file): `auvnav` opened, `at` = auvnav::testing (the SDK's checks),
 *  `pt` = this header's namespace, and kDeg, kImuPos.
 */
#include <auvnav/config.h>
#include <auvnav/plugin_api.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "plugin_common.h"

namespace auvnav::plugins::test
{
inline std::string readFile(const std::string& path)
{
	std::ifstream f(path);
	std::stringstream s;
	s << f.rdbuf();
	return s.str();
}

/** The plugin's default configuration (plugins/<name>/<name>.yaml). */
inline config::Node defaultConfig()
{
	return config::Node::load(AUVNAV_PLUGIN_DEFAULT_CONFIG);
}

/** The default configuration as the YAML text the host hands the module. */
inline std::string defaultConfigText()
{
	return readFile(AUVNAV_PLUGIN_DEFAULT_CONFIG);
}

/** A configuration from YAML text (keys not given take their defaults). */
inline config::Node configText(const std::string& yaml)
{
	return config::Node::fromText(yaml, "test config");
}

/** Model's constructor refuses `yaml` with a config::ConfigError. */
template <class Model>
::testing::AssertionResult ConstructorRefuses(const std::string& yaml)
{
	try
	{
		Model model(configText(yaml), "TEST");
	}
	catch (const config::ConfigError&)
	{
		return ::testing::AssertionSuccess();
	}
	return ::testing::AssertionFailure() << "accepted config: " << yaml;
}

/** dlopen()s the built module (RTLD_LOCAL) and checks its entry point: name,
 *  ABI/API version and build fingerprint; then creates a model from
 *  `config_yaml`, checks `uses()` and destroys it. */
inline ::testing::AssertionResult ModuleLoadsAndCreates(const std::string& name,
                                                        const std::string& config_yaml,
                                                        uint32_t expected_uses)
{
	using ::testing::AssertionFailure;
	std::unique_ptr<void, int (*)(void*)> h(dlopen(AUVNAV_PLUGIN_MODULE, RTLD_NOW | RTLD_LOCAL), &dlclose);
	if (!h) return AssertionFailure() << "dlopen: " << dlerror();
	auto entry_fn = reinterpret_cast<AuvnavEntryFn>(dlsym(h.get(), AUVNAV_PLUGIN_ENTRY_SYMBOL));
	if (!entry_fn)
		return AssertionFailure() << "no " << AUVNAV_PLUGIN_ENTRY_SYMBOL << " in " << AUVNAV_PLUGIN_MODULE;
	const AuvnavPluginEntry* e = entry_fn();
	if (!e || !e->create || !e->destroy) return AssertionFailure() << "incomplete entry";
	if (e->header.abi_version != AUVNAV_PLUGIN_ABI_VERSION)
		return AssertionFailure() << "ABI version " << e->header.abi_version;
	if (e->header.api_version != AUVNAV_PLUGIN_API_VERSION)
		return AssertionFailure() << "API version " << e->header.api_version;
	if (name != e->header.name) return AssertionFailure() << "name '" << e->header.name << "'";
	if (std::string(AUVNAV_BUILD_FINGERPRINT) != e->header.fingerprint)
		return AssertionFailure() << "fingerprint '" << e->header.fingerprint << "' vs '"
		                          << AUVNAV_BUILD_FINGERPRINT << "'";
	if (!e->header.version || !e->header.description || !*e->header.description)
		return AssertionFailure() << "missing version or description";
	char error[512] = "";
	MeasurementModel* m = e->create(config_yaml.c_str(), "TEST", error, sizeof error);
	if (!m) return AssertionFailure() << "create failed: " << error;
	const uint32_t uses = m->uses();
	e->destroy(m);
	if (uses != expected_uses)
		return AssertionFailure() << "uses() = " << uses << ", expected " << expected_uses;
	return ::testing::AssertionSuccess();
}

/** The factory refuses `config_yaml` with a message containing `expected`. */
inline ::testing::AssertionResult ModuleRefuses(const std::string& config_yaml, const std::string& expected)
{
	using ::testing::AssertionFailure;
	std::unique_ptr<void, int (*)(void*)> h(dlopen(AUVNAV_PLUGIN_MODULE, RTLD_NOW | RTLD_LOCAL), &dlclose);
	if (!h) return AssertionFailure() << "dlopen: " << dlerror();
	auto entry_fn = reinterpret_cast<AuvnavEntryFn>(dlsym(h.get(), AUVNAV_PLUGIN_ENTRY_SYMBOL));
	if (!entry_fn) return AssertionFailure() << "no entry point";
	const AuvnavPluginEntry* e = entry_fn();
	char error[512] = "";
	MeasurementModel* m = e->create(config_yaml.c_str(), "TEST", error, sizeof error);
	if (m)
	{
		e->destroy(m);
		return AssertionFailure() << "accepted config: " << config_yaml;
	}
	if (std::string(error).find(expected) == std::string::npos)
		return AssertionFailure() << "error '" << error << "' does not contain '" << expected << "'";
	return ::testing::AssertionSuccess();
}

/** Model's constructor and the module both refuse `yaml`, the module's
 *  message naming the key of the yaml's last line (the bad one; the lines
 *  before it set up the case). */
template <class Model>
::testing::AssertionResult RefusesNamingTheKey(const std::string& yaml)
{
	const std::size_t line = yaml.rfind('\n') + 1;  // 0 for a single line
	const std::string key = yaml.substr(line, yaml.find(':', line) - line);
	const ::testing::AssertionResult constructor = ConstructorRefuses<Model>(yaml);
	if (!constructor) return constructor;
	return ModuleRefuses(yaml, key);
}

// ---------------------------------------------------------------- shared steps

using plugins::kDeg;

/** IMU lever arm [m, body FRD] of the FlatFish sensor set
 *  (flatfish_sensors.yaml imu.position_m). */
inline const Eigen::Vector3d kImuPos(0.29424, 0, -0.02863);

/** at::TestContext with the FlatFish IMU lever arm in ctx().imu_position_b. */
class FlatfishContext : public auvnav::testing::TestContext
{
 public:
	FlatfishContext() { ctx().imu_position_b = kImuPos; }
};

/** The measurements `model` prepares from `obs`, expecting `expected`. */
inline std::vector<Measurement> prepareAll(MeasurementModel& model, const mrpt::obs::CObservation& obs,
                                           const FilterContext& ctx,
                                           PrepareStatus expected = PrepareStatus::Ok)
{
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(model.prepare(obs, ctx, out, why), expected) << why;
	return out;
}

/** The first (usually only) measurement `model` prepares from `obs` (Ok
 *  expected; an empty Measurement if there is none). */
inline Measurement prepareOne(MeasurementModel& model, const mrpt::obs::CObservation& obs,
                              const FilterContext& ctx)
{
	const std::vector<Measurement> out = prepareAll(model, obs, ctx);
	return out.empty() ? Measurement{} : out[0];
}

/** prepare refuses an (empty) observation of another class, Other, as
 *  Invalid, naming the class it expects (`expected_class`). */
template <class Other>
::testing::AssertionResult RefusesOtherClass(MeasurementModel& model, const FilterContext& ctx,
                                             const std::string& expected_class)
{
	std::vector<Measurement> out;
	std::string why;
	if (model.prepare(*Other::Create(), ctx, out, why) != PrepareStatus::Invalid)
		return ::testing::AssertionFailure() << "not Invalid: " << why;
	if (why.find(expected_class) == std::string::npos)
		return ::testing::AssertionFailure() << "'" << why << "' does not name " << expected_class;
	return ::testing::AssertionSuccess();
}

/** at::IsWellFormed for an observation the model must use (a Skip fails),
 *  with perturbations from `seed`. */
inline ::testing::AssertionResult IsWellFormedAndUsed(MeasurementModel& model,
                                                      const mrpt::obs::CObservation& obs,
                                                      const FilterContext& ctx, const NavState& x,
                                                      uint32_t seed = 1)
{
	auvnav::testing::WellFormedOptions opt;
	opt.seed = seed;
	opt.accept_skip = false;
	return auvnav::testing::IsWellFormed(model, obs, ctx, x, opt);
}

/** A filter (default process model and UT parameters) at mean x0 with
 *  covariance P0. */
inline ManifoldUkf filterAt(const NavState& x0, const Covariance& P0 = auvnav::testing::TypicalCovariance())
{
	ManifoldUkf ukf(ProcessModel{}, UtParams{});
	ukf.initialize(x0, P0);
	return ukf;
}

namespace detail
{
/** The filter still holds exactly `before` and `P_before`. */
inline ::testing::AssertionResult Untouched(const ManifoldUkf& ukf, const NavState& before,
                                            const Covariance& P_before)
{
	if (!auvnav::testing::NavStateIdentical(ukf.state(), before))
		return ::testing::AssertionFailure() << "mean changed";
	if (!(ukf.covariance() == P_before)) return ::testing::AssertionFailure() << "covariance changed";
	return ::testing::AssertionSuccess();
}
}  // namespace detail

/** `model` refuses `obs` as Invalid in prepare, so that a filter at x0
 *  (at::TypicalCovariance()) gets no update and keeps its mean and
 *  covariance exactly. */
inline ::testing::AssertionResult PrepareRefuses(MeasurementModel& model, const mrpt::obs::CObservation& obs,
                                                 const FilterContext& ctx, const NavState& x0)
{
	ManifoldUkf ukf = filterAt(x0);
	const Covariance P_before = ukf.covariance();
	const auto res = auvnav::testing::ApplyObservation(ukf, model, obs, ctx);
	if (res.status != PrepareStatus::Invalid || !res.updates.empty())
		return ::testing::AssertionFailure()
		       << "not refused in prepare (" << res.updates.size() << " updates)";
	return detail::Untouched(ukf, x0, P_before);
}

/** A filter at x0 (at::TypicalCovariance()) refuses the measurement `m` as
 *  Invalid and keeps its mean and covariance exactly: a measurement with a
 *  NaN never reaches the state. */
inline ::testing::AssertionResult FilterRefuses(const MeasurementModel& model, const Measurement& m,
                                                const FilterContext& ctx, const NavState& x0)
{
	ManifoldUkf ukf = filterAt(x0);
	const Covariance P_before = ukf.covariance();
	const UpdateResult r = ukf.update(model, m, ctx);
	if (r.status != UpdateStatus::Invalid) return ::testing::AssertionFailure() << "not refused: " << r.why;
	return detail::Untouched(ukf, x0, P_before);
}

/** A level state facing `heading_rad` with the IMU at p_n [m], everything
 *  else zero or default: the hand-computed cases. */
inline NavState levelState(double heading_rad, const Eigen::Vector3d& p_n = Eigen::Vector3d::Zero())
{
	NavState x;
	x.R_nb = auvnav::testing::rotationYpr(heading_rad, 0, 0);
	x.p_n = p_n;
	return x;
}

/** How many of the observations offered were used (prepare Ok) and skipped. */
struct Offered
{
	int used = 0, skipped = 0;
};

/** Offers `model` the observation `obs` `count` times, stamped t0_s + k dt_s
 *  [s]: the check of a min_interval_s (each one not used must say so). */
inline Offered offerInTurn(MeasurementModel& model, const FilterContext& ctx, mrpt::obs::CObservation& obs,
                           int count, double t0_s, double dt_s)
{
	Offered n;
	for (int k = 0; k < count; ++k)
	{
		obs.timestamp = mrpt::Clock::fromDouble(t0_s + dt_s * k);
		std::vector<Measurement> out;
		std::string why;
		if (model.prepare(obs, ctx, out, why) == PrepareStatus::Ok)
			++n.used;
		else
		{
			++n.skipped;
			EXPECT_NE(why.find("min_interval_s"), std::string::npos) << why;
		}
	}
	return n;
}

/** Euler angles of R_nb [rad] (yaw-pitch-roll, as at::rotationYpr). */
inline double headingOf(const Eigen::Matrix3d& R_nb)
{
	return std::atan2(R_nb(1, 0), R_nb(0, 0));
}
inline double rollOf(const Eigen::Matrix3d& R_nb)
{
	return std::atan2(R_nb(2, 1), R_nb(2, 2));
}
inline double pitchOf(const Eigen::Matrix3d& R_nb)
{
	return -std::asin(R_nb(2, 0));
}

/** Where a point at lever arm r_b [m, body FRD] is in state x [m, navigation
 *  frame], with the IMU at imu_b (x.p_n). */
inline Eigen::Vector3d pointOnVehicle_n(const NavState& x, const Eigen::Vector3d& r_b,
                                        const Eigen::Vector3d& imu_b = kImuPos)
{
	return x.p_n + x.R_nb * (r_b - imu_b);
}

}  // namespace auvnav::plugins::test

// ---------------------------------------------------------------- the tests' names
// What every plugin test uses unqualified (this header is for test sources
// only: a header of the plugins themselves must not open namespaces).
using namespace auvnav;
namespace at = auvnav::testing;
namespace pt = auvnav::plugins::test;
using pt::kDeg;
using pt::kImuPos;
