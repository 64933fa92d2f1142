// A well-formed plugin whose factory always fails: the model's constructor
// throws, AUVNAV_PLUGIN turns that into the factory's error message.
#include <auvnav/plugin_api.h>

#include <stdexcept>

namespace
{
class FailingModel final : public auvnav::SafeMeasurementModel
{
 public:
	FailingModel(const auvnav::config::Node& cfg, const std::string& /*label*/)
	{
		throw std::runtime_error("calibration file '" + cfg.string("calibration", "none") +
		                         "' cannot be read (failing_factory test plugin)");
	}
	uint32_t doUses() const override { return auvnav::kPosition; }

 protected:
	auvnav::PrepareStatus doPrepare(const mrpt::obs::CObservation&, const auvnav::FilterContext&,
	                                std::vector<auvnav::Measurement>&, std::string&) override
	{
		return auvnav::PrepareStatus::Skip;
	}
	bool doPredict(const auvnav::NavState&, const auvnav::Measurement&, const auvnav::FilterContext&,
	               Eigen::Ref<Eigen::VectorXd>) const override
	{
		return false;
	}
};
}  // namespace

AUVNAV_PLUGIN(FailingModel, "failing_factory", "0.0.1", "test: a factory that always fails")
