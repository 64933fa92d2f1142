// The plugin SDK's typed state handles (plugin_state.h), the host that checks
// and binds them (state_layout.h), the deprecated stateBlocks()/bindStates()
// shim, the test bench (testing/plugin_state_bench.h), the exception guards
// of SafeMeasurementModel, and the state block configuration.
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/plugin_host.h>
#include <auvnav/plugin_state.h>
#include <auvnav/state_block_config.h>
#include <auvnav/state_layout.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/plugin_state_bench.h>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "examples/biased_pressure.h"
#include "examples/biased_pressure_legacy.h"

using namespace auvnav;
namespace at = auvnav::testing;

namespace
{
StateBlockSpec spec(const std::string& name, std::vector<std::string> components, double sigma = 0.01)
{
	StateBlockSpec s;
	s.name = name;
	s.components = std::move(components);
	s.sigma = {sigma};
	return s;
}

/** A model owning the handles it is given (disabled ones included). */
class Owner final : public SafeMeasurementModel
{
 public:
	explicit Owner(std::vector<PluginState> blocks) : blocks_(std::move(blocks)) {}
	PluginState& block(std::size_t k) { return blocks_[k]; }

 protected:
	uint32_t doUses() const override { return kPosition | kPluginStates; }
	std::vector<PluginState*> doStates() override
	{
		std::vector<PluginState*> out;
		for (PluginState& b : blocks_) out.push_back(&b);
		return out;
	}
	PrepareStatus doPrepare(const mrpt::obs::CObservation&, const FilterContext&, std::vector<Measurement>&,
	                        std::string&) override
	{
		return PrepareStatus::Skip;
	}
	bool doPredict(const NavState& x, const Measurement&, const FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z) const override
	{
		z[0] = blocks_.empty() ? 0.0 : blocks_[0](x, 0);
		return true;
	}

 private:
	std::vector<PluginState> blocks_;
};

/** The layout of `models` as the navigator makes it (labels S0, S1, …). */
StateLayout layoutOf(const std::vector<MeasurementModel*>& models, ProcessModel& pm, Covariance& P0)
{
	static const std::vector<std::string> labels = {"S0", "S1", "S2"};
	static const std::string plugin = "test";
	std::vector<LabelledModel> labelled;
	for (std::size_t k = 0; k < models.size(); ++k) labelled.push_back({labels[k], plugin, *models[k]});
	P0 = Covariance::Identity(idx::core_dim, idx::core_dim);
	return appendPluginStates(labelled, pm, P0);
}

/** The host's refusal of `models`, or "" if it accepts them. */
std::string refusal(const std::vector<MeasurementModel*>& models)
{
	ProcessModel pm;
	Covariance P0;
	try
	{
		layoutOf(models, pm, P0);
		return "";
	}
	catch (const PluginError& e)
	{
		return e.what();
	}
}

obs::CObservationPressure pressure(double pa)
{
	obs::CObservationPressure o;
	o.pressure_pa = pa;
	return o;
}
}  // namespace

// ---------------------------------------------------------------- the handle

TEST(PluginState, DescribesItsSpecAndIsUnboundUntilTheHostBindsIt)
{
	const PluginState off;
	EXPECT_FALSE(off.enabled());
	EXPECT_EQ(off.uses(), 0u);
	EXPECT_EQ(off.valueOr(NavState{}, 0.25), 0.25);  // an optional state not configured
	const PluginState h(spec("misalignment", {"x", "y", "z"}));
	EXPECT_TRUE(h.enabled());
	EXPECT_EQ(h.uses(), uint32_t(kPluginStates));
	EXPECT_EQ(h.dimension(), 3);
	EXPECT_EQ(h.spec().name, "misalignment");
	EXPECT_FALSE(h.bound());
	EXPECT_EQ(h.tangentIndex(), -1);
	NavState x;
	x.extra = ExtraVector::Zero(3);
	EXPECT_FALSE(h.presentIn(x));
	// Writing through an unbound handle (tests) is refused in every build.
	EXPECT_THROW(h(x, 0) = 1.0, std::logic_error);
	// Reading one (as h does, from a const state) is NaN in a release build,
	// a failed h instead of a wild read, and an assertion in a debug build.
	const NavState& cx = x;
#ifdef NDEBUG
	EXPECT_TRUE(std::isnan(h(cx, 1)));
	EXPECT_TRUE(h.segment<3>(cx).array().isNaN().all());
#else
	EXPECT_DEATH((void)h(cx, 1), "bound");
#endif
}

