// auvnav-heading-plot: a run without ground truth against its own magnetometer.
//   auvnav-heading-plot --run RUN_DIR --rawlog RAWLOG --config NAV.yaml [--label MAG] --out PREFIX
// Writes PREFIX_heading.png (the filter's heading with its ±3σ band and the
// magnetometer's heading), PREFIX_residual.png (magnetometer − filter heading
// with the filter's ±3σ and the ±3σ of the difference) and PREFIX_track.png
// (the body origin in the horizontal plane), and prints the figures measured.
//
// The magnetometer heading is computed as the magnetometer plugin's heading
// mode does it (magnetometer.h): the reading calibrated with the config's
// hard_iron_ut / soft_iron, rotated by the observation's sensorPose, levelled
// with the filter's attitude at that time, plus declination_deg. Its error
// therefore includes the filter's roll/pitch error (small here) but not its
// heading.
#include <auvnav/angles.h>
#include <auvnav/cli.h>
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/register.h>
#include <mrpt/obs/CObservationIMU.h>

#include <Eigen/Geometry>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "plot.h"

using namespace auvnav::eval;

namespace
{
constexpr double kDeg = M_PI / 180;
const cv::Scalar kBlue(200, 90, 30), kRed(40, 40, 220), kGrey(150, 150, 150), kGreen(60, 160, 40);

/** A CSV with a header row, as columns by name. */
std::map<std::string, std::vector<std::string>> readCsv(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw std::runtime_error("cannot read " + path);
	std::string line;
	std::getline(f, line);
	std::vector<std::string> names;
	{
		std::stringstream s(line);
		std::string c;
		while (std::getline(s, c, ',')) names.push_back(c);
	}
	std::map<std::string, std::vector<std::string>> cols;
	while (std::getline(f, line))
	{
		std::stringstream s(line);
		std::string c;
		for (std::size_t i = 0; i < names.size() && std::getline(s, c, ','); ++i) cols[names[i]].push_back(c);
	}
	return cols;
}
std::vector<double> numbers(const std::map<std::string, std::vector<std::string>>& cols,
                            const std::string& name)
{
	const auto it = cols.find(name);
	if (it == cols.end()) throw std::runtime_error("no column " + name);
	std::vector<double> v;
	for (const auto& s : it->second) v.push_back(std::stod(s));
	return v;
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Plots a run's heading against its magnetometer's and its horizontal track (no ground truth).", ' ',
	    "1");
	TCLAP::ValueArg<std::string> run("", "run", "auvnav-run output folder (states.csv, nis.csv).", true, "",
	                                 "DIR", cmd);
	TCLAP::ValueArg<std::string> rawlog("", "rawlog", "The rawlog the run read.", true, "", "RAWLOG", cmd);
	TCLAP::ValueArg<std::string> config("", "config", "The navigator config the run used.", true, "",
	                                    "NAV.yaml", cmd);
	TCLAP::ValueArg<std::string> label("", "label", "Magnetometer sensor label. Default: MAG.", false, "MAG",
	                                   "LABEL", cmd);
	TCLAP::ValueArg<std::string> title("", "title", "Title prefix of the figures.", false, "", "TEXT", cmd);
	TCLAP::ValueArg<std::string> out("", "out", "Prefix of the PNG files.", true, "", "PREFIX", cmd);
	const auvnav::cli::ObsLibOption obs_libs(cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-heading-plot")) return *code;
	try
	{
		auvnav::obs::registerAllClasses();
		// The magnetometer's calibration from the navigator config.
		const auto nav = auvnav::config::Node::load(config.getValue());
		if (const auto code = obs_libs.load("auvnav-heading-plot", auvnav::declaredObservationLibraries(nav)))
			return *code;
		Eigen::Vector3d b = Eigen::Vector3d::Zero();
		Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
		double decl_deg = 0, sigma_mag_deg = 3;
		bool found = false;
		for (const auto& s : nav.sequence("sensors"))
		{
			if (s.string("label") != label.getValue()) continue;
			const auto c = s.child("config");
			b = c.vector3("hard_iron_ut", b);
			if (c.has("soft_iron"))
			{
				const auto v = c.numbers("soft_iron");
				if (v.size() != 9) throw std::runtime_error("soft_iron needs 9 numbers");
				for (int i = 0; i < 9; ++i) S(i / 3, i % 3) = v[i];
			}
			decl_deg = c.number("declination_deg", 0.0);
			sigma_mag_deg = c.number("heading_sigma_deg", 3.0);
			found = true;
		}
		if (!found)
			throw std::runtime_error("no sensor labelled " + label.getValue() + " in " + config.getValue());
		const Eigen::Matrix3d S_inv = S.inverse();

		const auto st = readCsv(run.getValue() + "/states.csv");
		const auto t = numbers(st, "time_s"), qw = numbers(st, "qw"), qx = numbers(st, "qx"),
		           qy = numbers(st, "qy"), qz = numbers(st, "qz"), yaw = numbers(st, "yaw_deg"),
		           sig = numbers(st, "sigma_att_d"), pn = numbers(st, "body_n_m"),
		           pe = numbers(st, "body_e_m");
		if (t.size() < 2) throw std::runtime_error("states.csv has fewer than 2 rows");
		const double t0 = t.front();

		// Filter heading, unwrapped; ±3σ band.
		std::vector<double> tt, psi, lo, hi, zero, s3lo, s3hi;
		for (std::size_t i = 0; i < t.size(); ++i)
		{
			const double y = i == 0 ? yaw[0] : psi.back() + auvnav::wrapAngleDeg(yaw[i] - psi.back());
			tt.push_back(t[i] - t0);
			psi.push_back(y);
			const double s3 = 3 * sig[i] / kDeg;
			lo.push_back(y - s3);
			hi.push_back(y + s3);
			s3lo.push_back(-s3);
			s3hi.push_back(s3);
		}

		// Magnetometer heading at every reading within the run, levelled with
		// the filter's attitude (the state row at or before the reading).
		std::vector<double> tm, psi_m, res, band_lo, band_hi;
		auvnav::io::RawlogReader r(rawlog.getValue());
		std::size_t k = 0, n_in = 0;
		double sum = 0, sum2 = 0;
		while (auto o = r.next())
		{
			if (o->sensorLabel != label.getValue()) continue;
			const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(o.get());
			if (!imu || !imu->has(mrpt::obs::IMU_MAG_X)) continue;
			const double to = mrpt::Clock::toDouble(o->timestamp);
			if (to < t.front() || to > t.back()) continue;
			while (k + 1 < t.size() && t[k + 1] <= to) ++k;
			const Eigen::Vector3d raw(imu->get(mrpt::obs::IMU_MAG_X), imu->get(mrpt::obs::IMU_MAG_Y),
			                          imu->get(mrpt::obs::IMU_MAG_Z));
			mrpt::poses::CPose3D pose;
			o->getSensorPose(pose);
			const Eigen::Matrix3d R_bs = pose.getRotationMatrix().asEigen();
			const Eigen::Matrix3d R_nb =
			    Eigen::Quaterniond(qw[k], qx[k], qy[k], qz[k]).normalized().toRotationMatrix();
			const Eigen::Vector3d m_n = R_nb * (R_bs * (S_inv * (100.0 * raw - b)));
			const double alpha = std::atan2(m_n.y(), m_n.x()) / kDeg;
			const double d =
			    auvnav::wrapAngleDeg(decl_deg - alpha);  // magnetometer − filter (the plugin's residual)
			tm.push_back(to - t0);
			psi_m.push_back(psi[k] + d);
			res.push_back(d);
			const double s = 3 * std::hypot(sig[k] / kDeg, sigma_mag_deg);
			band_lo.push_back(-s);
			band_hi.push_back(s);
			sum += d;
			sum2 += d * d;
			n_in += std::abs(d) <= 1.96 * std::hypot(sig[k] / kDeg, sigma_mag_deg);
		}
		if (tm.empty()) throw std::runtime_error("no magnetometer readings within the run");
		const double n = static_cast<double>(tm.size());
		std::printf(
		    "magnetometer - filter heading: %zu readings, mean %.2f deg, rms %.2f deg, within 1.96 "
		    "sqrt(sigma_psi^2 + "
		    "heading_sigma^2): %.1f %%\n",
		    tm.size(), sum / n, std::sqrt(sum2 / n), 100.0 * n_in / n);
		// 10 s means of the difference against the filter's σ: whether the heading
		// σ is consistent with the slow part of the magnetometer's error.
		{
			std::size_t in = 0, windows = 0;
			double worst = 0;
			for (double w0 = 10; w0 + 10 <= tm.back(); w0 += 10)
			{
				double s = 0, c = 0, sg = 0;
				for (std::size_t i = 0; i < tm.size(); ++i)
					if (tm[i] >= w0 && tm[i] < w0 + 10) s += res[i], ++c;
				for (std::size_t i = 0; i < tt.size(); ++i)
					if (tt[i] >= w0 && tt[i] < w0 + 10) sg = std::max(sg, sig[i] / kDeg);
				if (c == 0) continue;
				++windows;
				in += std::abs(s / c) <= 3 * sg;
				worst = std::max(worst, std::abs(s / c));
				std::printf(
				    "  %4.0f-%4.0f s: mean difference %6.2f deg, filter heading sigma (max) %.2f deg\n", w0,
				    w0 + 10, s / c, sg);
			}
			std::printf(
			    "10 s windows from 10 s: %zu of %zu with |mean difference| <= 3 sigma; largest |mean| %.2f "
			    "deg\n",
			    in, windows, worst);
		}
		// Heading σ over time.
		for (double at : {1.0, 2.0, 5.0, 10.0, 20.0, 40.0, 60.0, tt.back()})
		{
			std::size_t i = 0;
			while (i + 1 < tt.size() && tt[i + 1] <= at) ++i;
			std::printf("  heading sigma at %5.1f s: %.3f deg\n", tt[i], sig[i] / kDeg);
		}
		double exc = 0;
		for (std::size_t i = 0; i < pn.size(); ++i)
			exc = std::max(exc, std::hypot(pn[i] - pn[0], pe[i] - pe[0]));
		std::printf("max horizontal excursion from the start: %.2f m\n", exc);

		// MAG NIS from nis.csv: per second, the summed NIS and dimension.
		{
			const auto nc = readCsv(run.getValue() + "/nis.csv");
			const auto& lab = nc.at("label");
			const auto ns = numbers(nc, "nis_sum"), ds = numbers(nc, "dim_sum");
			double a = 0, dsum = 0;
			std::size_t secs = 0, in2 = 0, in_up = 0;
			for (std::size_t i = 0; i < lab.size(); ++i)
			{
				if (lab[i] != label.getValue() || ds[i] < 1) continue;
				const boost::math::chi_squared c(ds[i]);
				++secs;
				a += ns[i];
				dsum += ds[i];
				in2 += ns[i] >= boost::math::quantile(c, 0.025) && ns[i] <= boost::math::quantile(c, 0.975);
				in_up += ns[i] <= boost::math::quantile(c, 0.95);
			}
			std::printf(
			    "%s NIS: mean per dimension %.3f over %.0f updates; seconds with the summed NIS inside the "
			    "two-sided "
			    "95 %% chi-square interval: %.1f %%, below the 95 %% quantile: %.1f %% (%zu s)\n",
			    label.getValue().c_str(), dsum > 0 ? a / dsum : NAN, dsum, secs ? 100.0 * in2 / secs : NAN,
			    secs ? 100.0 * in_up / secs : NAN, secs);
		}

		const std::string pre = title.getValue().empty() ? "" : title.getValue() + ": ";
		{
			Plot p(pre + "heading: filter (+-3 sigma), magnetometer", "time [s]", "heading, unwrapped [deg]");
			p.band(tt, lo, hi, kGrey, "filter +-3 sigma");
			p.line(tm, psi_m, kRed, "magnetometer", 1);
			p.line(tt, psi, kBlue, "filter", 2);
			double y0 = 1e9, y1 = -1e9;
			for (double v : psi_m) y0 = std::min(y0, v), y1 = std::max(y1, v);
			p.yRange(y0 - 20, y1 + 20);
			p.save(out.getValue() + "_heading.png");
		}
		{
			Plot p(pre + "magnetometer - filter heading", "time [s]", "[deg]");
			p.band(tm, band_lo, band_hi, kGreen, "+-3 sqrt(P + R)");
			p.band(tt, s3lo, s3hi, kGrey, "filter +-3 sigma");
			p.line(tm, res, kRed, "difference", 1);
			p.yRange(-30, 30);
			p.save(out.getValue() + "_residual.png");
		}
		{
			Plot p(pre + "horizontal track", "east [m]", "north [m]", 640, 640);
			std::vector<double> e, nn;
			double lim = 1;
			for (std::size_t i = 0; i < pn.size(); ++i)
			{
				e.push_back(pe[i] - pe[0]);
				nn.push_back(pn[i] - pn[0]);
				lim = std::max({lim, std::abs(e.back()), std::abs(nn.back())});
			}
			lim = std::ceil(lim + 0.5);
			p.xRange(-lim, lim);
			p.yRange(-lim, lim);
			p.line(e, nn, kBlue, "filter", 2);
			p.save(out.getValue() + "_track.png");
		}
		return 0;
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-heading-plot", e.what());
	}
}
