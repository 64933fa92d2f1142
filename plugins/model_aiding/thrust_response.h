#pragma once
/** @file thrust_response.h
 *  The force each thruster gives while its command changes (model_aiding).
 *
 *  A thruster controller takes a command when it is logged and holds it until
 *  the next one (zero-order hold); the force follows with a first-order lag,
 *      ḟ_i = (u_i − f_i) / τ_i   (τ_i = 0: at once),
 *  so the force at time t is the earlier commands' response, not the command
 *  logged at t. Comparing the command with the motion of the same instant
 *  puts the whole step of a manoeuvre's first command into the residual.
 *  Forces here are per thruster, in the plugin's force unit (gains applied).
 */
#include <Eigen/Core>
#include <cmath>
#include <vector>

namespace auvnav::plugins
{
class ThrustResponse
{
 public:
	explicit ThrustResponse(std::vector<double> time_constants_s = {}) : tau_s_(std::move(time_constants_s))
	{
	}

	bool started() const { return started_; }
	//! Time [s] of the last command held.
	double time_s() const { return t_s_; }

	/** Starts over at t_s with every thruster at steady state on `command`. */
	void restart(double t_s, const Eigen::VectorXd& command)
	{
		t_s_ = t_s;
		force_ = command;
		held_ = command;
		started_ = true;
	}

	/** Force of each thruster at t_s (the held command through the lag);
	 *  before time_s(), the force at time_s(). */
	Eigen::VectorXd forceAt(double t_s) const
	{
		Eigen::VectorXd f = force_;
		if (t_s <= t_s_) return f;
		for (Eigen::Index i = 0; i < f.size(); ++i)
			f[i] = held_[i] + (force_[i] - held_[i]) * decay(i, t_s - t_s_);
		return f;
	}

	/** df/dt of each thruster at t_s (0 once a thruster has settled). */
	Eigen::VectorXd rateAt(double t_s) const
	{
		const Eigen::VectorXd f = forceAt(t_s);
		Eigen::VectorXd rate = Eigen::VectorXd::Zero(f.size());
		for (Eigen::Index i = 0; i < f.size(); ++i)
			if (tau(i) > 0 && t_s > t_s_) rate[i] = (held_[i] - f[i]) / tau(i);
		return rate;
	}

	/** Moves to t_s (>= time_s()) and holds `command` from then on. */
	void hold(double t_s, const Eigen::VectorXd& command)
	{
		force_ = forceAt(t_s);
		held_ = command;
		t_s_ = t_s;
	}

 private:
	double tau(Eigen::Index i) const
	{
		return static_cast<std::size_t>(i) < tau_s_.size() ? tau_s_[static_cast<std::size_t>(i)] : 0.0;
	}
	//! What is left of a step after dt [s]: exp(−dt/τ), 0 for τ = 0.
	double decay(Eigen::Index i, double dt_s) const { return tau(i) > 0 ? std::exp(-dt_s / tau(i)) : 0.0; }

	std::vector<double> tau_s_;
	bool started_ = false;
	double t_s_ = 0;
	Eigen::VectorXd force_, held_;
};
}  // namespace auvnav::plugins
