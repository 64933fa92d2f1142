#pragma once
/** @file gps.h
 *  GNSS horizontal position update (plugin "gps").
 *
 *  Observation: mrpt::obs::CObservationGPS carrying an NMEA GGA message.
 *  Latitude/longitude (and height above the ellipsoid, altitude_meters +
 *  geoidal_distance) are converted to the navigation frame with
 *  FilterContext::frame->toNed(). With r_a the antenna position and r_imu the
 *  IMU lever arm (body FRD):
 *
 *      z = antenna north, east in the navigation frame (2) [m]
 *      h = (p_n + R_nb (r_a − r_imu)).head<2>()
 *
 *  Noise (sigma_m)² I₂ (the white part, optionally scaled by the fix's HDOP)
 *  plus, when correlated_sigma_m > 0, the slowly varying part (multipath,
 *  atmosphere; Gauss-Markov with correlation_time_s) inflated by (1+ρ)/(1−ρ),
 *  ρ = exp(−Δt/τ), Δt the time since the last fix used: consecutive fixes
 *  share that error, and the filter, which takes them as independent, must
 *  not average it down faster than it really averages out. Observations
 *  without a GGA message or without a fix (fix_quality 0) are skipped; gross
 *  outliers fail the χ² gate (gate_probability). A fix that fails it against
 *  the filter's mean and position covariance (linearised) is still offered
 *  but does not start a new min_interval_s: the next fix is tried at once
 *  (wild fixes at the interval's phase must not be the only ones used).
 *
 *  Bias (`states: {bias: {sigma: …, process: gauss_markov, …}}`,
 *  state_block_config.h; without `process` it is a random constant): the
 *  slowly varying error as a plugin-owned state b = (b_n, b_e) instead of
 *  an inflated R, h = … + b. The filter then knows
 *  that fixes a few seconds apart share their error (every 1 Hz fix can be
 *  used, min_interval_s 0) and how much of its position σ is that shared
 *  error, which is what a smoother needs to weigh the fixes before a dive
 *  against those after it. Exclusive with correlated_sigma_m (the same error
 *  counted twice is refused).
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

namespace auvnav::plugins
{
class GpsModel final : public SafeMeasurementModel
{
 public:
	GpsModel(const config::Node& cfg, const std::string& label);

	const Eigen::Vector3d& position_b() const { return position_b_; }

 protected:
	uint32_t doUses() const override { return kAttitude | kPosition | bias_.uses(); }
	//! The antenna is at p_n + R_nb r (+ b): affine in the position and the bias.
	MeasurementStructure doStructure() const override { return {kPosition | bias_.uses()}; }
	std::vector<PluginState*> doStates() override { return {&bias_}; }
	bool doReportsPositionFix() const override { return true; }
	double doGateProbability() const override { return gate_probability_; }
	/** The antenna's position from a valid GGA fix (no rate limit, no state). */
	bool doInitialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, InitialFix& out) override;
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	/** The GGA fix of `obs` in the navigation frame (Ok), or why not. */
	PrepareStatus decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        Eigen::Vector3d& p_n, double& hdop, std::string& why) const;
	/** Variance [m²] of the correlated error for a fix `since_last_s` after
	 *  the last one used (0 when correlated_sigma_m is 0). */
	double correlatedVariance(double since_last_s) const;
	/** The fix fails the gate against the filter's mean and position
	 *  covariance (linearised; false without them). */
	bool likelyOutlier(const Measurement& m, const FilterContext& ctx) const;

	std::string label_;
	Eigen::Vector3d position_b_;
	double sigma_m_ = 3.0;
	bool scale_by_hdop_ = false;
	double gate_probability_ = 0.999;
	double min_interval_s_ = 0;       // fixes closer than this to the last one used are skipped
	double correlated_sigma_m_ = 0;   // Gauss-Markov part of the error, per axis [m]
	double correlation_time_s_ = 60;  // its time constant [s]
	double last_used_s_ = -1e300;
	PluginState bias_;  // (b_n, b_e) if configured
};
}  // namespace auvnav::plugins
