// Example out-of-tree auvnav plugin "compass" (see compass.h and README.md).
#include "compass.h"

#include <auvnav/plugin_api.h>
#include <auvnav/state_block_config.h>
#include <mrpt/obs/CObservationIMU.h>

#include "CObservationCompass.h"

#include <cmath>

namespace compass_example
{
namespace
{
constexpr double kDeg = M_PI / 180;
}

CompassModel::CompassModel(const auvnav::config::Node& cfg, const std::string& label)
    : label_(label),
      declination_rad_(cfg.inRange("declination_deg", -180.0, 180.0, 0.0) * kDeg),
      sigma_rad_(cfg.positive("sigma_deg", 2.0) * kDeg),
      gate_probability_(cfg.inRange("gate_probability", 0.0, 1.0, 0.999))
{
	if (sigma_rad_ > M_PI / 2)
		cfg.fail("sigma_deg", "a compass sigma above 90 deg carries no heading information");
	if (!(gate_probability_ > 0)) cfg.fail("gate_probability", "expected a probability in (0, 1], got 0");
	if (cfg.has("states"))
	{
		const auto st = cfg.child("states");
		st.allowOnly({"heading_bias"});
		if (st.has("heading_bias"))
			heading_bias_ = auvnav::PluginState(
			    auvnav::stateBlockFromConfig(st.child("heading_bias"), "heading_bias", {""}, "_deg", kDeg));
	}
}

double CompassModel::yawOf(const Eigen::Matrix3d& R_nb)
{
	return auvnav::wrapAngle(std::atan2(R_nb(1, 0), R_nb(0, 0)));
}

auvnav::PrepareStatus CompassModel::doPrepare(const mrpt::obs::CObservation& obs,
                                              const auvnav::FilterContext& /*ctx*/,
                                              std::vector<auvnav::Measurement>& out, std::string& why)
{
	using mrpt::obs::CObservationIMU;
	out.clear();
	double heading = 0;
	if (const auto* c = dynamic_cast<const CObservationCompass*>(&obs))
		heading = c->heading_rad;
	else if (const auto* imu = dynamic_cast<const CObservationIMU*>(&obs))
	{
		if (!imu->has(mrpt::obs::IMU_YAW))
		{
			why = "CObservationIMU without IMU_YAW (magnetic heading)";
			return auvnav::PrepareStatus::Invalid;
		}
		heading = imu->get(mrpt::obs::IMU_YAW);
	}
	else
	{
		why =
		    std::string("expected compass_example::CObservationCompass or mrpt::obs::CObservationIMU, got ") +
		    obs.GetRuntimeClass()->className;
		return auvnav::PrepareStatus::Invalid;
	}
	if (!std::isfinite(heading))
	{
		why = "non-finite heading";
		return auvnav::PrepareStatus::Invalid;
	}
	auvnav::Measurement m;
	m.z = Eigen::VectorXd::Constant(1, auvnav::wrapAngle(heading + declination_rad_));
	m.R = Eigen::MatrixXd::Constant(1, 1, sigma_rad_ * sigma_rad_);
	m.label = "heading";
	out.push_back(std::move(m));
	return auvnav::PrepareStatus::Ok;
}

bool CompassModel::doPredict(const auvnav::NavState& x, const auvnav::Measurement& /*m*/,
                             const auvnav::FilterContext& /*ctx*/, Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 1) return false;
	z_pred[0] = auvnav::wrapAngle(yawOf(x.R_nb) + heading_bias_.valueOr(x, 0.0));
	return true;
}

}  // namespace compass_example

// The plugin's entry point: the only symbol libauvnav_plugin_compass.so exports.
AUVNAV_PLUGIN(
    compass_example::CompassModel, "compass", "1.0.0",
    "Magnetic compass heading (own CObservationCompass, or CObservationIMU IMU_YAW) on the attitude, "
    "optional heading-bias state; example out-of-tree plugin")
