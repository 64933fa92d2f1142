// Self-test of the plugin-author checks (auvnav/testing/model_checks.h): each
// deliberately broken model must be caught, a correct one must pass.
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/testing/model_checks.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace auvnav;
namespace at = auvnav::testing;

namespace
{
enum class Flaw
{
	None,
	UndeclaredVelocity,  //!< h reads v_n, uses() omits kVelocity
	UndeclaredGyroBias,  //!< reads a block inside the tangent prefix but not declared
	AsymmetricR,
	IndefiniteR,
	WrongSizeR,
	NanZ,
	NanH,
	PredictFails,
	ResidualOffset,
	NonDeterministic,
	SkipWithMeasurements,
	Invalid,
	NotAffine,  //!< declares affine_in = position + velocity, but h is quadratic in the position
	WrapsButClaimsDifference  //!< residual() wraps the second entry; structure() declares differences
};

/** z = north position + 0.1·north velocity (2 numbers), with injectable flaws. */
class TestModel final : public SafeMeasurementModel
{
 public:
	explicit TestModel(Flaw f) : flaw_(f) {}

 protected:
	uint32_t doUses() const override
	{
		return flaw_ == Flaw::UndeclaredVelocity ? kPosition : (kPosition | kVelocity | kAttitude);
	}
	//! h is linear in the position and velocity (true unless NotAffine).
	MeasurementStructure doStructure() const override
	{
		// ResidualOffset overrides residual() as its own (else the filter ignores it).
		return {kPosition | kVelocity, 0u, flaw_ == Flaw::ResidualOffset};
	}
	void doResidual(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& zp,
	                Eigen::Ref<Eigen::VectorXd> r) const override
	{
		r = z - zp;
		if (flaw_ == Flaw::ResidualOffset) r.array() += 1e-3;
		if (flaw_ == Flaw::WrapsButClaimsDifference) r[1] = std::remainder(r[1], 2 * M_PI);
	}

	PrepareStatus doPrepare(const mrpt::obs::CObservation&, const FilterContext&,
	                        std::vector<Measurement>& out, std::string& why) override
	{
		out.clear();
		Measurement m;
		m.z = Eigen::Vector2d(1.0, 2.0);
		m.R = Eigen::Matrix2d::Identity();
		if (flaw_ == Flaw::AsymmetricR) m.R(0, 1) = 0.5;
		if (flaw_ == Flaw::IndefiniteR) m.R(1, 1) = -1;
		if (flaw_ == Flaw::WrongSizeR) m.R = Eigen::Matrix3d::Identity();
		if (flaw_ == Flaw::NanZ) m.z[1] = NAN;
		out.push_back(m);
		if (flaw_ == Flaw::Invalid)
		{
			out.clear();
			why = "broken on purpose";
			return PrepareStatus::Invalid;
		}
		if (flaw_ == Flaw::SkipWithMeasurements) return PrepareStatus::Skip;
		return PrepareStatus::Ok;
	}
	bool doPredict(const NavState& x, const Measurement&, const FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z) const override
	{
		if (flaw_ == Flaw::PredictFails) return false;
		z[0] = x.p_n.x() + 0.1 * x.v_n.x();
		z[1] = (x.R_nb * Eigen::Vector3d(1, 0, 0)).y();
		if (flaw_ == Flaw::UndeclaredGyroBias) z[1] += x.b_w.z();
		if (flaw_ == Flaw::NotAffine) z[0] += 1e-3 * x.p_n.x() * x.p_n.x();
		if (flaw_ == Flaw::NanH) z[1] = NAN;
		if (flaw_ == Flaw::NonDeterministic) z[0] += 1e-6 * ++calls_;
		return true;
	}

 private:
	Flaw flaw_;
	mutable int calls_ = 0;
};

::testing::AssertionResult check(Flaw f, uint32_t seed = 1)
{
	at::TestContext tc;
	TestModel model(f);
	at::WellFormedOptions opt;
	opt.seed = seed;
	return at::IsWellFormed(model, *auvnav::obs::CObservationPressure::Create(), tc.ctx(),
	                        at::RandomNavState(seed), opt);
}

std::string message(const ::testing::AssertionResult& r)
{
	return r.message();
}
}  // namespace

TEST(ModelChecks, CorrectModelPasses)
{
	for (uint32_t seed = 1; seed <= 10; ++seed) EXPECT_TRUE(check(Flaw::None, seed));
}

