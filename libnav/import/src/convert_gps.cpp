// The GPS converter: a fix into an NMEA GGA message of
// mrpt::obs::CObservationGPS (finishObservation sets its UTC time).
#include <mrpt/obs/CObservationGPS.h>

#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
/** How good a fix is, as an NMEA GGA fix_quality (0 no fix … 9): read as
 *  such (`fix_quality`), mapped from a sensor_msgs/NavSatStatus
 *  (`navsat_status`), or 1 (a plain fix) when neither is given. */
class FixQualitySpec
{
 public:
	FixQualitySpec(const config::Node& q, const config::Node& s)
	    : quality_(parseScalar(q, "fix_quality", UnitKind::Dimensionless)),
	      status_(parseScalar(q, "navsat_status", UnitKind::Dimensionless))
	{
		if (quality_.present && status_.present)
			s.fail("fix_quality", "give fix_quality or navsat_status, not both");
	}

	bool read(const Record& r, Columns& cols, uint8_t& out, std::string& why) const
	{
		double x = 0;
		if (quality_.present)
		{
			if (readScalar(quality_, r, cols, x, why) != Read::Ok || !(x >= 0 && x <= 9))
			{
				if (why.empty()) why = "fix_quality missing or not 0..9";
				return false;
			}
			out = static_cast<uint8_t>(x);
			return true;
		}
		if (!status_.present)
		{
			out = 1;
			return true;
		}
		// sensor_msgs/NavSatStatus: −1 no fix, 0 fix, 1 SBAS, 2 GBAS.
		if (readScalar(status_, r, cols, x, why) != Read::Ok)
		{
			if (why.empty()) why = "navsat_status missing";
			return false;
		}
		out = x < 0 ? 0 : x >= 2 ? 4 : x >= 1 ? 2 : 1;
		return true;
	}

 private:
	ScalarSpec quality_, status_;
};

class GpsConverter final : public MountedConverter
{
 public:
	GpsConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : MountedConverter(s, label), lat_lon_(q, s), quality_(q, s)
	{
		if (!lat_lon_.present()) s.fail("latitude", "a gps needs latitude and longitude");
		alt_ = parseScalar(q, "altitude", UnitKind::Length);
		geoid_ = parseScalar(q, "geoid_separation", UnitKind::Length);
		sats_ = parseScalar(q, "satellites", UnitKind::Dimensionless);
		hdop_ = parseScalar(q, "hdop", UnitKind::Dimensionless);
		const std::string ref = s.string("altitude_reference", alt_.present ? "" : "msl");
		if (ref != "msl" && ref != "ellipsoid")
			s.fail("altitude_reference",
			       "required with altitude: msl (NMEA GGA) or ellipsoid (sensor_msgs/NavSatFix)");
		ellipsoid_ = ref == "ellipsoid";
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		// Through locals: MRPT's GGA fields are packed, a reference to one
		// would be misaligned.
		double lat_deg = 0, lon_deg = 0, alt = NAN, geoid = NAN, sats = NAN, hdop = NAN;
		uint8_t quality = 0;
		if (lat_lon_.read(r, cols_, lat_deg, lon_deg, why) != Read::Ok)
		{
			if (why.empty()) why = "latitude/longitude missing";
			return nullptr;
		}
		if (!readOptional(alt_, r, cols_, alt, why) || !readOptional(geoid_, r, cols_, geoid, why) ||
		    !quality_.read(r, cols_, quality, why) || !readOptional(sats_, r, cols_, sats, why) ||
		    !readOptional(hdop_, r, cols_, hdop, why))
			return nullptr;
		mrpt::obs::gnss::Message_NMEA_GGA gga;
		gga.fields.latitude_degrees = lat_deg;
		gga.fields.longitude_degrees = lon_deg;
		gga.fields.altitude_meters = alt;
		// NavSatFix altitudes are ellipsoidal: GGA altitude + geoid separation
		// must give back the ellipsoidal height, so the separation is 0 here.
		gga.fields.geoidal_distance = std::isnan(geoid) || ellipsoid_ ? 0 : geoid;
		gga.fields.fix_quality = quality;
		gga.fields.satellitesUsed = sats >= 0 && sats < 256 ? static_cast<uint32_t>(sats) : 0;
		gga.fields.thereis_HDOP = !std::isnan(hdop);
		gga.fields.HDOP = std::isnan(hdop) ? 0.0f : static_cast<float>(hdop);
		auto o = mrpt::obs::CObservationGPS::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		o->setMsg(gga);
		return o;
	}

 private:
	LatLonSpec lat_lon_;
	FixQualitySpec quality_;
	ScalarSpec alt_, geoid_, sats_, hdop_;
	bool ellipsoid_ = false;
};
}  // namespace

const ConverterFactory makeGpsConverter = factoryOf<GpsConverter>;

}  // namespace auvnav::import::detail
