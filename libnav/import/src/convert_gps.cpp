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
class GpsConverter final : public Converter
{
 public:
	GpsConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), mounting_(s)
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
		double lat = 0, lon = 0, lat_raw = 0, lon_raw = 0;
		if (readScalar(lat_, r, cols_, lat, why, 0, &lat_raw) != Read::Ok ||
		    readScalar(lon_, r, cols_, lon, why, 0, &lon_raw) != Read::Ok)
		{
			if (why.empty()) why = "latitude/longitude missing";
			return nullptr;
		}
		if (!(std::abs(lat) <= M_PI / 2 && std::abs(lon) <= 2 * M_PI))
		{
			why = "latitude/longitude not finite or out of range";
			return nullptr;
		}
		Message_NMEA_GGA gga;
		// Degrees in, degrees kept: no rad round trip that could move the last bit.
		gga.fields.latitude_degrees = lat_.unit.name == "deg" ? lat_raw : lat / kDeg;
		gga.fields.longitude_degrees = lon_.unit.name == "deg" ? lon_raw : lon / kDeg;
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
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		o->setMsg(gga);
		return o;
	}

 private:
	std::string label_;
	Mounting mounting_;
	ScalarSpec lat_, lon_, alt_, geoid_, quality_, status_, sats_, hdop_;
	bool ellipsoid_ = false;
	Columns cols_;
};
}  // namespace

std::unique_ptr<Converter> makeGpsConverter(const config::Node& q, const config::Node& s,
                                            const std::string& label)
{
	return std::make_unique<GpsConverter>(q, s, label);
}

}  // namespace auvnav::import::detail
