// The pressure converter: absolute or gauge pressure, or a depth, into
// auvnav::obs::CObservationPressure.
#include <auvnav/obs/CObservationPressure.h>

#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
class PressureConverter final : public MountedConverter
{
 public:
	PressureConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : MountedConverter(s, label)
	{
		pressure_ = parseScalar(q, "pressure", UnitKind::Pressure);
		depth_ = parseScalar(q, "depth", UnitKind::Length);
		temp_ = parseScalar(q, "temperature", UnitKind::Temperature);
		if (pressure_.present == depth_.present) s.fail("pressure", "give exactly one of pressure and depth");
		const std::string ref = s.string("pressure_reference", pressure_.present ? "" : "absolute");
		if (ref != "absolute" && ref != "gauge")
			s.fail("pressure_reference",
			       "required with pressure: absolute (atmosphere included) or gauge (relative to the "
			       "atmosphere)");
		gauge_ = ref == "gauge";
		// Converting a gauge reading or a depth to absolute pressure needs the
		// atmosphere (and for a depth the water density and gravity): asked
		// for, never assumed.
		if (gauge_ || depth_.present) atmospheric_pa_ = s.positive("atmospheric_pressure_pa");
		if (depth_.present)
		{
			density_ = s.inRange("density_kg_m3", 900, 1100);
			gravity_ = s.inRange("gravity_mps2", 9.7, 9.9);
			notes_.push_back(
			    "depth converted to absolute pressure with the spec's density, gravity and atmosphere");
		}
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationPressure::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		double v = 0;
		const ScalarSpec& src = pressure_.present ? pressure_ : depth_;
		const Read res = readScalar(src, r, cols_, v, why);
		if (res == Read::Bad) return nullptr;
		if (res == Read::Missing || !std::isfinite(v))
		{
			why = pressure_.present ? "pressure missing or not finite" : "depth missing or not finite";
			return nullptr;
		}
		if (pressure_.present)
			o->pressure_pa = gauge_ ? v + atmospheric_pa_ : v;
		else
			o->pressure_pa = atmospheric_pa_ + density_ * gravity_ * v;
		if (!readOptional(temp_, r, cols_, o->temperature_c, why)) return nullptr;
		return o;
	}

 private:
	ScalarSpec pressure_, depth_, temp_;
	bool gauge_ = false;
	double atmospheric_pa_ = 0, density_ = 0, gravity_ = 0;
};
}  // namespace

const ConverterFactory makePressureConverter = factoryOf<PressureConverter>;

}  // namespace auvnav::import::detail
