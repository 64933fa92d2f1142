// The thrusters converter: per-thruster efforts into
// auvnav::obs::CObservationThrusters.
#include <auvnav/obs/CObservationThrusters.h>

#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
class ThrustersConverter final : public Converter
{
 public:
	ThrustersConverter(const config::Node& q, const config::Node& s, const std::string& label) : label_(label)
	{
		if (s.has("mounting"))
			s.fail("mounting", "thruster efforts have no mounting (the geometry is vehicle configuration)");
		const config::Node e = q.child("effort");
		e.allowOnly({"count", "field", "unit"});
		count_ = CountSpec::parse(e, "count");
		field_.present = true;
		field_.field = e.string("field");
		field_.where = e.where("field");
		const std::string unit = e.string("unit");
		if (unit == "N")
			unit_ = auvnav::obs::EffortUnit::Force_N;
		else if (unit == "rpm")
			unit_ = auvnav::obs::EffortUnit::Speed_rpm;
		else
			e.fail("unit", "expected N (commanded force) or rpm (shaft speed)");
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationThrusters::Create();
		o->sensorLabel = label_;
		o->unit = unit_;
		int n = 0;
		if (!count_.read(r, cols_, n, why)) return nullptr;
		o->effort.resize(static_cast<std::size_t>(n));
		for (int i = 0; i < n; ++i)
		{
			double& x = o->effort[static_cast<std::size_t>(i)];
			if (readScalar(field_, r, cols_, x, why, i) != Read::Ok || !std::isfinite(x))
			{
				count_.explainMissing(n, why);
				if (why.empty()) why = "effort " + std::to_string(i) + " missing or not finite";
				return nullptr;
			}
		}
		return o;
	}

 private:
	std::string label_;
	CountSpec count_;
	ScalarSpec field_;
	auvnav::obs::EffortUnit unit_ = auvnav::obs::EffortUnit::Force_N;
	Columns cols_;
};
}  // namespace

const ConverterFactory makeThrustersConverter = factoryOf<ThrustersConverter>;

}  // namespace auvnav::import::detail
