#pragma once
/** @file CObservationThrusters.h
 *  Thruster efforts commanded by the vehicle's controller.
 *
 *  Contract: one entry per thruster in `effort`, in the unit given by `unit`
 *  (commanded force [N] or shaft speed [rpm]); the thruster count is
 *  `effort.size()`. The thruster geometry (configuration matrix) is not part
 *  of the observation: it belongs to the vehicle configuration.
 *  Serialization is versioned; every version stays readable.
 */
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <cstdint>
#include <vector>

namespace auvnav::obs
{
enum class EffortUnit : uint8_t
{
	Force_N = 0,
	Speed_rpm = 1
};

class CObservationThrusters : public mrpt::obs::CObservation
{
	DEFINE_SERIALIZABLE(CObservationThrusters, auvnav::obs)

 public:
	EffortUnit unit = EffortUnit::Force_N;
	std::vector<double> effort;  //!< per-thruster commanded effort, in `unit`

	std::size_t thrusterCount() const { return effort.size(); }

	// Efforts are not located: the pose is the body origin.
	void getSensorPose(mrpt::poses::CPose3D& out) const override { out = mrpt::poses::CPose3D(); }
	void setSensorPose(const mrpt::poses::CPose3D&) override {}
	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
