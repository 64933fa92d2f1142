#include "inertial.h"

#include <mrpt/obs/CObservationIMU.h>

#include <Eigen/Geometry>
#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
namespace
{
constexpr double kMg = 1e-3 * 9.80665;  // 1 mg in m/s² (standard gravity, as datasheets)
}

InertialModel::InertialModel(const config::Node& cfg, const std::string& /*label*/) : GatedModel(cfg)
{
	const double rate_hz = cfg.inRange("rate_hz", 1.0, 10000.0, 100.0);
	const double vrw = cfg.nonNegative("vrw_mg_per_sqrt_hz", 0.12) * kMg;  // m/s²/√Hz
	const double extra = cfg.nonNegative("extra_sigma_mps2", 0.02);
	const double white = vrw * std::sqrt(rate_hz);  // per-sample σ of white noise
	sigma_mps2_ = std::sqrt(white * white + extra * extra);
	if (!(sigma_mps2_ > 0))
		cfg.fail("extra_sigma_mps2",
		         "vrw_mg_per_sqrt_hz and extra_sigma_mps2 are both 0: noise must be positive");
	coriolis_ = cfg.boolean("coriolis", false);
}

uint32_t InertialModel::doUses() const
{
	return kAttitude | kAcceleration | kGravity | kAccelBias | (coriolis_ ? kVelocity : 0u);
}

PrepareStatus InertialModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& /*ctx*/,
                                       std::vector<Measurement>& out, std::string& why)
{
	using namespace mrpt::obs;
	out.clear();
	const auto* imu = observationAs<CObservationIMU>(obs, why);
	if (!imu) return PrepareStatus::Invalid;
	constexpr TIMUDataIndex kAcc[3] = {IMU_X_ACC, IMU_Y_ACC, IMU_Z_ACC};
	Eigen::Vector3d f;
	for (int i = 0; i < 3; ++i)
	{
		if (!imu->has(kAcc[i]))
		{
			why = "accelerometer data missing";
			return PrepareStatus::Invalid;
		}
		f[i] = imu->get(kAcc[i]);
	}
	if (!f.allFinite())
	{
		why = "non-finite specific force";
		return PrepareStatus::Invalid;
	}
	return appendMeasurement(out, f, Eigen::Matrix3d::Identity() * (sigma_mps2_ * sigma_mps2_),
	                         "specific_force");
}

bool InertialModel::doPredict(const NavState& x, const Measurement& /*m*/, const FilterContext& ctx,
                              Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 3) return false;
	// Specific force = acceleration relative to the Earth-fixed frame minus
	// gravity (down-positive, so −g along z), plus Coriolis if enabled.
	Eigen::Vector3d f_n = x.a_n - Eigen::Vector3d(0, 0, x.g);
	if (coriolis_) f_n += 2 * ctx.omega_ie_n.cross(x.v_n);
	z_pred = x.R_nb.transpose() * f_n + x.b_a;
	return true;
}

bool InertialModel::doAffineSlopes(const NavState& x, const Measurement& /*m*/, const FilterContext& ctx,
                                   int from, int to, Eigen::Ref<Eigen::MatrixXd> At) const
{
	if (At.cols() != 3 || At.rows() != to - from) return false;
	auto put = [&](int i, const Eigen::Vector3d& slope)
	{
		if (i >= from && i < to) At.row(i - from) = slope.transpose();
	};
	// ∂h/∂a_n,i = R_nbᵀ e_i, and the same for the accelerometer bias: its
	// tangent is in navigation axes (b_a ⊞ t e_i = b_a + t R_nbᵀ e_i, state.h).
	for (int i = 0; i < 3; ++i)
	{
		const Eigen::Vector3d col = x.R_nb.row(i).transpose();
		put(idx::acc + i, col);
		put(idx::acc_bias + i, col);
		if (coriolis_)
			put(idx::vel + i, x.R_nb.transpose() * (2 * ctx.omega_ie_n.cross(Eigen::Vector3d::Unit(i))));
	}
	put(idx::gravity, -x.R_nb.row(2).transpose());
	return true;
}

}  // namespace auvnav::plugins
