#include "pressure.h"

#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/state.h>

#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
PressureModel::PressureModel(const config::Node& cfg, const std::string& /*label*/)
    : GatedModel(cfg),
      density_kg_m3_(cfg.inRange("density_kg_m3", 900.0, 1100.0, 1025.0)),
      atmospheric_pa_(cfg.inRange("atmospheric_pressure_pa", 50e3, 120e3, 101325.0)),
      sigma_pa_(cfg.positive("sigma_pa", 100.0)),
      bias_sigma_pa_(cfg.inRange("bias_sigma_pa", 0.0, 1e5, 0.0)),
      position_b_(cfg.vector3("position_m", Eigen::Vector3d(0, 0, 0.3)))
{
	if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
}

double PressureModel::noiseVariance(const FilterContext& ctx) const
{
	const double white = sigma_pa_ * sigma_pa_;
	if (bias_sigma_pa_ <= 0 || !ctx.covariance) return white;
	// The depth variance in pressure units (nominal gravity: the floor needs
	// no more precision than that).
	const double pa_per_m = density_kg_m3_ * kNominalGravity;
	const double prior = pa_per_m * pa_per_m * (*ctx.covariance)(idx::pos + 2, idx::pos + 2);
	const double floor = bias_sigma_pa_ * bias_sigma_pa_;
	if (!std::isfinite(prior)) return white;
	// A scalar update with noise R leaves P R / (P + R); this R leaves the
	// floor. At or below it, an update that changes nothing (10⁶ P).
	const double at_floor =
	    prior > floor * (1 + 1e-6) ? prior * floor / (prior - floor) : 1e6 * std::max(prior, floor);
	return std::max(white, at_floor);
}

PrepareStatus PressureModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                       std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto* p = observationAs<auvnav::obs::CObservationPressure>(obs, why);
	if (!p) return PrepareStatus::Invalid;
	if (!std::isfinite(p->pressure_pa))
	{
		why = "non-finite pressure";
		return PrepareStatus::Invalid;
	}
	if (p->pressure_pa < kMinPressurePa || p->pressure_pa > kMaxPressurePa)
	{
		why = "absurd pressure (outside 50 kPa .. 100 MPa)";
		return PrepareStatus::Invalid;
	}
	return appendMeasurement(out, Eigen::VectorXd::Constant(1, p->pressure_pa),
	                         Eigen::MatrixXd::Constant(1, 1, noiseVariance(ctx)), "pressure");
}

bool PressureModel::doPredict(const NavState& x, const Measurement& /*m*/, const FilterContext& ctx,
                              Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 1) return false;
	const double depth_s = x.p_n.z() + x.R_nb.row(2).dot(position_b_ - ctx.imu_position_b);
	z_pred[0] = atmospheric_pa_ + density_kg_m3_ * x.g * depth_s;
	return true;
}

}  // namespace auvnav::plugins
