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

#include <Eigen/Core>
#include <limits>
#include <string>

#include "position_fix_model.h"

namespace auvnav::plugins
{
/** One GGA fix: the antenna's position [m, navigation frame] and the HDOP
 *  (NaN if not reported). */
struct GgaFix
{
	Eigen::Vector3d p_n = Eigen::Vector3d::Zero();
	double hdop = std::numeric_limits<double>::quiet_NaN();
};

class GpsModel final : public PositionFixModel<GgaFix>
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	GpsModel(const config::Node& cfg, const std::string& label);

 protected:
	//! The antenna is at p_n + R_nb r (+ b): affine in the position and the bias.
	MeasurementStructure doStructure() const override { return {kPosition | bias().uses()}; }

 private:
	/** The GGA fix of `obs` in the navigation frame (Ok), or why not. */
	PrepareStatus decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, GgaFix& fix,
	                        std::string& why) const override;
	/** North, east with σ from sigma_m (HDOP) and the correlated error, one
	 *  fix per min_interval_s (see the file comment). */
	PrepareStatus measureFix(const GgaFix& fix, const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                         std::vector<Measurement>& out, std::string& why) override;
	/** Variance [m²] of the correlated error for a fix `since_last_s` after
	 *  the last one used (0 when correlated_sigma_m is 0). */
	double correlatedVariance(double since_last_s) const;
	/** The fix fails the gate against the filter's mean and position
	 *  covariance (linearised; false without them). */
	bool likelyOutlier(const Measurement& m, const FilterContext& ctx) const;

	double sigma_m_ = 3.0;
	bool scale_by_hdop_ = false;
	MinInterval min_interval_;        // fixes closer than this to the last one used are skipped
	double correlated_sigma_m_ = 0;   // Gauss-Markov part of the error, per axis [m]
	double correlation_time_s_ = 60;  // its time constant [s]
};
}  // namespace auvnav::plugins
