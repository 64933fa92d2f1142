// The USBL converter: acoustic fixes into auvnav::obs::CObservationUSBL.
#include <auvnav/obs/CObservationUSBL.h>

#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
/** An acoustic fix (CObservationUSBL): latitude/longitude/depth or
 *  north/east/down from the navigation origin, chosen per record by which
 *  cells hold numbers, with its optional covariance, slant range,
 *  transponder id and measurement time (UNIX seconds). */
class UsblConverter final : public MountedConverter
{
 public:
	UsblConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : MountedConverter(s, label)
	{
		lat_ = parseScalar(q, "latitude", UnitKind::Angle);
		lon_ = parseScalar(q, "longitude", UnitKind::Angle);
		depth_ = parseScalar(q, "depth", UnitKind::Length);
		north_ = parseScalar(q, "north", UnitKind::Length);
		east_ = parseScalar(q, "east", UnitKind::Length);
		down_ = parseScalar(q, "down", UnitKind::Length);
		if (lat_.present != lon_.present) s.fail("latitude", "give latitude and longitude together");
		if (north_.present != east_.present) s.fail("north", "give north and east together");
		if (!lat_.present && !north_.present)
			s.fail("latitude", "a usbl fix needs latitude/longitude(/depth) or north/east(/down)");
		if (q.has("position_covariance"))
			cov_ = parseVector(q, "position_covariance", UnitKind::LengthSquared, 9);
		sigma_ = parseScalar(q, "position_sigma", UnitKind::Length);
		if (!cov_.empty() && sigma_.present)
			s.fail("position_sigma", "give position_covariance or position_sigma");
		range_ = parseScalar(q, "slant_range", UnitKind::Length);
		id_ = parseScalar(q, "transponder_id", UnitKind::Dimensionless);
		time_ = parseScalar(q, "measurement_time", UnitKind::Time);
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationUSBL::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		double a = 0, b = 0, c = NAN;
		AngleRead lat, lon;
		Read ra = lat_.present ? readAngle(lat_, r, cols_, lat, why) : Read::Missing;
		Read rb = lat_.present ? readAngle(lon_, r, cols_, lon, why) : Read::Missing;
		if (ra == Read::Bad || rb == Read::Bad) return nullptr;
		if (ra == Read::Ok && rb == Read::Ok)
		{
			if (!latLonDegrees(lat_, lat, lon_, lon, o->position[0], o->position[1], why)) return nullptr;
			o->frame = auvnav::obs::UsblFrame::Geodetic;
			if (readScalar(depth_, r, cols_, c, why) == Read::Bad) return nullptr;
		}
		else
		{
			ra = north_.present ? readScalar(north_, r, cols_, a, why) : Read::Missing;
			rb = north_.present ? readScalar(east_, r, cols_, b, why) : Read::Missing;
			if (ra != Read::Ok || rb != Read::Ok)
			{
				if (why.empty()) why = "no position (latitude/longitude or north/east)";
				return nullptr;
			}
			o->frame = auvnav::obs::UsblFrame::LocalNed;
			o->position[0] = a;
			o->position[1] = b;
			if (readScalar(down_, r, cols_, c, why) == Read::Bad) return nullptr;
		}
		o->position[2] = c;
		double v = 0;
		for (std::size_t i = 0; i < cov_.size(); ++i)
		{
			const Read res = readScalar(cov_[i], r, cols_, v, why);
			if (res == Read::Bad) return nullptr;
			o->covariance_ned_m2[i] = res == Read::Ok ? v : NAN;
		}
		const Read rs = readScalar(sigma_, r, cols_, v, why);
		if (rs == Read::Bad) return nullptr;
		if (rs == Read::Ok) o->covariance_ned_m2 = {v * v, 0, 0, 0, v * v, 0, 0, 0, v * v};
		const Read rr = readScalar(range_, r, cols_, v, why);
		if (rr == Read::Bad) return nullptr;
		o->slant_range_m = rr == Read::Ok ? v : NAN;
		const Read ri = readScalar(id_, r, cols_, v, why);
		if (ri == Read::Bad) return nullptr;
		if (ri == Read::Ok)
		{
			if (!(v >= 0 && v <= 65535))
			{
				why = "transponder_id not 0..65535";
				return nullptr;
			}
			o->transponder_id = static_cast<uint16_t>(v);
		}
		const Read rt = readScalar(time_, r, cols_, v, why);
		if (rt == Read::Bad) return nullptr;
		if (rt == Read::Ok)
		{
			if (!(v > 0 && v < 1e11))
			{
				why = "measurement_time not a UNIX time";
				return nullptr;
			}
			o->measurement_time = mrpt::Clock::fromDouble(v);
		}
		return o;
	}

 private:
	ScalarSpec lat_, lon_, depth_, north_, east_, down_, sigma_, range_, id_, time_;
	std::vector<ScalarSpec> cov_;
};
}  // namespace

const ConverterFactory makeUsblConverter = factoryOf<UsblConverter>;

}  // namespace auvnav::import::detail
