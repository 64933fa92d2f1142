#pragma once
/** @file dvl.h
 *  DVL bottom-track velocity update (plugin "dvl").
 *
 *  Observation: auvnav::obs::CObservationDVL in any of its frames. With r_s
 *  the DVL position and R_bs its mounting rotation (sensor to body), r_imu
 *  the IMU lever arm, the velocity of the DVL point over the seabed in body
 *  axes is
 *
 *      v_s_b = R_nbᵀ v_n + ω × (r_s − r_imu)
 *      ω = omega_ib_b − b_w − R_nbᵀ omega_ie_n   (body rate relative to the Earth)
 *
 *  (v_n is the IMU point's velocity; the lever-arm term moves it to the DVL)
 *  and, per the observation's `frame`:
 *
 *      Instrument  z = velocity_s_mps (3)   h = R_bsᵀ v_s_b
 *      Vehicle     z = velocity_s_mps (3)   h = v_s_b
 *      EarthNed    z = velocity_s_mps (3)   h = R_nb v_s_b = v_n + R_nb (ω × (r_s − r_imu))
 *      EarthEnu    z = velocity_s_mps (3)   h = [h_E, h_N, −h_D] of EarthNed
 *      Beam        one scalar measurement per valid beam i:
 *                  z = beams[i].velocity_mps   h = u_iᵀ R_bsᵀ v_s_b
 *                  u_i = [sin i cos a_i, sin i sin a_i, cos i] (sensor frame)
 *
 *  Sign BottomOverInstrument (Teledyne RDI PD0) negates h; z stays what the
 *  instrument reported. An Earth-frame velocity carries no heading
 *  information except through the lever arm: the DVL rotated it with its own
 *  compass, whose error is not the filter's.
 *
 *  Noise:
 *  - 3-D frames: the observation's velocity covariance (beam geometry × beam
 *    noise, in the frame of z) plus extra_sigma_mps² I for what the covariance
 *    does not know (mounting misalignment, scale factor, sound speed); if the
 *    covariance is zero or unusable, sigma_mps² I replaces it. Earth frames
 *    add the DVL's own attitude error: a rotation error δθ moves the reported
 *    velocity v by δθ × v, so R gains [v]× diag(σ_t², σ_t², σ_ψ²) [v]×ᵀ
 *    (σ_ψ = earth_heading_sigma_deg: the cross-track error speed × σ_ψ;
 *    σ_t = earth_tilt_sigma_deg), with v the reported velocity.
 *  - Beam: per beam beam_velocity_sigma_mps² of the observation (or
 *    beam_sigma_mps² if it has none) plus extra_sigma_mps²; the beams are
 *    treated as independent (the common misalignment/scale part is in truth
 *    correlated between beams). Invalid beams are not used; fewer than 3
 *    valid beams skip the ping.
 *
 *  Optional plugin-owned states (`states:` in the config; state_block_config.h):
 *  - `scale_factor` s (1): the DVL reads (1 + s) times the velocity, the
 *    error of the sound speed or of the beam angles. In h the velocity is
 *    v_s_b + s r_b, with r_b the filter's mean of v_s_b (misalignment applied
 *    as below) scale_reference_lag_s (default 10 s) before the measurement:
 *    the same to first order as (1 + s) v_s_b, but the scale's gain is no
 *    longer formed with the velocity estimate whose error the innovation
 *    carries with the opposite sign. With (1 + s) v_s_b every ping pulled s
 *    down by about σ_s² tr(S⁻¹ P_v) (P_v: the prior velocity covariance in
 *    the measurement's axes), an errors-in-variables bias that a GPS on the
 *    surface only partly held: −0.3 % on the square mission with the
 *    simulator's 1 cm/s beam noise, −0.6 % with perfect GPS fixes, −3 % with
 *    the accelerometer weakened (tests/integration/test_plugin_states.cpp).
 *    A reference 10 s old is uncorrelated with the current prior error (which
 *    forgets the pings within a few seconds) and, on straight legs, equal to
 *    the velocity; without one (the first lag seconds, after a gap in bottom
 *    lock longer than the lag, no filter mean, or scale_reference_lag_s 0)
 *    h uses (1 + s) v_s_b;
 *  - `misalignment` δ (3, rad, body axes): the true mounting is
 *    Exp(δ) R_bs, so Instrument h = R_bsᵀ Exp(δ)ᵀ v_s_b, Vehicle
 *    h = Exp(δ)ᵀ v_s_b, Beam h = (Exp(δ) R_bs u_i)ᵀ v_s_b. Earth frames were
 *    rotated with the DVL's own attitude, so a mounting error does not reach
 *    them: δ keeps its prior there (it is not observable).
 *  Both are observable only through motion the IMU sees independently
 *  (turns, speed changes, a position reference); the filter reports their σ.
 *
 *  The mounting comes from the configuration (default: the FlatFish nominal
 *  mounting) or, with `use_observation_pose: true`, from each observation's
 *  sensorPose. It travels to h in the typed payload DvlPing (below), with
 *  tag = the frame code (auvnav::obs::DvlFrame).
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <string>

#include "plugin_common.h"

namespace auvnav::obs
{
class CObservationDVL;
enum class DvlFrame : uint8_t;
}  // namespace auvnav::obs

namespace auvnav::plugins
{
/** What h needs of one DVL measurement (Measurement::payload<DvlPing>()). */
struct DvlPing
{
	double r_s[3];  //!< sensor position [m, body FRD]
	//! Instrument: rotation vector of R_bs [rad]; Beam: R_bs u_i, the beam's
	//! unit vector in body axes; other frames: 0 (unused).
	double axis[3];
	double sign;        //!< +1 VehicleOverBottom, −1 BottomOverInstrument
	double beam_index;  //!< Beam: index of the beam in the observation; else 0
	//! The scale factor's reference velocity r_b (above) and whether there is
	//! one (0: none, h uses (1 + s) v_s_b).
	double scale_reference_b[3];
	double scale_reference_valid;
};

