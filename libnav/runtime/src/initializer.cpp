#include <auvnav/initializer.h>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>

namespace auvnav
{
void Initializer::addImu(double t_s, const Eigen::Vector3d& f_b)
{
	if (samples_ == 0) start_s_ = t_s;
	f_sum_b_ += f_b;
	++samples_;
}

void Initializer::addFix(double t_s, const InitialFix& fix)
{
	if (!fix.p_n.allFinite() || !fix.r_b.allFinite()) return;
	consensus_.add(t_s, fix);
	fix_ = consensus_.agreed();
}

NavState Initializer::initialState(const earth::TangentFrame& frame) const
{
	// Level from the mean specific force: f_b = R_nbᵀ (0, 0, −g).
	const Eigen::Vector3d fm = f_sum_b_ / static_cast<double>(samples_);
	const double roll = std::atan2(-fm.y(), -fm.z());
	const double pitch = std::atan2(fm.x(), std::hypot(fm.y(), fm.z()));
	NavState x0;
	x0.R_nb = (Eigen::AngleAxisd(initial_.heading_rad, Eigen::Vector3d::UnitZ()) *
	           Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
	           Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
	              .toRotationMatrix();
	x0.g = earth::normalGravity(frame.origin().lat_rad, frame.origin().h_m);
	Eigen::Vector3d p_body(initial_.north_m, initial_.east_m, 0.0);
	// A fix is of its sensor point (e.g. the antenna): the body origin is
	// r_b behind it along the initial attitude.
	if (initial_.position_from_fix && fix_) p_body = fix_->p_n - x0.R_nb * fix_->r_b;
	p_body.z() = initial_.depth_m;
	x0.p_n = p_body + x0.R_nb * imu_.position_b;
	return x0;
}

std::string Initializer::startEvent(const NavState& x0) const
{
	if (!initial_.position_from_fix || !fix_) return "";
	const Eigen::Vector3d p_body = x0.p_n - x0.R_nb * imu_.position_b;
	const int n = consensus_.fixes(), agree = consensus_.agreeing();
	char what[200];
	std::snprintf(
	    what, sizeof what,
	    "initialised at N %.2f E %.2f m from the newest of %d agreeing fixes (%d in the last %.0f s, "
	    "%d outliers)",
	    p_body.x(), p_body.y(), agree, n, consensus_.params().window_s, n - agree);
	return what;
}

std::string Initializer::waitingFor(double t_s, bool any_observation) const
{
	if (samples_ == 0)
		return any_observation ? "no valid IMU sample with label '" + imu_.label + "' (imu.label)"
		                       : "no observations at all";
	if (t_s - start_s_ < imu_.leveling_s)
		return "IMU data for levelling: " + std::to_string(t_s - start_s_) + " s of " +
		       std::to_string(imu_.leveling_s) + " s (imu.leveling_s)";
	if (initial_.position_from_fix && !fix_)
		return std::to_string(consensus_.params().min_fixes) + " agreeing GPS fixes on label '" +
		       initial_.fix_label + "' (filter.initial.position: gps, filter.initial.fix_consensus): " +
		       std::to_string(consensus_.agreeing()) + " of " + std::to_string(consensus_.fixes()) +
		       " agree; set filter.initial.position: config to start without them";
	return "initialisation";
}

void Initializer::clear()
{
	f_sum_b_.setZero();
	samples_ = 0;
	start_s_ = -1;
	consensus_.clear();
	fix_.reset();
}

}  // namespace auvnav
