// Test plugin "probe": a deliberately careless depth model, to check that the
// navigator (not the plugin) keeps bad numbers out of the state.
// Observation: auvnav::obs::CObservationPressure, whose pressure_pa field is
// taken as a depth [m] WITHOUT any check (NaN/Inf pass through to z).
//   mode: passthrough   z = pressure_pa, h = p_n.z (IMU depth), R = 0.01 m²
//   mode: nan_h         the same z, but h returns NaN
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/plugin_api.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace
{
class ProbeModel final : public auvnav::SafeMeasurementModel
{
 public:
	ProbeModel(const auvnav::config::Node& cfg, const std::string& /*label*/)
	    : mode_(cfg.string("mode", "passthrough"))
	{
		if (mode_ != "passthrough" && mode_ != "nan_h") cfg.fail("mode", "expected passthrough or nan_h");
	}
	uint32_t doUses() const override { return auvnav::kPosition; }

 protected:
	auvnav::PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const auvnav::FilterContext&,
	                                std::vector<auvnav::Measurement>& out, std::string& why) override
	{
		out.clear();
		const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(&obs);
		if (!p)
		{
			why = "expected CObservationPressure";
			return auvnav::PrepareStatus::Invalid;
		}
		auvnav::Measurement m;
		m.z = Eigen::VectorXd::Constant(1, p->pressure_pa);  // unchecked on purpose
		m.R = Eigen::MatrixXd::Constant(1, 1, 0.01);
		m.label = "depth";
		out.push_back(std::move(m));
		return auvnav::PrepareStatus::Ok;
	}
	bool doPredict(const auvnav::NavState& x, const auvnav::Measurement&, const auvnav::FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override
	{
		z_pred[0] = mode_ == "nan_h" ? std::numeric_limits<double>::quiet_NaN() : x.p_n.z();
		return true;
	}

 private:
	std::string mode_;
};
}  // namespace

AUVNAV_PLUGIN(ProbeModel, "probe", "0.0.1", "test: unchecked depth (passthrough) or NaN h (nan_h)")
