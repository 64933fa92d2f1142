// A well-formed plugin that tests/host/CMakeLists.txt builds with a sanitizer
// (-fsanitize=address as "asan_built", -fsanitize=undefined as "ubsan_built")
// while the navigator is not: dlopen would abort the program inside the
// sanitizer runtime's initialiser, so the host must refuse it before loading.
#include <auvnav/plugin_api.h>

#ifndef AUVNAV_TEST_PLUGIN_NAME
#error "AUVNAV_TEST_PLUGIN_NAME must be defined by the build rules"
#endif

namespace
{
class SanitizedModel final : public auvnav::SafeMeasurementModel
{
 public:
	SanitizedModel(const auvnav::config::Node&, const std::string&) {}
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

AUVNAV_PLUGIN(SanitizedModel, AUVNAV_TEST_PLUGIN_NAME, "0.0.1", "test: built with a sanitizer")
