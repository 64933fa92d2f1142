#pragma once
/** @file sonar.h
 *  Simulated Gemini-720i-like imaging sonar: raw polar frames (beams × range
 *  bins, 8-bit) with speckle, the seabed return shaped by the vertical beam,
 *  and surveyed poles as bright compact returns with acoustic shadows behind
 *  them. The geometry goes into each CObservationImage (sonar/frame.h); the
 *  poles truly in view are reported for scoring the detector.
 *
 *  Model (per beam c at bearing θ_c and bin r at slant range ρ_r):
 *    seabed   ρ > h: L_s · exp(−½((φ − tilt)/(vbw/2))²), φ = asin(h/ρ) the
 *             depression to the seabed, h the sonar's height above the seabed
 *             under that ground point;
 *    pole     L_p · exp(−½((θ_c − β)/σ_θ)²) · exp(−½((ρ_r − ρ_p)/σ_ρ)²), β, ρ_p
 *             the bearing and range of the pole's near face, σ_θ² the beam's
 *             (FWHM/2.355)² plus the pole's angular half-width², σ_ρ 0.15 m;
 *    shadow   the seabed term × shadow_factor behind a pole, in the beams it
 *             covers (poles rise above the sonar: the shadow reaches max range);
 *    level    (seabed/shadow + water noise + pole) × Rayleigh speckle (mean 1).
 *  Bearings are horizontal (the mounting's yaw plus misalignment); the tilt
 *  only shapes the seabed return.
 */
#include <auvnav/config.h>
#include <auvnav/sonar/geometry.h>
#include <auvnav/sonar/landmarks.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/random/RandomGenerators.h>

#include <vector>

#include "environment.h"
#include "sensors.h"

namespace auvnav::sim
{
/** A pole truly in view in one frame. */
struct PoleInView
{
	std::string id;
	double bearing_rad = 0, range_m = 0;  //!< true, in the sonar frame (near face)
};

class SonarSim
{
 public:
	/** `n`: the sensors file's `sonar:` section; `poles`: the truth map. */
	SonarSim(const config::Node& n, sonar::PoleMap poles, uint32_t seed);
	double period_s() const { return period_s_; }
	double offset_s() const { return offset_s_; }
	const sonar::PolarGeometry& geometry() const { return geom_; }
	/** A frame at this instant; `in_view` receives the poles it shows. */
	mrpt::obs::CObservationImage::Ptr sample(const Truth& truth, const Environment& env,
	                                         std::vector<PoleInView>& in_view);
	/** True heading of the sonar's bearing-0 direction in NED [rad]. */
	double sonarHeading(const Truth& truth) const;

 private:
	double period_s_, offset_s_;
	Mounting mount_;
	sonar::PolarGeometry geom_;
	sonar::PoleMap poles_;
	double tilt_rad_, vertical_beamwidth_rad_, horizontal_beamwidth_rad_;
	double seabed_level_, pole_level_, water_level_, shadow_factor_;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

}  // namespace auvnav::sim