TEST(PluginState, ReadsItsPlaceAfterTheStatesOfTheModelsBeforeIt)
{
	Owner first({PluginState(spec("a", {"n", "e"}))});
	Owner second({PluginState(spec("scale", {""})), PluginState(spec("misalignment", {"x", "y", "z"}))});
	ProcessModel pm;
	Covariance P0;
	const StateLayout layout = layoutOf({&first, &second}, pm, P0);
	const PluginState& scale = second.block(0);
	const PluginState& mis = second.block(1);
	ASSERT_TRUE(scale.bound() && mis.bound());
	EXPECT_EQ(scale.tangentIndex(), idx::extra + 2);
	EXPECT_EQ(mis.tangentIndex(1), idx::extra + 4);
	NavState x;
	x.extra.resize(6);
	x.extra << 10, 11, 12, 13, 14, 15;
	EXPECT_EQ(scale.value(x), 12);
	EXPECT_EQ(scale.valueOr(std::as_const(x), 0.0), 12);
	EXPECT_EQ(mis(x, 2), 15);
	EXPECT_EQ(Eigen::Vector3d(mis.segment<3>(x)), Eigen::Vector3d(13, 14, 15));
	EXPECT_EQ(mis.segment(x).size(), 3);
	mis.segment(x) = Eigen::Vector3d(1, 2, 3);
	scale.value(x) = -1;
	EXPECT_EQ(x.extra[2], -1);
	EXPECT_EQ(x.extra[5], 3);
	EXPECT_TRUE(mis.presentIn(x));
	x.extra.resize(5);
	EXPECT_FALSE(mis.presentIn(x));
	EXPECT_THROW(mis(x, 2) = 0, std::logic_error);
	// Names, offsets and initial σ as the outputs show them.
	EXPECT_EQ(layout.tangent_names[idx::extra + 2], "S1.scale");
	EXPECT_EQ(layout.tangent_names[idx::extra + 5], "S1.misalignment_z");
	ASSERT_EQ(layout.plugin_blocks.size(), 3u);
	EXPECT_EQ(layout.plugin_blocks[2].offset, idx::extra + 3);
	EXPECT_EQ(P0(idx::extra + 3, idx::extra + 3), 1e-4);
	EXPECT_EQ(pm.dim(), idx::core_dim + 6);
}

// ---------------------------------------------------------------- the host

TEST(StateLayout, SkipsDisabledHandlesAndModelsWithoutStates)
{
	Owner none({});
	Owner some({PluginState(), PluginState(spec("bias", {"n", "e"})), PluginState()});
	ProcessModel pm;
	Covariance P0;
	const StateLayout layout = layoutOf({&none, &some}, pm, P0);
	ASSERT_EQ(layout.plugin_blocks.size(), 1u);
	EXPECT_EQ(layout.plugin_blocks[0].sensor, "S1");
	EXPECT_TRUE(some.block(1).bound());
	EXPECT_FALSE(some.block(0).bound());
	EXPECT_EQ(some.block(1).tangentIndex(), idx::extra);
}

TEST(StateLayout, ChecksEveryBlockOnceAndNamesTheSensor)
{
	Owner twice({PluginState(spec("bias", {""})), PluginState(spec("bias", {"n", "e"}))});
	EXPECT_NE(refusal({&twice}).find("two state blocks named 'bias'"), std::string::npos)
	    << refusal({&twice});
	Owner bad_sigma({PluginState(spec("bias", {""}, 0.0))});
	const std::string why = refusal({&bad_sigma});
	EXPECT_NE(why.find("sensor 'S0' (plugin test)"), std::string::npos) << why;
	EXPECT_NE(why.find("sigma"), std::string::npos) << why;
	Owner same_component({PluginState(spec("bias", {"x", "x"}))});
	EXPECT_NE(refusal({&same_component}).find("component 'x' twice"), std::string::npos);
	std::vector<std::string> cells;
	for (int i = 0; i <= idx::max_extra; ++i) cells.push_back("c" + std::to_string(i));
	Owner too_many({PluginState(spec("map", cells))});
	EXPECT_NE(refusal({&too_many}).find("no room"), std::string::npos);
	// One handle, laid out twice (shared, or a second navigator on one model).
	Owner once({PluginState(spec("bias", {""}))});
	EXPECT_EQ(refusal({&once}), "");
	EXPECT_NE(refusal({&once}).find("bound already"), std::string::npos);
}

