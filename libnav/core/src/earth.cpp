#include <auvnav/earth.h>

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/NormalGravity.hpp>
#include <cmath>
#include <vector>

namespace auvnav::earth
{
namespace
{
constexpr double kDeg = 180.0 / M_PI;
}

double rotationRate()
{
	return GeographicLib::Constants::WGS84_omega<double>();
}

double normalGravity(double lat_rad, double h_m)
{
	double gy = 0, gz = 0;
	GeographicLib::NormalGravity::WGS84().Gravity(lat_rad * kDeg, h_m, gy, gz);
	return std::hypot(gy, gz);
}

Eigen::Vector3d earthRateNed(double lat_rad)
{
	const double w = rotationRate();
	return {w * std::cos(lat_rad), 0.0, -w * std::sin(lat_rad)};
}

struct TangentFrame::Impl
{
	GeographicLib::LocalCartesian enu;  // GeographicLib's local frame is ENU
};

TangentFrame::TangentFrame(const Geodetic& origin)
    : impl_(std::make_unique<Impl>(
          Impl{GeographicLib::LocalCartesian(origin.lat_rad * kDeg, origin.lon_rad * kDeg, origin.h_m)})),
      origin_(origin),
      omega_ie_n_(earthRateNed(origin.lat_rad))
{
}
TangentFrame::~TangentFrame() = default;
TangentFrame::TangentFrame(const TangentFrame& o)
    : impl_(std::make_unique<Impl>(*o.impl_)), origin_(o.origin_), omega_ie_n_(o.omega_ie_n_)
{
}
TangentFrame& TangentFrame::operator=(const TangentFrame& o)
{
	if (this != &o)
	{
		impl_ = std::make_unique<Impl>(*o.impl_);
		origin_ = o.origin_;
		omega_ie_n_ = o.omega_ie_n_;
	}
	return *this;
}

Geodetic TangentFrame::toGeodetic(const Eigen::Vector3d& p_n) const
{
	Geodetic g;
	impl_->enu.Reverse(p_n.y(), p_n.x(), -p_n.z(), g.lat_rad, g.lon_rad, g.h_m);
	g.lat_rad /= kDeg;
	g.lon_rad /= kDeg;
	return g;
}

Eigen::Vector3d TangentFrame::toNed(const Geodetic& g) const
{
	double e = 0, n = 0, u = 0;
	impl_->enu.Forward(g.lat_rad * kDeg, g.lon_rad * kDeg, g.h_m, e, n, u);
	return {n, e, -u};
}

Eigen::Vector3d TangentFrame::gravityNed(const Eigen::Vector3d& p_n) const
{
	double lat = 0, lon = 0, h = 0;
	std::vector<double> M(9);  // local ENU at the point -> ENU at the origin
	impl_->enu.Reverse(p_n.y(), p_n.x(), -p_n.z(), lat, lon, h, M);
	double gy = 0, gz = 0;
	GeographicLib::NormalGravity::WGS84().Gravity(lat, h, gy, gz);
	const Eigen::Vector3d g_enu_point(0.0, gy, gz);
	const Eigen::Matrix3d M_origin_point =
	    Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(M.data());
	const Eigen::Vector3d g_enu0 = M_origin_point * g_enu_point;
	return {g_enu0.y(), g_enu0.x(), -g_enu0.z()};
}

}  // namespace auvnav::earth
