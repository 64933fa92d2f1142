#pragma once
/** @file adcp.h
 *  ADCP current-profile aiding (plugin "adcp"): the z_c,i update of Arnold &
 *  Medagoda (2018), one 3-D measurement per cell.
 *
 *  Observation: auvnav::obs::CObservationADCP, per cell i the velocity of the
 *  water relative to the sensor in the sensor frame. With r_s the ADCP
 *  position and R_bs its mounting rotation (sensor to body), r_imu the IMU
 *  lever arm:
 *
 *      z_i = cells[i].velocity_s_mps (3) [m/s]
 *      h_i = R_bsᵀ R_nbᵀ (c_i − v_s,n) + [b_adcp.x, b_adcp.y, 0]
 *      v_s,n = v_n + R_nb (ω × (r_s − r_imu))
 *      ω   = omega_ib_b − b_w − R_nbᵀ omega_ie_n     (body rate relative to the Earth)
 *      c_i = [(1 − w_i) current_vehicle_ne + w_i current_far_ne ; 0]
 *      w_i = d_i / d_max,  d_i = cellDistance(i),
 *      d_max = blank_distance_m + cells.size() · cell_size_m
 *
 *  d_max is the far end of the profile of THIS observation (the far-current
 *  state is the current there), not a configured cell count: the authors'
 *  formulation divides by a fixed number of cells, which mis-scales the
 *  interpolation whenever the geometry differs.
 *
 *  A cell that is not `valid`, whose correlation is below `min_correlation`
 *  (or not finite), whose centre is beyond `max_distance_m`, or whose velocity
 *  is not finite becomes a Measurement with `skipped = true` (empty z and R,
 *  `label` says why), so every cell is accounted for. A malformed observation
 *  (cell_size ≤ 0, negative or non-finite blank distance, non-finite used
 *  sensor pose) is Invalid; one without cells is a Skip.
 *
 *  Noise per cell: (σ² + extra_sigma_mps²) I3 with σ = `sigma_mps` if
 *  configured, else the observation's velocity_sigma_mps if > 0 and finite,
 *  else 0.05 m/s. Each cell is gated on its own (χ², 3 DOF).
 *
 *  What h needs travels in the typed payload AdcpCell (below);
 *  Measurement::tag = cell index.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

#include "plugin_common.h"

namespace auvnav::plugins
{
/** Per-cell data from prepare to h (Measurement::payload<AdcpCell>()). R_bs
 *  is kept as a matrix, not a rotation vector: h runs once per sigma point
 *  and would otherwise take an exponential each time. */
struct AdcpCell
{
	double distance_m;      //!< d_i, cell centre along the profile
	double max_distance_m;  //!< d_max, the profile's far end (far-layer weight)
	double r_s[3];          //!< sensor position [m, body FRD]
	double R_bs[9];         //!< sensor-to-body rotation, column-major
};

/** Interpolation weight of the far current for a cell at distance `d_m` from
 *  the transducer in a profile ending at `d_max_m`: d / d_max (0 at the
 *  transducer, 1 at the far end). Not clamped; NaN if d_max ≤ 0. */
double adcpFarWeight(double d_m, double d_max_m);

/** The water current at weight `w` of the linear two-state profile, NED
 *  (vertical 0): (1 − w) current_vehicle + w current_far. */
Eigen::Vector3d adcpCellCurrent(const Eigen::Vector2d& current_vehicle_ne,
                                const Eigen::Vector2d& current_far_ne, double w);

class AdcpModel final : public GatedModel
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	AdcpModel(const config::Node& cfg, const std::string& label);

	const Eigen::Vector3d& position_b() const { return position_b_; }
	const Eigen::Matrix3d& R_bs() const { return R_bs_; }
	double minCorrelation() const { return min_correlation_; }
	double maxDistance_m() const { return max_distance_m_; }  //!< +inf if not configured
	double extraSigma_mps() const { return extra_sigma_mps_; }
	double sigma_mps() const { return sigma_mps_; }  //!< 0 if not configured

	/** Labels of skipped cells (Measurement::label). */
	static constexpr const char* kSkipInvalid = "skipped_invalid";
	static constexpr const char* kSkipCorrelation = "skipped_low_correlation";
	static constexpr const char* kSkipDistance = "skipped_beyond_max_distance";
	static constexpr const char* kSkipNonFinite = "skipped_non_finite";

 protected:
	uint32_t doUses() const override
	{
		return kAttitude | kGyroBias | kVelocity | kCurrentVehicle | kCurrentFar | kAdcpBias;
	}
	/** h is linear in the gyro bias, velocity, currents and bias once the
	 *  attitude is held (doPredict): only the attitude's sigma points are evaluated. */
	MeasurementStructure doStructure() const override
	{
		return {kGyroBias | kVelocity | kCurrentVehicle | kCurrentFar | kAdcpBias};
	}
	/** The slopes of h in the gyro bias (lever arm), velocity, currents and
	 *  bias, in closed form for the held attitude (MeasurementModel::affineSlopes). */
	bool doAffineSlopes(const NavState& x, const Measurement& m, const FilterContext& ctx, int from, int to,
	                    Eigen::Ref<Eigen::MatrixXd> At) const override;
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	Eigen::Vector3d position_b_;
	Eigen::Matrix3d R_bs_;
	bool use_observation_pose_ = false;
	double sigma_mps_ = 0;  // 0: from the observation
	double extra_sigma_mps_ = 0.02;
	double min_correlation_ = 0.5;
	double max_distance_m_;
};
}  // namespace auvnav::plugins
