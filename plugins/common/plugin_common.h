#pragma once
/** @file plugin_common.h
 *  Small helpers shared by the core sensor-model plugins (internal to
 *  plugins/; not installed). Header-only, so that each plugin stays one
 *  self-contained MODULE.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>
#include <auvnav/state.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace auvnav::plugins
{
constexpr double kDeg = M_PI / 180;

/** A core plugin's model: SafeMeasurementModel with the `gate_probability`
 *  key every core plugin has, read and checked here once. The key is a
 *  probability in (0, 1] (default 0.999); 1 disables the χ² gate. */
class GatedModel : public SafeMeasurementModel
{
 protected:
	explicit GatedModel(const config::Node& cfg)
	    : gate_probability_(cfg.inRange("gate_probability", 0.0, 1.0, 0.999))
	{
		if (!(gate_probability_ > 0)) cfg.fail("gate_probability", "expected a probability in (0, 1], got 0");
	}
	double doGateProbability() const final { return gate_probability_; }

 private:
	double gate_probability_;
};

/** `obs` as the observation class T, or null with `why` naming the class
 *  expected and the one given: every plugin's first check in prepare. */
template <class T>
const T* observationAs(const mrpt::obs::CObservation& obs, std::string& why)
{
	const auto* typed = dynamic_cast<const T*>(&obs);
	if (!typed)
		why = std::string("expected ") + T::GetRuntimeClassIdStatic().className + ", got " +
		      obs.GetRuntimeClass()->className;
	return typed;
}

/** Mounting rotation R_bs (sensor to body) from yaw, pitch, roll in degrees,
 *  exactly as MRPT's CPose3D (and the simulator) build it: Rz·Ry·Rx. */
inline Eigen::Matrix3d rotationFromYprDeg(const Eigen::Vector3d& ypr_deg)
{
	const mrpt::poses::CPose3D p(0, 0, 0, ypr_deg[0] * kDeg, ypr_deg[1] * kDeg, ypr_deg[2] * kDeg);
	return p.getRotationMatrix().asEigen();
}

/** Appends the one measurement of an observation (z, R, label) to `out`:
 *  the last step of a prepare that gives a single measurement. */
inline PrepareStatus appendMeasurement(std::vector<Measurement>& out, Eigen::VectorXd z, Eigen::MatrixXd R,
                                       const char* label)
{
	Measurement m;
	m.z = std::move(z);
	m.R = std::move(R);
	m.label = label;
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

/** The `min_interval_s` key [s] of a plugin that thins its observations: one
 *  closer than that to the last one used is skipped (0, the default: none).
 *  The plugin says which observation it used (markUsed), so that one it only
 *  offers (e.g. a likely outlier) need not start a new interval. */
class MinInterval
{
 public:
	MinInterval() = default;
	explicit MinInterval(const config::Node& cfg)
	    : min_interval_s_(cfg.inRange("min_interval_s", 0.0, 3600.0, 0.0))
	{
	}

	/** Time [s] from the last observation used to `t_s` (huge before the first). */
	double sinceLastUsed_s(double t_s) const { return t_s - last_used_s_; }
	/** True if `t_s` is within min_interval_s of the last observation used:
	 *  then it is counted and `why` says "within min_interval_s of the last
	 *  <what> used". */
	bool tooSoon(double t_s, const char* what, std::string& why)
	{
		if (!(sinceLastUsed_s(t_s) < min_interval_s_)) return false;
		++skipped_;
		why = std::string("within min_interval_s of the last ") + what + " used";
		return true;
	}
	void markUsed(double t_s) { last_used_s_ = t_s; }
	/** Observations skipped by tooSoon() so far. */
	std::size_t skippedCount() const { return skipped_; }

 private:
	double min_interval_s_ = 0;
	double last_used_s_ = -1e300;  // none used yet
	std::size_t skipped_ = 0;
};
}  // namespace auvnav::plugins