class DvlModel final : public GatedModel
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	DvlModel(const config::Node& cfg, const std::string& label);

	const Eigen::Vector3d& position_b() const { return position_b_; }
	const Eigen::Matrix3d& R_bs() const { return R_bs_; }

 protected:
	uint32_t doUses() const override
	{
		return kAttitude | kGyroBias | kVelocity | scale_.uses() | misalignment_.uses();
	}
	/** The sensor's velocity is R_nbᵀ v_n + (ω − b_w) × r: affine in the gyro
	 *  bias and velocity with the attitude (and any scale or misalignment state) held. */
	MeasurementStructure doStructure() const override { return {kGyroBias | kVelocity}; }
	std::vector<PluginState*> doStates() override { return {&scale_, &misalignment_}; }
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	/** The DVL's mounting for one observation (config or its sensorPose). */
	struct Mount
	{
		Eigen::Vector3d r_s;
		Eigen::Matrix3d R_bs;
	};
	PrepareStatus prepareVelocity(const obs::CObservationDVL& dvl, const Mount& mount, double sign,
	                              std::vector<Measurement>& out, std::string& why) const;
	PrepareStatus prepareBeams(const obs::CObservationDVL& dvl, const Mount& mount, double sign,
	                           std::vector<Measurement>& out, std::string& why) const;
	/** Records the filter's mean sensor velocity for this ping and writes the
	 *  scale factor's reference (dvl.h) into every measurement of `out`. */
	void setScaleReference(const Eigen::Vector3d& r_s, obs::DvlFrame frame, const FilterContext& ctx,
	                       std::vector<Measurement>& out);
	/** Covariance of the reported velocity from the DVL's own attitude error
	 *  (Earth frames), for the reported velocity v_n in NED. */
	Eigen::Matrix3d earthAttitudeCovariance(const Eigen::Vector3d& v_n) const;

	Eigen::Vector3d position_b_;
	Eigen::Matrix3d R_bs_;
	bool use_observation_pose_ = false;
	double sigma_mps_ = 0.02;
	double extra_sigma_mps_ = 0.005;
	double beam_sigma_mps_ = 0.01;
	double earth_heading_sigma_rad_ = 0;
	double earth_tilt_sigma_rad_ = 0;
	PluginState scale_;         // s (1), if configured
	PluginState misalignment_;  // δ (3) [rad, body axes], if configured
	double scale_reference_lag_s_ = 10;
	//! (time, the filter's mean of v_s_b with misalignment) per ping with a
	//! scale state, oldest first: the scale's reference velocity (see above).
	std::deque<std::pair<double, Eigen::Vector3d>> scale_reference_history_;
};
}  // namespace auvnav::plugins
