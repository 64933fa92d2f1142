#include "smooth_outputs.h"

#include <auvnav/io/c_file.h>
#include <auvnav/io/json.h>
#include <auvnav/io/line_file.h>
#include <auvnav/smoother_stream.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "run_outputs.h"

namespace fs = std::filesystem;

namespace auvnav::run
{
std::string stretchFileOf(const std::string& run_dir)
{
	return (fs::path(run_dir) / "smoother" / "stretches.bin").string();
}

namespace
{
/** Scratch rows, newest first: t, kind, R_nb (9), euclidean (n), σ (n),
 *  the six off-diagonal covariances. */
class ReversedRows
{
 public:
	ReversedRows(const std::string& path, int n)
	    : path_(path), n_(n), row_(2 + 9 + 2 * n + 6), f_(io::openCFile(path, "w+b", "cannot create"))
	{
	}
	~ReversedRows()
	{
		f_.reset();
		std::error_code ec;
		fs::remove(path_, ec);
	}
	void add(double t, const NavState& x, const Covariance& P, SmoothedKind kind)
	{
		double* p = row_.data();
		*p++ = t;
		*p++ = static_cast<double>(kind);
		std::memcpy(p, x.R_nb.data(), 9 * sizeof(double));
		p += 9;
		const TangentVector e = x.euclidean();
		std::memcpy(p, e.data(), n_ * sizeof(double));
		p += n_;
		sigmaAndOffDiagonals(P, p, p + n_);
		if (std::fwrite(row_.data(), sizeof(double), row_.size(), f_.get()) != row_.size())
			throw std::runtime_error(path_ + ": write failed");
		++rows_;
	}
	std::size_t rows() const { return rows_; }
	/** Row i in time order (the last one written is the first). */
	void get(std::size_t i, double& t, NavState& x, SmoothedKind& kind, const double*& sigma,
	         const double*& cov)
	{
		const off_t at = static_cast<off_t>((rows_ - 1 - i) * row_.size() * sizeof(double));
		if (fseeko(f_.get(), at, SEEK_SET) != 0 ||
		    std::fread(row_.data(), sizeof(double), row_.size(), f_.get()) != row_.size())
			throw std::runtime_error(path_ + ": read failed");
		const double* p = row_.data();
		t = *p++;
		kind = static_cast<SmoothedKind>(static_cast<int>(*p++));
		std::memcpy(x.R_nb.data(), p, 9 * sizeof(double));
		p += 9;
		x.extra.resize(n_ - idx::core_dim);
		x.setEuclidean(Eigen::Map<const TangentVector>(p, n_));
		sigma = p + n_;
		cov = p + 2 * n_;
	}

 private:
	std::string path_;
	int n_;
	std::vector<double> row_;  // before f_: no file is created if it cannot be allocated
	io::CFile f_;
	std::size_t rows_ = 0;
};
}  // namespace

SmoothRunResult smoothRun(const std::string& run_dir)
{
	const auto t0 = std::chrono::steady_clock::now();
	const std::string stretches = stretchFileOf(run_dir);
	if (!fs::exists(stretches))
		throw std::runtime_error(stretches +
		                         ": no stretch file (was the run made with auvnav-run --smooth?)");
	StretchFileHeader header;
	{
		StretchReader probe(stretches);
		header = probe.header();
	}
	SmoothRunResult res;
	ReversedRows scratch((fs::path(run_dir) / "smoother" / "reversed.tmp").string(), header.n);
	const BackwardPassSummary sum =
	    smoothStretchFile(stretches, [&](double t, const NavState& x, const Covariance& P, SmoothedKind kind)
	                      { scratch.add(t, x, P, kind); });

	// Text outputs written as .tmp and renamed: a half-written file never
	// stands beside a finished run.
	const fs::path tum_path = fs::path(run_dir) / "smoothed_trajectory.tum";
	const fs::path csv_path = fs::path(run_dir) / "smoothed_states.csv";
	std::size_t written = 0;
	{
		io::LineFile tum(tum_path.string() + ".tmp"), csv(csv_path.string() + ".tmp");
		tum.line(
		    "# timestamp north_m east_m down_m qx qy qz qw  (body origin, NED tangent frame; auvnav RTS "
		    "smoother)");
		csv.line(statesCsvHeader(header.tangent_names, header.stored_names) + ",smoother");
		std::string row;
		NavState x;
		for (std::size_t i = 0; i < scratch.rows(); ++i)
		{
			double t;
			SmoothedKind kind;
			const double *sigma, *cov;
			if (i + 1 < scratch.rows())
			{
				// A segment's end and the next segment's start (before and
				// after a reset) share a time: one row per time, the later.
				double t_next;
				SmoothedKind k_next;
				const double *s_next, *c_next;
				scratch.get(i + 1, t_next, x, k_next, s_next, c_next);
				scratch.get(i, t, x, kind, sigma, cov);
				if (t_next == t) continue;
			}
			else
				scratch.get(i, t, x, kind, sigma, cov);
			++written;
			const Eigen::Vector3d p = x.p_n - x.R_nb * header.imu_position_b;
			formatTumRow(row, t, x, p);
			tum.line(row);
			formatStatesRow(row, t, x, p, sigma, cov);
			row += ',';
			row += smoothedKindName(kind);
			csv.line(row);
		}
		tum.flush();
		csv.flush();
	}
	fs::rename(tum_path.string() + ".tmp", tum_path);
	fs::rename(csv_path.string() + ".tmp", csv_path);

	res.rows = written;
	res.smoothed = sum.smoothed;
	res.segment_ends = sum.segment_ends;
	res.kept = sum.kept;
	res.repairs = sum.repairs;
	res.limit_hits = sum.limit_hits;
	res.partial_tail = sum.partial_tail;
	res.stretch_bytes = fs::file_size(stretches);
	res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

	io::Json j;
	j["rows"] = res.rows;
	j["smoothed"] = res.smoothed;
	j["segment_ends"] = res.segment_ends;
	j["filtered_kept"] = res.kept;
	j["covariance_repairs"] = res.repairs;
	j["sigma_limit_hits"] = res.limit_hits;
	j["partial_last_record"] = res.partial_tail;
	j["stretch_file_bytes"] = res.stretch_bytes;
	j["stretch_record_bytes"] = stretchRecordBytes(header.n);
	j["state_dim"] = header.n;
	j["backward_wall_s"] = res.wall_s;
	io::writeJsonAtomically(fs::path(run_dir) / "smoother.json", j);
	return res;
}
}  // namespace auvnav::run
