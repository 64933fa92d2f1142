// The DVL converter: velocity (frame, sign, axes), covariance, bottom lock,
// altitude and beams into auvnav::obs::CObservationDVL.
#include <auvnav/obs/CObservationDVL.h>

#include <Eigen/Dense>
#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
class DvlConverter final : public AxisMappedConverter
{
 public:
	DvlConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : AxisMappedConverter(s, label)
	{
		frame_ = parseText(s, "frame");
		if (!frame_.present)
			s.fail("frame",
			       "required: instrument, vehicle, earth_ned, earth_enu or beam (which one depends on "
			       "the DVL's output setting; a wrong guess is a wrong velocity)");
		sign_ = parseText(s, "sign");
		if (!sign_.present)
			s.fail("sign", "required: vehicle_over_bottom, or bottom_over_instrument (Teledyne RDI PD0)");
		checkText(s, frame_, "frame",
		          [](const std::string& n)
		          {
			          auvnav::obs::DvlFrame f;
			          return auvnav::obs::parseDvlFrame(n, f);
		          });
		checkText(s, sign_, "sign",
		          [](const std::string& n)
		          {
			          auvnav::obs::DvlSign x;
			          return auvnav::obs::parseDvlSign(n, x);
		          });
		if (frame_.is_constant && frame_.constant == "beam" && !axes().isIdentity(1e-12))
			s.fail("axes",
			       "not applied to beam azimuths with frame: beam (give them in the sensor frame, without "
			       "axes)");
		velocity_ = parseVector(q, "velocity", UnitKind::Velocity, 3);
		cov_ = parseVector(q, "velocity_covariance", UnitKind::VelocitySquared, 9);
		sigma_ = parseScalar(q, "velocity_sigma", UnitKind::Velocity);
		lock_ = parseScalar(q, "bottom_lock", UnitKind::Dimensionless);
		altitude_ = parseScalar(q, "altitude", UnitKind::Length);
		inclination_ = parseScalar(q, "beam_inclination", UnitKind::Angle);
		beam_sigma_ = parseScalar(q, "beam_velocity_sigma", UnitKind::Velocity);
		if (q.has("beams"))
		{
			const config::Node b = q.child("beams");
			b.allowOnly({"count", "range", "range_is", "valid", "velocity", "azimuth"});
			beam_count_ = CountSpec::parse(b, "count");
			range_ = parseScalar(b, "range", UnitKind::Length);
			valid_ = parseScalar(b, "valid", UnitKind::Dimensionless);
			beam_velocity_ = parseScalar(b, "velocity", UnitKind::Velocity);
			azimuth_ = parseScalar(b, "azimuth", UnitKind::Angle);
			const std::string range_is = b.string("range_is", "slant");
			if (range_is != "slant" && range_is != "vertical")
				b.fail("range_is", "expected slant or vertical");
			ranges_vertical_ = range_is == "vertical";
			has_beams_ = true;
		}
		if (!velocity_[0].present && !(has_beams_ && beam_velocity_.present))
			s.fail("velocity", "a dvl needs velocity (3 fields) or beams.velocity");
		// altitude from slant ranges is range × cos(inclination): without the
		// inclination it would be the slant range (15 % high at 30 deg).
		if (has_beams_ && range_.present && !ranges_vertical_ && !inclination_.present && !altitude_.present)
			s.fail("beam_inclination",
			       "required with slant beams.range and no altitude (altitude = range x "
			       "cos(beam_inclination)); or give beams.range_is: vertical");
		if (ranges_vertical_ && !inclination_.present && !altitude_.present)
			notes_.push_back("beams.range_is vertical: altitude = mean of the valid vertical ranges");
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		using namespace auvnav::obs;
		auto o = CObservationDVL::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		std::string name;
		if (!readText(frame_, r, cols_, name, why)) return nullptr;
		if (!auvnav::obs::parseDvlFrame(name, o->frame))
		{
			why = "frame '" + name + "' unknown";
			return nullptr;
		}
		// Beam azimuths and radial velocities are not rotated by `axes`: a beam-frame
		// record with axes would be silently in the source frame.
		if (o->frame == DvlFrame::Beam && !axes().isIdentity(1e-12))
		{
			why =
			    "frame beam: axes are not applied to beam azimuths (give them in the sensor frame, without "
			    "axes)";
			return nullptr;
		}
		if (!readText(sign_, r, cols_, name, why)) return nullptr;
		if (!auvnav::obs::parseDvlSign(name, o->sign))
		{
			why = "sign '" + name + "' unknown";
			return nullptr;
		}
		double x = 0;
		inclination_read_ = readScalar(inclination_, r, cols_, x, why) == Read::Ok;
		if (inclination_read_)
			o->beam_inclination_rad = x;
		else if (!why.empty())
			return nullptr;
		if (readScalar(beam_sigma_, r, cols_, x, why) == Read::Ok)
			o->beam_velocity_sigma_mps = x;
		else if (!why.empty())
			return nullptr;
		if (!readBeams(r, *o, why)) return nullptr;

		bool velocity_ok = false;
		if (velocity_[0].present)
		{
			Eigen::Vector3d v(NAN, NAN, NAN);
			const Read res = readVec3(velocity_, r, cols_, v, why, "velocity");
			if (res == Read::Bad) return nullptr;
			// NaN or a declared invalid value is "no velocity" (no bottom lock), not an error.
			velocity_ok = res == Read::Ok && v.allFinite();
			const bool rotate = o->frame == DvlFrame::Instrument || o->frame == DvlFrame::Vehicle;
			const Eigen::Vector3d v_out = velocity_ok ? Eigen::Vector3d(rotate ? axes() * v : v) : v;
			// An invalid velocity is kept as read (NaN for a missing one), not made up.
			for (int k = 0; k < 3; ++k)
				o->velocity_s_mps[static_cast<std::size_t>(k)] = velocity_ok ? v_out[k] : v[k];
		}
		if (o->frame == DvlFrame::Beam)
		{
			int valid = 0;
			for (const auto& b : o->beams) valid += b.valid;
			velocity_ok = valid >= 3;
		}
		if (!readCovariance(r, *o, why)) return nullptr;

		o->bottom_lock = velocity_ok;
		if (lock_.present)
		{
			const Read res = readScalar(lock_, r, cols_, x, why);
			if (res == Read::Bad) return nullptr;
			o->bottom_lock = velocity_ok && res == Read::Ok && x != 0;
		}
		if (!readOptional(altitude_, r, cols_, x, why)) return nullptr;
		o->altitude_m = std::isnan(x) ? altitudeFromBeams(*o) : x;
		return o;
	}

