#include "harness.h"

#include <Eigen/Eigenvalues>

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "mission.h"

namespace fs = std::filesystem;

namespace auvnav::test
{
double yawOf(const Eigen::Matrix3d& R)
{
	return std::atan2(R(1, 0), R(0, 0));
}

RunResult runNavigator(const std::string& config_file, const std::string& rawlog,
                       const std::vector<std::pair<std::string, std::string>>& overrides,
                       const std::vector<DenialWindow>& denials)
{
	auto cfg = config::Node::load(config_file);
	for (const auto& [k, v] : overrides) cfg.set(k, v);
	PluginHost host;  // outlives nav (declared first): the models keep their libraries loaded
	Navigator nav(cfg, host);
	for (const auto& d : denials) nav.addDenial(d);
	RunResult res;
	double next_row = 0;
	RunCallbacks callbacks;
	callbacks.on_predict = [&](const Navigator& n)
	{
		if (n.time() < next_row) return;
		next_row = std::floor(n.time()) + 1.0;
		EstimateRow r;
		r.t_unix = n.time();
		r.p_n = n.bodyPosition_n();
		r.R_nb = n.filter().state().R_nb;
		const auto& P = n.filter().covariance();
		r.P_ne = P.block<2, 2>(idx::pos, idx::pos);
		r.P_att = P.block<3, 3>(idx::att, idx::att);
		res.rows.push_back(r);
	};
	const RunSummary run = runRawlog(nav, rawlog, callbacks);
	run.rethrow();
	res.wall_s = run.wall_s;
	res.data_s = run.data_s;
	res.stats = run.stats;
	res.repairs = nav.filter().choleskyRepairs();
	res.status = nav.health().status();
	res.worst = nav.health().worst();
	res.status_reason = nav.health().reason();
	return res;
}

std::pair<std::size_t, std::size_t> diveAndResurfacing(const std::vector<TruthRow>& truth)
{
	std::size_t dive = 0;
	while (dive < truth.size() && !truth[dive].submerged) ++dive;
	std::size_t surf = dive;
	while (surf < truth.size() && truth[surf].submerged) ++surf;
	return {dive, surf};
}

HorizontalError horizontalError(const Navigator& nav, const std::vector<TruthRow>& truth)
{
	const auto& tr = truthAt(truth, nav.time());
	const Eigen::Matrix2d P = nav.filter().covariance().block<2, 2>(idx::pos, idx::pos);
	HorizontalError e;
	e.error_m = (nav.bodyPosition_n() - tr.p_n).head<2>().norm();
	e.two_sigma_m = 2 * std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(P).eigenvalues().maxCoeff());
	return e;
}

ScratchDir simulate(const std::string& mission, unsigned seed)
{
	return simulate(mission, seed, {}, "");
}

ScratchDir simulate(const std::string& mission, unsigned seed,
                    const std::vector<std::pair<std::string, std::string>>& sensor_overrides,
                    const std::string& tag)
{
	auto spec = sim::MissionSpec::load(std::string(AUVNAV_SOURCE_DIR) + "/" + mission);
	for (const auto& [k, v] : sensor_overrides) spec.sensors.set(k, v);
	ScratchDir dir("it_" + spec.name + tag + "_" + std::to_string(seed));
	sim::runMission(spec, seed, dir.string());
	return dir;
}

}  // namespace auvnav::test
