#pragma once
/** @file inertial.h
 *  Accelerometer update on the acceleration state (plugin "inertial").
 *
 *  The filter's translation model is constant acceleration: the IMU's
 *  specific force is not an input but a measurement of the acceleration state
 *  a_n of the IMU point, with the attitude, gravity and accelerometer bias:
 *
 *      z = f_b (specific force, IMU axes = body FRD axes) [m/s²]
 *      h = R_nbᵀ (a_n − [0, 0, g]ᵀ) + b_a        (at rest: z ≈ [0, 0, −g])
 *
 *  Optionally (`coriolis: true`) the Coriolis term R_nbᵀ·2 ω_ie_n × v_n of the
 *  rotating navigation frame is added; it then also reads the velocity.
 *
 *  Noise: the accelerometer white noise (velocity random walk, datasheet
 *  mg/√Hz) as a per-sample σ = VRW·√rate, plus a model-noise term: the
 *  acceleration state is constant between samples and also absorbs vibration,
 *  so it never matches one sample exactly. The two add in quadrature.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <string>

#include "plugin_common.h"

namespace auvnav::plugins
{
class InertialModel final : public GatedModel
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	InertialModel(const config::Node& cfg, const std::string& label);

	/** Per-axis 1σ of one sample [m/s²] (white noise and model noise). */
	double sigma_mps2() const { return sigma_mps2_; }

 protected:
	uint32_t doUses() const override;
	/** h = R_nbᵀ (a_n − g e_z + 2 Ω × v_n) + b_a: affine in all but the attitude. */
	MeasurementStructure doStructure() const override
	{
		return {kAcceleration | kGravity | kAccelBias | kVelocity};
	}
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;
	/** The slopes of h in the acceleration, gravity, bias and velocity (the
	 *  Coriolis term), in closed form for the held attitude. */
	bool doAffineSlopes(const NavState& x, const Measurement& m, const FilterContext& ctx, int from, int to,
	                    Eigen::Ref<Eigen::MatrixXd> At) const override;

 private:
	double sigma_mps2_ = 0;
	bool coriolis_ = false;
};
}  // namespace auvnav::plugins