TEST(ModelChecks, CatchesWrongUsesMask)
{
	const auto r = check(Flaw::UndeclaredVelocity);
	EXPECT_FALSE(r);
	EXPECT_NE(message(r).find("undeclared"), std::string::npos) << message(r);
	EXPECT_NE(message(r).find("velocity"), std::string::npos) << message(r);
	// Also inside the tangent prefix, where the filter itself would not notice.
	EXPECT_FALSE(check(Flaw::UndeclaredGyroBias));
}

TEST(ModelChecks, CatchesAWrongAffineDeclaration)
{
	const auto r = check(Flaw::NotAffine);
	EXPECT_FALSE(r);
	EXPECT_NE(message(r).find("not affine"), std::string::npos) << message(r);
	EXPECT_NE(message(r).find("position"), std::string::npos) << message(r);
}

TEST(ModelChecks, CatchesBadNoise)
{
	EXPECT_NE(message(check(Flaw::AsymmetricR)).find("symmetric"), std::string::npos);
	EXPECT_NE(message(check(Flaw::IndefiniteR)).find("positive definite"), std::string::npos);
	EXPECT_NE(message(check(Flaw::WrongSizeR)).find("R is 3x3"), std::string::npos);
}

TEST(ModelChecks, CatchesBadValuesAndResiduals)
{
	EXPECT_NE(message(check(Flaw::NanZ)).find("z not finite"), std::string::npos);
	EXPECT_NE(message(check(Flaw::NanH)).find("h(x) not finite"), std::string::npos);
	EXPECT_NE(message(check(Flaw::PredictFails)).find("predict returned false"), std::string::npos);
	EXPECT_NE(message(check(Flaw::ResidualOffset)).find("residual(z, z)"), std::string::npos);
	EXPECT_NE(message(check(Flaw::NonDeterministic)).find("deterministic"), std::string::npos);
}

TEST(ModelChecks, CatchesAWrappingResidualDeclaredAsADifference)
{
	const auto r = check(Flaw::WrapsButClaimsDifference);
	EXPECT_FALSE(r);
	EXPECT_NE(message(r).find("is not what structure() declares"), std::string::npos) << message(r);
}

TEST(ModelChecks, CatchesPrepareProblems)
{
	EXPECT_NE(message(check(Flaw::Invalid)).find("broken on purpose"), std::string::npos);
	EXPECT_NE(message(check(Flaw::SkipWithMeasurements)).find("Skip with 1"), std::string::npos);
}

TEST(ModelChecks, RandomStatesAreReproducibleAndPlausible)
{
	EXPECT_TRUE(at::NavStateIdentical(at::RandomNavState(4), at::RandomNavState(4)));
	EXPECT_FALSE(at::NavStateIdentical(at::RandomNavState(4), at::RandomNavState(5)));
	for (uint32_t seed = 1; seed <= 50; ++seed)
	{
		const NavState x = at::RandomNavState(seed);
		EXPECT_TRUE(x.allFinite());
		EXPECT_NEAR((x.R_nb * x.R_nb.transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
		EXPECT_GE(x.p_n.z(), 0);
		EXPECT_GT(x.g, 9.7);
		// Roll and pitch within ±30°: body z is within 30·√2° of down.
		EXPECT_GT(x.R_nb(2, 2), std::cos(43 * M_PI / 180));
	}
}

TEST(ModelChecks, StateComparisonsAndRoundTrip)
{
	const NavState x = at::RandomNavState(9);
	for (uint32_t seed = 1; seed <= 20; ++seed) EXPECT_TRUE(at::BoxplusRoundTrip(x, seed));
	TangentVector d = TangentVector::Zero(idx::core_dim);
	d[idx::vel + 1] = 1e-3;
	const NavState y = x.boxplus(d);
	EXPECT_TRUE(at::NavStateNear(y, x, 1.1e-3));
	const auto r = at::NavStateNear(y, x, 1e-4);
	EXPECT_FALSE(r);
	EXPECT_NE(message(r).find("vel_e"), std::string::npos) << message(r);
	EXPECT_FALSE(at::NavStateIdentical(y, x));
	NavState nan = x;
	nan.g = NAN;
	EXPECT_FALSE(at::NavStateNear(nan, x, 1e9));
	EXPECT_FALSE(at::NavStateIdentical(nan, nan));  // NaN is never equal
}
