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
	    : MountedConverter(s, label), lat_lon_(q, s)
	{
		depth_ = parseScalar(q, "depth", UnitKind::Length);
		north_ = parseScalar(q, "north", UnitKind::Length);
		east_ = parseScalar(q, "east", UnitKind::Length);
		down_ = parseScalar(q, "down", UnitKind::Length);
		if (north_.present != east_.present) s.fail("north", "give north and east together");
		if (!lat_lon_.present() && !north_.present)
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
		if (!labelAndMount(*o, r, why) || !readPosition(r, *o, why)) return nullptr;
		for (std::size_t i = 0; i < cov_.size(); ++i)
			if (!readOptional(cov_[i], r, cols_, o->covariance_ned_m2[i], why)) return nullptr;
		double sigma = NAN, id = NAN, time = NAN;
		if (!readOptional(sigma_, r, cols_, sigma, why) ||
		    !readOptional(range_, r, cols_, o->slant_range_m, why) || !readOptional(id_, r, cols_, id, why) ||
		    !readOptional(time_, r, cols_, time, why))
			return nullptr;
		if (!std::isnan(sigma))
			o->covariance_ned_m2 = {sigma * sigma, 0, 0, 0, sigma * sigma, 0, 0, 0, sigma * sigma};
		if (!std::isnan(id))
		{
			if (!(id >= 0 && id <= 65535))
			{
				why = "transponder_id not 0..65535";
				return nullptr;
			}
			o->transponder_id = static_cast<uint16_t>(id);
		}
		if (!std::isnan(time))
		{
			if (!(time > 0 && time < 1e11))
			{
				why = "measurement_time not a UNIX time";
				return nullptr;
			}
			o->measurement_time = mrpt::Clock::fromDouble(time);
		}
		return o;
	}

 private:
	/** The fix: latitude/longitude/depth when the record has them, else
	 *  north/east/down from the navigation origin. */
	bool readPosition(const Record& r, auvnav::obs::CObservationUSBL& o, std::string& why)
	{
		const Read geodetic = lat_lon_.read(r, cols_, o.position[0], o.position[1], why);
		if (geodetic == Read::Bad) return false;
		if (geodetic == Read::Ok)
		{
			o.frame = auvnav::obs::UsblFrame::Geodetic;
			return readOptional(depth_, r, cols_, o.position[2], why);
		}
		double north = 0, east = 0;
		if (readScalar(north_, r, cols_, north, why) != Read::Ok ||
		    readScalar(east_, r, cols_, east, why) != Read::Ok)
		{
			if (why.empty()) why = "no position (latitude/longitude or north/east)";
			return false;
		}
		o.frame = auvnav::obs::UsblFrame::LocalNed;
		o.position[0] = north;
		o.position[1] = east;
		return readOptional(down_, r, cols_, o.position[2], why);
	}

	LatLonSpec lat_lon_;
	ScalarSpec depth_, north_, east_, down_, sigma_, range_, id_, time_;
	std::vector<ScalarSpec> cov_;
};
}  // namespace

const ConverterFactory makeUsblConverter = factoryOf<UsblConverter>;

}  // namespace auvnav::import::detail