TEST(StateLayout, RefusesAModelWhoseStatesThrow)
{
	class Throws final : public SafeMeasurementModel
	{
	 protected:
		std::vector<PluginState*> doStates() override { throw std::runtime_error("no states today"); }
		PrepareStatus doPrepare(const mrpt::obs::CObservation&, const FilterContext&,
		                        std::vector<Measurement>&, std::string&) override
		{
			return PrepareStatus::Skip;
		}
		bool doPredict(const NavState&, const Measurement&, const FilterContext&,
		               Eigen::Ref<Eigen::VectorXd>) const override
		{
			return true;
		}
	} model;
	EXPECT_TRUE(model.states().empty());
	EXPECT_NE(refusal({&model}).find("states() failed"), std::string::npos);
}

TEST(StateLayout, HonoursTheDeprecatedStateBlocksOfAnUnportedModel)
{
	// The same plugin twice, the deprecated way and with a handle, after
	// another sensor's block: the same layout and the same h.
	at::TestContext tc;
	const auto cfg =
	    config::Node::fromText("bias: {sigma: 50, process: random_walk, process_sigma: 1}", "test");
	legacy_example::BiasedPressure legacy(cfg);
	handle_example::BiasedPressure ported(cfg);
	const at::PluginStateBench legacy_bench(legacy, 2, "PRESSURE");
	const at::PluginStateBench bench(ported, 2, "PRESSURE");
	EXPECT_EQ(legacy_bench.layout.tangent_names, bench.layout.tangent_names);
	EXPECT_EQ(legacy_bench.P0, bench.P0);
	EXPECT_EQ(legacy_bench.process.prior_mean, bench.process.prior_mean);
	EXPECT_THROW((void)legacy_bench["bias"], std::out_of_range);  // no handle to offer
	NavState x = bench.randomState(3);
	bench["bias"].value(x) = 40;
	for (MeasurementModel* m : std::vector<MeasurementModel*>{&legacy, &ported})
	{
		std::vector<Measurement> out;
		std::string why;
		ASSERT_EQ(m->prepare(pressure(2e5), tc.ctx(), out, why), PrepareStatus::Ok) << why;
		EXPECT_DOUBLE_EQ(at::Predict(*m, out[0], tc.ctx(), x)[0], 101325 + 1025 * 9.81 * x.p_n.z() + 40);
		EXPECT_TRUE(at::IsWellFormed(*m, pressure(2e5), tc.ctx(), x));
		// Both refuse a state without their bias (the legacy one itself, the ported one by the SDK).
		EXPECT_TRUE(std::isnan(at::Predict(*m, out[0], tc.ctx(), at::RandomNavState(3, 2))[0]));
	}
}

// ---------------------------------------------------------------- the bench

TEST(PluginStateBench, BindsAsTheNavigatorWithAnotherSensorFirst)
{
	const auto cfg = config::Node::fromText("bias: {sigma: 50, mean: 7}", "test");
	handle_example::BiasedPressure model(cfg);
	const at::PluginStateBench bench(model, 3);
	EXPECT_EQ(bench.extraSize(), 4);
	EXPECT_EQ(bench["bias"].tangentIndex(), idx::extra + 3);
	EXPECT_EQ(bench.initialState().extra[3], 7);  // the block's mean
	EXPECT_EQ(bench.P0(idx::extra + 3, idx::extra + 3), 2500);
	EXPECT_EQ(bench.process.dim(), idx::core_dim + 4);
	EXPECT_EQ(bench.randomState(5).extra.size(), 4);
	EXPECT_THROW((void)bench["scale"], std::out_of_range);
}

// ---------------------------------------------------------------- exception guards

