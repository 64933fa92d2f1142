#include "guidance.h"
#include <auvnav/angles.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace auvnav::sim
{
namespace
{
double yawOf(const Eigen::Matrix3d& R_nb)
{
	return std::atan2(R_nb(1, 0), R_nb(0, 0));
}

void appendSteps(const config::Node& list_owner, const std::string& key, std::vector<PlanStep>& out,
                 int depth)
{
	if (depth > 4) list_owner.fail(key, "repeat blocks nested too deep");
	for (const auto& s : list_owner.sequence(key))
	{
		if (s.has("repeat"))
		{
			const int n = s.integer("repeat");
			if (n < 1 || n > 1000) s.fail("repeat", "expected 1..1000");
			for (int i = 0; i < n; ++i) appendSteps(s, "steps", out, depth + 1);
			continue;
		}
		PlanStep p;
		p.surface = s.boolean("surface", false);
		p.depth_m = p.surface ? 0 : s.nonNegative("depth_m");
		if (s.has("goto"))
		{
			const auto ne = s.numbers("goto");
			if (ne.size() != 2) s.fail("goto", "expected [north_m, east_m]");
			p.kind = PlanStep::Kind::Goto;
			p.target_ne = {ne[0], ne[1]};
			p.speed_mps = s.inRange("speed_mps", 0.05, 2.0);
			p.acceptance_m = s.positive("acceptance_m", 2.0);
		}
		else if (s.has("wait_s"))
		{
			p.kind = PlanStep::Kind::Wait;
			p.duration_s = s.positive("wait_s");
			p.speed_mps = 0;
		}
		else
			s.fail("goto", "each plan step needs 'goto', 'wait_s' or 'repeat'");
		out.push_back(p);
	}
}
}  // namespace

std::string PlanStep::describe() const
{
	std::ostringstream s;
	if (kind == Kind::Goto)
		s << "goto (" << target_ne.x() << ", " << target_ne.y() << ") at " << speed_mps << " m/s";
	else
		s << "wait " << duration_s << " s";
	s << (surface ? " on the surface" : " at " + std::to_string(depth_m) + " m");
	return s.str();
}

std::vector<PlanStep> planFromConfig(const config::Node& mission)
{
	std::vector<PlanStep> plan;
	appendSteps(mission, "plan", plan, 0);
	if (plan.empty()) mission.fail("plan", "the plan is empty");
	return plan;
}

ControllerGains ControllerGains::fromConfig(const config::Node& n)
{
	ControllerGains k;
	k.lookahead_m = n.positive("lookahead_m", k.lookahead_m);
	k.heading_kp = n.nonNegative("heading_kp", k.heading_kp);
	k.heading_kd = n.nonNegative("heading_kd", k.heading_kd);
	k.speed_kp = n.nonNegative("speed_kp", k.speed_kp);
	k.speed_ki = n.nonNegative("speed_ki", k.speed_ki);
	k.sway_kp = n.nonNegative("sway_kp", k.sway_kp);
	k.depth_kp = n.nonNegative("depth_kp", k.depth_kp);
	k.depth_kd = n.nonNegative("depth_kd", k.depth_kd);
	k.depth_ki = n.nonNegative("depth_ki", k.depth_ki);
	k.attitude_kp = n.nonNegative("attitude_kp", k.attitude_kp);
	k.attitude_kd = n.nonNegative("attitude_kd", k.attitude_kd);
	k.roll_kp = n.nonNegative("roll_kp", k.roll_kp);
	k.roll_kd = n.nonNegative("roll_kd", k.roll_kd);
	k.speed_ramp_mps2 = n.positive("speed_ramp_mps2", k.speed_ramp_mps2);
	k.depth_rate_mps = n.positive("depth_rate_mps", k.depth_rate_mps);
	return k;
}

Controller::Controller(const VehicleParams& vehicle, const ControllerGains& gains, std::vector<PlanStep> plan)
    : vehicle_(vehicle), k_(gains), plan_(std::move(plan))
{
	// Allocate surge, sway, heave, pitch and yaw only: with two heave thrusters
	// roll and pitch cannot be set independently (the configuration matrix has
	// rank 5), so roll is left to the hydrostatic restoring moment.
	const auto T = vehicle_.configurationMatrix();
	if (k_.controlsRoll())
	{
		// All six axes: only if the thrusters span them (e.g. 4 vertical thrusters).
		const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod{Eigen::MatrixXd(T)};
		if (cod.rank() < 6)
			throw config::ConfigError(
			    "controller.roll_kp/roll_kd: the thrusters cannot produce all six axes "
			    "(configuration matrix rank " +
			    std::to_string(cod.rank()) + "); leave roll to the restoring moment (gains 0)");
		allocation_ = cod.pseudoInverse();
		return;
	}
	Eigen::MatrixXd T_controlled(5, T.cols());
	T_controlled << T.row(0), T.row(1), T.row(2), T.row(4), T.row(5);
	allocation_ = T_controlled.completeOrthogonalDecomposition().pseudoInverse();
}

bool Controller::surfaceDemanded() const
{
	return finished() || plan_[step_].surface;
}

void Controller::beginStep(const VehicleState& x, double t_s)
{
	step_start_s_ = t_s;
	leg_start_ne_ = x.p_n.head<2>();
	heading_hold_rad_ = yawOf(x.R_nb());
	started_ = true;
}

Vector6d Controller::wrench(const VehicleState& x, double dt_s)
{
	const PlanStep& s = plan_[step_];
	const Eigen::Matrix3d R_nb = x.R_nb();
	const double yaw = yawOf(R_nb);
	const Eigen::Vector3d v_b = x.nu_b.head<3>();
	const double r = x.nu_b[5];

	double heading_demand = heading_hold_rad_;
	double speed_target = 0;
	if (s.kind == PlanStep::Kind::Goto)
	{
		// Line-of-sight guidance along the leg (Fossen 2011, ch. 10).
		const Eigen::Vector2d leg = s.target_ne - leg_start_ne_;
		const double path = leg.norm() > 1e-6 ? std::atan2(leg.y(), leg.x()) : yaw;
		const Eigen::Vector2d e = x.p_n.head<2>() - leg_start_ne_;
		const double cross = -e.x() * std::sin(path) + e.y() * std::cos(path);
		heading_demand = path + std::atan(-cross / k_.lookahead_m);
		speed_target = s.speed_mps;
	}
	// Ramp the speed demand: no thrust steps at leg changes.
	const double max_change = k_.speed_ramp_mps2 * dt_s;
	speed_demand_mps_ += std::clamp(speed_target - speed_demand_mps_, -max_change, max_change);

	Vector6d tau = Vector6d::Zero();
	const double u_err = speed_demand_mps_ - v_b.x();
	speed_integral_ = std::clamp(speed_integral_ + u_err * dt_s, -5.0, 5.0);
	const double ff = vehicle_.D_l(0, 0) * speed_demand_mps_ +
	                  vehicle_.D_q(0, 0) * speed_demand_mps_ * std::abs(speed_demand_mps_);
	tau[0] = ff + k_.speed_kp * u_err + k_.speed_ki * speed_integral_;
	tau[1] = -k_.sway_kp * v_b.y();
	tau[5] = k_.heading_kp * wrapAngle(heading_demand - yaw) - k_.heading_kd * r;
	// Pitch hold: the weak metacentric restoring alone lets the Munk moment
	// pitch the vehicle steeply while diving.
	const double pitch = -std::asin(std::clamp(R_nb(2, 0), -1.0, 1.0));
	tau[4] = -k_.attitude_kp * pitch - k_.attitude_kd * x.nu_b[4];
	if (k_.controlsRoll())
	{
		const double roll = std::atan2(R_nb(2, 1), R_nb(2, 2));
		tau[3] = -k_.roll_kp * roll - k_.roll_kd * x.nu_b[3];
	}
	if (!s.surface)
	{
		// Slew the depth demand: dives and climbs at a bounded rate, no overshoot.
		const double max_step = k_.depth_rate_mps * dt_s;
		depth_demand_m_ += std::clamp(s.depth_m - depth_demand_m_, -max_step, max_step);
		const double depth_err = depth_demand_m_ - x.p_n.z();
		const double depth_rate = x.v_n().z();
		depth_integral_ = std::clamp(depth_integral_ + depth_err * dt_s, -20.0, 20.0);
		// Feed-forward cancels the net buoyancy.
		const double fz_n = (vehicle_.buoyancy_n - vehicle_.weight_n) + k_.depth_kp * depth_err -
		                    k_.depth_kd * depth_rate + k_.depth_ki * depth_integral_;
		tau.head<3>() += R_nb.transpose() * Eigen::Vector3d(0, 0, fz_n);
	}
	else
	{
		depth_integral_ = 0;
		depth_demand_m_ = x.p_n.z();  // a later dive starts from where the vehicle floats
	}
	return tau;
}

Eigen::VectorXd Controller::command(const VehicleState& x, double t_s, double dt_s)
{
	if (finished()) return Eigen::VectorXd::Zero(vehicle_.thrusters.size());
	if (!started_) beginStep(x, t_s);
	const PlanStep* s = &plan_[step_];
	const bool done = s->kind == PlanStep::Kind::Goto
	                      ? (x.p_n.head<2>() - s->target_ne).norm() < s->acceptance_m ||
	                            (x.p_n.head<2>() - leg_start_ne_).dot(s->target_ne - leg_start_ne_) >=
	                                (s->target_ne - leg_start_ne_).squaredNorm()
	                      : t_s - step_start_s_ >= s->duration_s;
	if (done)
	{
		++step_;
		if (finished()) return Eigen::VectorXd::Zero(vehicle_.thrusters.size());
		beginStep(x, t_s);
	}
	const Vector6d tau = wrench(x, dt_s);
	Eigen::VectorXd u;
	if (k_.controlsRoll())
		u = allocation_ * tau;
	else
	{
		Eigen::Matrix<double, 5, 1> tau_controlled;
		tau_controlled << tau[0], tau[1], tau[2], tau[4], tau[5];
		u = allocation_ * tau_controlled;
	}
	for (Eigen::Index i = 0; i < u.size(); ++i)
		u[i] = std::clamp(u[i], -vehicle_.thrusters[i].max_force_n, vehicle_.thrusters[i].max_force_n);
	return u;
}

}  // namespace auvnav::sim
