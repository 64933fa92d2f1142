// The ADCP converter: current profile cells into auvnav::obs::CObservationADCP.
#include <auvnav/obs/CObservationADCP.h>

#include <Eigen/Dense>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
class AdcpConverter final : public AxisMappedConverter
{
 public:
	AdcpConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : AxisMappedConverter(s, label)
	{
		blank_ = parseScalar(q, "blank_distance", UnitKind::Length);
		cell_size_ = parseScalar(q, "cell_size", UnitKind::Length);
		sigma_ = parseScalar(q, "velocity_sigma", UnitKind::Velocity);
		if (!blank_.present || !cell_size_.present)
			s.fail("cell_size", "an adcp needs blank_distance and cell_size");
		const config::Node c = q.child("cells");
		c.allowOnly({"count", "velocity", "correlation", "valid"});
		count_ = CountSpec::parse(c, "count");
		velocity_ = parseVector(c, "velocity", UnitKind::Velocity, 3);
		if (!velocity_[0].present) c.fail("velocity", "missing (3 field templates such as cell_{i}_vx)");
		correlation_ = parseScalar(c, "correlation", UnitKind::Dimensionless);
		valid_ = parseScalar(c, "valid", UnitKind::Dimensionless);
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationADCP::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		if (readScalar(blank_, r, cols_, o->blank_distance_m, why) != Read::Ok ||
		    readScalar(cell_size_, r, cols_, o->cell_size_m, why) != Read::Ok)
		{
			if (why.empty()) why = "blank_distance/cell_size missing";
			return nullptr;
		}
		double x = 0;
		const Read rs = readScalar(sigma_, r, cols_, x, why);
		if (rs == Read::Bad) return nullptr;
		if (rs == Read::Ok) o->velocity_sigma_mps = x;
		int n = 0;
		if (!count_.read(r, cols_, n, why)) return nullptr;
		o->cells.resize(static_cast<std::size_t>(n));
		for (int i = 0; i < n; ++i)
		{
			auto& cell = o->cells[static_cast<std::size_t>(i)];
			Eigen::Vector3d v;
			const Read rv = readVec3(velocity_, r, cols_, v, why, "cell velocity", i);
			if (rv == Read::Bad) return count_.explainMissing(n, why), nullptr;
			double corr = 1, valid = 1;
			const Read rc = readScalar(correlation_, r, cols_, corr, why, i);
			if (rc == Read::Bad) return count_.explainMissing(n, why), nullptr;
			const Read rb = readScalar(valid_, r, cols_, valid, why, i);
			if (rb == Read::Bad) return count_.explainMissing(n, why), nullptr;
			const bool finite = rv == Read::Ok && v.allFinite();
			const Eigen::Vector3d v_s = finite ? Eigen::Vector3d(axes() * v) : Eigen::Vector3d::Zero();
			for (int k = 0; k < 3; ++k) cell.velocity_s_mps[static_cast<std::size_t>(k)] = v_s[k];
			cell.correlation = rc == Read::Ok ? corr : 0;
			cell.valid = finite && valid != 0;
		}
		return o;
	}

 private:
	ScalarSpec blank_, cell_size_, sigma_;
	CountSpec count_;
	std::vector<ScalarSpec> velocity_;
	ScalarSpec correlation_, valid_;
};
}  // namespace

const ConverterFactory makeAdcpConverter = factoryOf<AdcpConverter>;

}  // namespace auvnav::import::detail