TEST(SafeMeasurementModel, EveryMethodTurnsAnExceptionIntoItsSafeAnswer)
{
	class Throws final : public SafeMeasurementModel
	{
	 protected:
		uint32_t doUses() const override { throw std::runtime_error("uses"); }
		MeasurementStructure doStructure() const override { throw std::runtime_error("structure"); }
		double doGateProbability() const override { throw std::runtime_error("gate"); }
		bool doReportsPositionFix() const override { throw std::runtime_error("fix"); }
		double doMeasurementTime(const mrpt::obs::CObservation&, double) const override
		{
			throw std::runtime_error("time");
		}
		bool doInitialFix(const mrpt::obs::CObservation&, const FilterContext&, InitialFix&) override
		{
			throw std::runtime_error("initial fix");
		}
		void doResidual(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&,
		                Eigen::Ref<Eigen::VectorXd>) const override
		{
			throw std::runtime_error("residual");
		}
		bool doAffineSlopes(const NavState&, const Measurement&, const FilterContext&, int, int,
		                    Eigen::Ref<Eigen::MatrixXd>) const override
		{
			throw std::runtime_error("slopes");
		}
		PrepareStatus doPrepare(const mrpt::obs::CObservation&, const FilterContext&,
		                        std::vector<Measurement>&, std::string&) override
		{
			throw std::runtime_error("prepare");
		}
		bool doPredict(const NavState&, const Measurement&, const FilterContext&,
		               Eigen::Ref<Eigen::VectorXd>) const override
		{
			throw 42;  // not even a std::exception
		}
	} m;
	at::TestContext tc;
	const auto obs = pressure(1e5);
	EXPECT_EQ(m.uses(), uint32_t(kAllBlocks));  // always right, if slow
	EXPECT_EQ(m.structure().affine_in, 0u);
	EXPECT_FALSE(m.structure().custom_residual);
	EXPECT_EQ(m.gateProbability(), 0.999);
	EXPECT_FALSE(m.reportsPositionFix());
	EXPECT_TRUE(std::isnan(m.measurementTime(obs, 1.7e9)));  // the navigator's invalid observation
	InitialFix fix;
	EXPECT_FALSE(m.initialFix(obs, tc.ctx(), fix));
	std::vector<Measurement> out(1);
	std::string why;
	EXPECT_EQ(m.prepare(obs, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_TRUE(out.empty());
	EXPECT_NE(why.find("prepare"), std::string::npos) << why;
	Measurement meas;
	meas.z = Eigen::VectorXd::Zero(1);
	Eigen::VectorXd z(1), r(1);
	EXPECT_FALSE(m.predict(NavState{}, meas, tc.ctx(), z));
	Eigen::MatrixXd At = Eigen::MatrixXd::Zero(3, 1);
	EXPECT_FALSE(m.affineSlopes(NavState{}, meas, tc.ctx(), 0, 3, At));
	m.residual(meas.z, meas.z, r);
	EXPECT_TRUE(std::isnan(r[0]));
	EXPECT_TRUE(m.states().empty());
}

TEST(SafeMeasurementModel, DefaultsOfTheDoMethodsAreTheInterfacesDefaults)
{
	handle_example::BiasedPressure m(config::Node::fromText("{}", "test"));
	at::TestContext tc;
	const auto obs = pressure(1e5);
	EXPECT_EQ(m.measurementTime(obs, 12.5), 12.5);
	EXPECT_FALSE(m.reportsPositionFix());
	InitialFix fix;
	EXPECT_FALSE(m.initialFix(obs, tc.ctx(), fix));
	EXPECT_EQ(m.gateProbability(), 0.999);
	EXPECT_EQ(m.uses(), uint32_t(kPosition));
	Eigen::VectorXd r(2);
	m.residual(Eigen::Vector2d(1, 2), Eigen::Vector2d(0.5, 0.5), r);
	EXPECT_EQ(r, Eigen::Vector2d(0.5, 1.5));
}

// ---------------------------------------------------------------- configuration

TEST(StateBlockConfig, RandomWalkPerMetreIsProcessSigmaPerRootMetre)
{
	const auto n =
	    config::Node::fromText("{sigma_deg: 1, process: random_walk_per_m, process_sigma_deg: 0.01}", "test");
	const StateBlockSpec b = stateBlockFromConfig(n, "heading_bias", {""}, "_deg", M_PI / 180);
	EXPECT_EQ(b.process, StateProcess::RandomWalkPerMetre);
	EXPECT_NEAR(b.process_sigma, 0.01 * M_PI / 180, 1e-18);
	EXPECT_EQ(b.problem(), "");
	try
	{
		stateBlockFromConfig(config::Node::fromText("{sigma: 1, process: per_metre}", "test"), "b", {""});
		ADD_FAILURE() << "accepted process: per_metre";
	}
	catch (const config::ConfigError& e)
	{
		EXPECT_NE(std::string(e.what()).find("random_walk_per_m"), std::string::npos) << e.what();
	}
	EXPECT_THROW(stateBlockFromConfig(
	                 config::Node::fromText("{sigma: 1, process: random_walk_per_m}", "test"), "b", {""}),
	             config::ConfigError);  // process_sigma is required
}