 private:
	template <class Valid>
	static void checkText(const config::Node& s, const TextSpec& t, const char* key, Valid valid)
	{
		if (t.is_constant && !valid(t.constant)) s.fail(key, "'" + t.constant + "' is not a valid value");
		for (const auto& [from, to] : t.map)
			if (!valid(to)) s.fail(key, "map value '" + to + "' (for '" + from + "') is not a valid value");
	}

	bool readBeams(const Record& r, auvnav::obs::CObservationDVL& o, std::string& why)
	{
		if (!has_beams_) return true;
		int n = 0;
		if (!beam_count_.read(r, cols_, n, why)) return false;
		o.beams.resize(static_cast<std::size_t>(n));
		for (int i = 0; i < n; ++i)
		{
			auto& b = o.beams[static_cast<std::size_t>(i)];
			double range = NAN, valid = 1, vel = NAN, az = 0;
			const Read rr = readScalar(range_, r, cols_, range, why, i);
			if (rr == Read::Bad) return beam_count_.explainMissing(n, why), false;
			if (rr == Read::Missing) range = NAN;
			const Read rv = readScalar(valid_, r, cols_, valid, why, i);
			if (rv == Read::Bad) return beam_count_.explainMissing(n, why), false;
			const Read rb = readScalar(beam_velocity_, r, cols_, vel, why, i);
			if (rb == Read::Bad) return beam_count_.explainMissing(n, why), false;
			if (rb == Read::Missing) vel = NAN;
			const Read rz = readScalar(azimuth_, r, cols_, az, why, i);
			if (rz == Read::Bad) return beam_count_.explainMissing(n, why), false;
			// Without a validity field a beam is valid when its range (and, in
			// beam mode, its velocity) is a finite positive number.
			bool ok = rv == Read::Ok ? valid != 0 : std::isfinite(range) && range > 0;
			if (beam_velocity_.present) ok = ok && std::isfinite(vel);
			b.range_m = std::isfinite(range) ? range : 0;
			b.valid = ok;
			b.velocity_mps = vel;  // NaN (no radial velocity) stays NaN: 0 would be a measurement
			b.azimuth_rad = az;
		}
		return true;
	}

	bool readCovariance(const Record& r, auvnav::obs::CObservationDVL& o, std::string& why)
	{
		if (cov_[0].present)
		{
			Eigen::Matrix3d C;
			int ok = 0;
			for (int k = 0; k < 9; ++k)
			{
				const Read res =
				    readScalar(cov_[static_cast<std::size_t>(k)], r, cols_, C(k / 3, k % 3), why);
				if (res == Read::Bad) return false;
				ok += res == Read::Ok;
			}
			if (ok == 9)
			{
				// A NaN covariance (beam mode, no 3-D velocity) is kept as read, not made 0.
				const bool rotate =
				    o.frame == auvnav::obs::DvlFrame::Instrument || o.frame == auvnav::obs::DvlFrame::Vehicle;
				if (rotate && C.allFinite()) C = axes() * C * axes().transpose();
				for (int k = 0; k < 9; ++k) o.velocity_cov[static_cast<std::size_t>(k)] = C(k / 3, k % 3);
			}
			else if (ok != 0)
			{
				why = "velocity_covariance: only " + std::to_string(ok) + " of 9 components present";
				return false;
			}
			return true;
		}
		double s = 0;
		const Read res = readScalar(sigma_, r, cols_, s, why);
		if (res == Read::Bad) return false;
		if (res == Read::Ok)
			for (std::size_t k = 0; k < 3; ++k) o.velocity_cov[4 * k] = s * s;
		return true;
	}

	double altitudeFromBeams(const auvnav::obs::CObservationDVL& o) const
	{
		double sum = 0;
		int n = 0;
		for (const auto& b : o.beams)
			if (b.valid && b.range_m > 0)
			{
				// Slant ranges without an inclination give no altitude (not the slant range).
				if (!ranges_vertical_ && !inclination_read_) return std::nan("");
				sum += ranges_vertical_ ? b.range_m : b.range_m * std::cos(o.beam_inclination_rad);
				++n;
			}
		return n > 0 ? sum / n : std::nan("");
	}

	TextSpec frame_, sign_;
	std::vector<ScalarSpec> velocity_, cov_;
	ScalarSpec sigma_, lock_, altitude_, inclination_, beam_sigma_;
	bool has_beams_ = false, ranges_vertical_ = false;
	bool inclination_read_ = false;  // this record's beam_inclination was read
	CountSpec beam_count_;
	ScalarSpec range_, valid_, beam_velocity_, azimuth_;
};
}  // namespace

const ConverterFactory makeDvlConverter = factoryOf<DvlConverter>;

}  // namespace auvnav::import::detail
