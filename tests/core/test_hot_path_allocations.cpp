// The filter's hot path does not allocate per sigma point (DEVELOPERS.md):
// once warm, ManifoldUkf::predict allocates nothing and ::update once, the
// innovation it returns (UpdateResult::innovation, a VectorXd of the
// measurement's size). Counted through malloc, which this executable defines (ahead of libc in the symbol
// scope, so the calls from libauvnav_nav.so, libstdc++'s operator new and
// Eigen's aligned_malloc all land here) and forwards to glibc's own.
// Not built under the sanitizers, which bring their own malloc.
#include <auvnav/measurement_function.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstddef>

#include "filter_test_util.h"

extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);

namespace
{
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void count()
{
	if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" void* malloc(std::size_t n)
{
	count();
	return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t k, std::size_t n)
{
	count();
	return __libc_calloc(k, n);
}
extern "C" void* realloc(void* p, std::size_t n)
{
	count();
	return __libc_realloc(p, n);
}

namespace
{
using namespace auvnav;

/** Allocations made by f(). */
template <class F>
long allocationsIn(F&& f)
{
	g_allocations = 0;
	g_counting = true;
	f();
	g_counting = false;
	return g_allocations.load();
}

/** Accelerometer-like: R_nbᵀ (a_n − g e_D) + b_a, affine in all but the attitude. */
class Accel final : public MeasurementFunction
{
 public:
	uint32_t uses() const noexcept override { return kAttitude | kAcceleration | kGravity | kAccelBias; }
	MeasurementStructure structure() const noexcept override
	{
		return {kAcceleration | kGravity | kAccelBias};
	}
	bool predict(const NavState& x, const Measurement&, const FilterContext&,
	             Eigen::Ref<Eigen::VectorXd> z) const noexcept override
	{
		z = x.R_nb.transpose() * (x.a_n - Eigen::Vector3d(0, 0, x.g)) + x.b_a;
		return true;
	}
};

/** Body velocity and a heading-free nonlinear read of every block. */
class Velocity final : public MeasurementFunction
{
 public:
	uint32_t uses() const noexcept override { return kAllBlocks & ~kPluginStates; }
	bool predict(const NavState& x, const Measurement&, const FilterContext&,
	             Eigen::Ref<Eigen::VectorXd> z) const noexcept override
	{
		z.head<3>() = x.R_nb.transpose() * x.v_n;
		z[3] = x.Dl_sub(0, 0) * z[0] + x.current_vehicle_ne.squaredNorm() + 1e-3 * x.p_n.z() + x.b_adcp.x();
		return true;
	}
};

struct Counts
{
	long predict = 0, update = 0;
	int updates = 0;
	bool all_accepted = true;
};

/** Runs `steps` predictions with an accelerometer update each and a
 *  velocity update every fifth; counts the allocations of those calls
 *  after `warm` steps. */
Counts hotPathAllocations(double heading_sigma_deg, int steps, int warm)
{
	const ProcessModel pm = test::makeProcessModel();
	const NavState x0 = test::makeState(0.7);
	const TangentVector sigma = test::makeSigmas(Eigen::Vector3d(3, 3, heading_sigma_deg) * M_PI / 180);
	ManifoldUkf ukf(pm, {});
	ukf.initialize(x0, test::correlatedCovariance(sigma, 5));
	const Accel accel;
	const Velocity velocity;
	Measurement fa, fv;
	fa.z.resize(3);
	fa.R = Eigen::Matrix3d::Identity() * 0.02 * 0.02;
	fv.z.resize(4);
	fv.R = Eigen::Vector4d(0.01, 0.01, 0.01, 1.0).asDiagonal();
	FilterContext ctx;
	ctx.omega_ie_n = Eigen::Vector3d(6.1e-5, 0, 4.0e-5);
	Counts c;
	for (int step = 0; step < steps; ++step)
	{
		const Eigen::Vector3d w(0.1 * std::sin(0.3 * step), 0.05, 0.2);
		ctx.t_s = 0.01 * step;
		ctx.omega_ib_b = w;
		const long p = allocationsIn([&] { ukf.predict(w, ctx.omega_ie_n, 0.01); });
		// Measurements a little off the mean's prediction: accepted updates.
		accel.predict(ukf.state(), fa, ctx, fa.z);
		fa.z += Eigen::Vector3d(0.01, -0.01, 0.02);
		velocity.predict(ukf.state(), fv, ctx, fv.z);
		fv.z += Eigen::Vector4d(0.02, 0.01, -0.01, 0.1);
		long u = 0;
		int updates = 0;
		auto apply = [&](const MeasurementFunction& model, const Measurement& m)
		{
			UpdateStatus status = UpdateStatus::Invalid;
			u += allocationsIn([&] { status = ukf.update(model, m, ctx).status; });
			c.all_accepted &= status == UpdateStatus::Accepted;
			++updates;
		};
		apply(accel, fa);
		if (step % 5 == 0) apply(velocity, fv);
		if (step < warm) continue;
		c.predict += p;
		c.update += u;
		c.updates += updates;
	}
	return c;
}
}  // namespace

TEST(HotPathAllocations, TheCounterSeesAnAllocation)
{
	// The test below can fail: a vector's growth is counted.
	EXPECT_GE(allocationsIn(
	              []
	              {
		              Eigen::VectorXd v(100);
		              v.setZero();
		              EXPECT_EQ(v.sum(), 0.0);
	              }),
	          1);
}

TEST(HotPathAllocations, PredictAllocatesNothingAndUpdateOnlyItsResult)
{
	const Counts c = hotPathAllocations(4, 60, 10);  // heading known to 4°
	EXPECT_TRUE(c.all_accepted);
	EXPECT_EQ(60, c.updates);
	EXPECT_EQ(0, c.predict);
	EXPECT_EQ(c.updates, c.update) << "one allocation an update: UpdateResult::innovation";
}

TEST(HotPathAllocations, UnknownHeadingScaledPairsAllocateOnlyTheResult)
{
	// Heading σ 180°: the attitude pairs are evaluated at the 90° limit and
	// rescaled (ukf.h) at every update, as on a vehicle without a heading
	// source; their deviations come from the update's arena too, not from
	// the heap.
	const Counts c = hotPathAllocations(180, 60, 10);
	EXPECT_TRUE(c.all_accepted);
	EXPECT_EQ(0, c.predict);
	EXPECT_EQ(c.updates, c.update) << "one allocation an update: UpdateResult::innovation";
}
