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
class GpsConverter final : public MountedConverter
{
 public:
	GpsConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : MountedConverter(s, label)
	{
		lat_ = parseScalar(q, "latitude", UnitKind::Angle);
		lon_ = parseScalar(q, "longitude", UnitKind::Angle);
		alt_ = parseScalar(q, "altitude", UnitKind::Length);
		geoid_ = parseScalar(q, "geoid_separation", UnitKind::Length);
		quality_ = parseScalar(q, "fix_quality", UnitKind::Dimensionless);
		status_ = parseScalar(q, "navsat_status", UnitKind::Dimensionless);
		sats_ = parseScalar(q, "satellites", UnitKind::Dimensionless);
		hdop_ = parseScalar(q, "hdop", UnitKind::Dimensionless);
		if (!lat_.present || !lon_.present) s.fail("latitude", "a gps needs latitude and longitude");
		if (quality_.present && status_.present)
			s.fail("fix_quality", "give fix_quality or navsat_status, not both");
		const std::string ref = s.string("altitude_reference", alt_.present ? "" : "msl");
		if (ref != "msl" && ref != "ellipsoid")
			s.fail("altitude_reference",
			       "required with altitude: msl (NMEA GGA) or ellipsoid (sensor_msgs/NavSatFix)");
		ellipsoid_ = ref == "ellipsoid";
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		using mrpt::obs::gnss::Message_NMEA_GGA;
		AngleRead lat, lon;
		if (readAngle(lat_, r, cols_, lat, why) != Read::Ok ||
		    readAngle(lon_, r, cols_, lon, why) != Read::Ok)
		{
			if (why.empty()) why = "latitude/longitude missing";
			return nullptr;
		}
		// Through locals: MRPT's GGA fields are packed, a reference to one
		// would be misaligned.
		double lat_deg = 0, lon_deg = 0;
		if (!latLonDegrees(lat_, lat, lon_, lon, lat_deg, lon_deg, why)) return nullptr;
		Message_NMEA_GGA gga;
		gga.fields.latitude_degrees = lat_deg;
		gga.fields.longitude_degrees = lon_deg;
		double x = 0;
		Read res = readScalar(alt_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		gga.fields.altitude_meters = res == Read::Ok ? x : NAN;
		res = readScalar(geoid_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		// NavSatFix altitudes are ellipsoidal: GGA altitude + geoid separation
		// must give back the ellipsoidal height, so the separation is 0 here.
		gga.fields.geoidal_distance = (res == Read::Ok && !ellipsoid_) ? x : 0;
		gga.fields.fix_quality = 1;
		if (quality_.present)
		{
			if (readScalar(quality_, r, cols_, x, why) != Read::Ok || !(x >= 0 && x <= 9))
			{
				if (why.empty()) why = "fix_quality missing or not 0..9";
				return nullptr;
			}
			gga.fields.fix_quality = static_cast<uint8_t>(x);
		}
		else if (status_.present)
		{
			// sensor_msgs/NavSatStatus: −1 no fix, 0 fix, 1 SBAS, 2 GBAS.
			if (readScalar(status_, r, cols_, x, why) != Read::Ok)
			{
				if (why.empty()) why = "navsat_status missing";
				return nullptr;
			}
			gga.fields.fix_quality = x < 0 ? 0 : x >= 2 ? 4 : x >= 1 ? 2 : 1;
		}
		res = readScalar(sats_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		gga.fields.satellitesUsed = res == Read::Ok && x >= 0 && x < 256 ? static_cast<uint32_t>(x) : 0;
		res = readScalar(hdop_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		gga.fields.thereis_HDOP = res == Read::Ok;
		gga.fields.HDOP = res == Read::Ok ? static_cast<float>(x) : 0.0f;
		auto o = mrpt::obs::CObservationGPS::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		o->setMsg(gga);
		return o;
	}

 private:
	ScalarSpec lat_, lon_, alt_, geoid_, quality_, status_, sats_, hdop_;
	bool ellipsoid_ = false;
};
}  // namespace

const ConverterFactory makeGpsConverter = factoryOf<GpsConverter>;

}  // namespace auvnav::import::detail
