#include "ground_truth.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auvnav::sim
{
std::vector<TruthRow> readTruth(const std::filesystem::path& csv)
{
	std::ifstream f(csv);
	if (!f) throw std::runtime_error("cannot read " + csv.string());
	std::string header;
	std::getline(f, header);
	std::vector<std::string> names;
	{
		std::stringstream ss(header);
		for (std::string n; std::getline(ss, n, ',');) names.push_back(n);
	}
	auto col = [&](const std::string& n) {
		const auto it = std::find(names.begin(), names.end(), n);
		if (it == names.end()) throw std::runtime_error(csv.string() + ": no column " + n);
		return static_cast<std::size_t>(it - names.begin());
	};
	const std::size_t c_t = col("unix_time_s"), c_n = col("north_m"), c_e = col("east_m"), c_d = col("down_m"),
					  c_qw = col("qw"), c_qx = col("qx"), c_qy = col("qy"), c_qz = col("qz"),
					  c_dist = col("distance_m"), c_sub = col("submerged"), c_cn = col("current_n_mps"),
					  c_ce = col("current_e_mps");
	std::vector<TruthRow> rows;
	std::vector<double> v;
	std::size_t line_no = 1;
	for (std::string line; std::getline(f, line);)
	{
		++line_no;
		v.clear();
		std::stringstream ss(line);
		for (std::string c; std::getline(ss, c, ',');) v.push_back(std::strtod(c.c_str(), nullptr));
		if (v.size() != names.size())
			throw std::runtime_error(csv.string() + ":" + std::to_string(line_no) + ": wrong number of columns");
		TruthRow r;
		r.t_unix = v[c_t];
		r.p_n = {v[c_n], v[c_e], v[c_d]};
		r.q_nb = Eigen::Quaterniond(v[c_qw], v[c_qx], v[c_qy], v[c_qz]);
		r.distance_m = v[c_dist];
		r.submerged = v[c_sub] > 0.5;
		r.current_ne = {v[c_cn], v[c_ce]};
		rows.push_back(r);
	}
	if (rows.empty()) throw std::runtime_error(csv.string() + ": no rows");
	return rows;
}

const TruthRow& truthAt(const std::vector<TruthRow>& truth, double t)
{
	auto it = std::lower_bound(truth.begin(), truth.end(), t,
							   [](const TruthRow& r, double tt) { return r.t_unix < tt; });
	if (it == truth.end()) return truth.back();
	if (it != truth.begin() && std::abs((it - 1)->t_unix - t) < std::abs(it->t_unix - t)) --it;
	return *it;
}

}  // namespace auvnav::sim
