#pragma once
/** @file guidance.h
 *  Mission plan and the vehicle's guidance & control: line-of-sight waypoint
 *  following, surge-speed, depth, pitch and heading loops producing a body
 *  wrench, and thrust allocation through the pseudo-inverse of the thruster
 *  configuration matrix (roll row dropped unless roll gains are set, for vehicles whose
 *  thrusters can roll them, e.g. the BlueROV2 Heavy) with per-thruster saturation. The controller sees
 *  the true state (the simulator's autopilot is not under test).
 */
#include <auvnav/config.h>

#include <Eigen/Core>
#include <vector>

#include "vehicle.h"

namespace auvnav::sim
{
struct PlanStep
{
	enum class Kind
	{
		Goto,  //!< follow the line from the current position to `target_ne`
		Wait   //!< hold heading for `duration_s` with zero speed demand
	};
	Kind kind = Kind::Goto;
	Eigen::Vector2d target_ne{0, 0};
	bool surface = true;  //!< float at the surface (no depth control)
	double depth_m = 0;   //!< depth demand when not surfaced
	double speed_mps = 0.5;
	double duration_s = 0;
	double acceptance_m = 2;
	std::string describe() const;
};

/** Reads `plan:` (a list of steps; `repeat: N` + `steps:` expands). */
std::vector<PlanStep> planFromConfig(const config::Node& mission);

struct ControllerGains
{
	double lookahead_m = 6;
	double heading_kp = 120, heading_kd = 350;           // N·m/rad, N·m/(rad/s)
	double speed_kp = 150, speed_ki = 10;                // N/(m/s), N/m
	double sway_kp = 80;                                 // N/(m/s)
	double depth_kp = 60, depth_kd = 250, depth_ki = 2;  // N/m, N/(m/s), N/(m·s)
	double attitude_kp = 200, attitude_kd = 60;          // pitch hold, N·m/rad, N·m/(rad/s)
	//! Roll hold, N·m/rad, N·m/(rad/s); 0 (default): roll left to the restoring
	//! moment and the roll row dropped from the allocation (5 controlled axes).
	double roll_kp = 0, roll_kd = 0;
	bool controlsRoll() const { return roll_kp > 0 || roll_kd > 0; }
	double speed_ramp_mps2 = 0.02;
	double depth_rate_mps = 0.15;  //!< slew limit of the depth demand
	static ControllerGains fromConfig(const config::Node& n);
};

class Controller
{
 public:
	Controller(const VehicleParams& vehicle, const ControllerGains& gains, std::vector<PlanStep> plan);

	/** Thruster force commands for the next control period [N]. */
	Eigen::VectorXd command(const VehicleState& x, double t_s, double dt_s);
	bool finished() const { return step_ >= plan_.size(); }
	std::size_t stepIndex() const { return step_; }
	bool surfaceDemanded() const;

 private:
	void beginStep(const VehicleState& x, double t_s);
	Vector6d wrench(const VehicleState& x, double dt_s);

	VehicleParams vehicle_;
	ControllerGains k_;
	std::vector<PlanStep> plan_;
	Eigen::MatrixXd allocation_;  // pseudo-inverse of the configuration matrix
	std::size_t step_ = 0;
	bool started_ = false;
	double step_start_s_ = 0;
	Eigen::Vector2d leg_start_ne_{0, 0};
	double heading_hold_rad_ = 0;
	double speed_demand_mps_ = 0;
	double depth_demand_m_ = 0;
	double speed_integral_ = 0, depth_integral_ = 0;
};

}  // namespace auvnav::sim
