#include "dvl.h"

#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/so3.h>
#include <auvnav/state_block_config.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iterator>

#include "plugin_common.h"

namespace auvnav::plugins
{
namespace
{
using obs::DvlFrame;

/** NED ↔ ENU: swaps north and east and flips down to up (its own inverse). */
Eigen::Matrix3d nedToEnu()
{
	Eigen::Matrix3d P;
	P << 0, 1, 0, 1, 0, 0, 0, 0, -1;
	return P;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
	Eigen::Matrix3d S;
	S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
	return S;
}

/** The sensor's covariance if it is a usable one (finite, symmetric,
 *  positive semi-definite, not all zero, positive definite once `extra_var`
 *  is added); else nothing. */
bool usableCovariance(const std::array<double, 9>& cov_rowmajor, double extra_var, Eigen::Matrix3d& C)
{
	C = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cov_rowmajor.data());
	if (!(C.allFinite() && C.cwiseAbs().maxCoeff() > 0 &&
	      (C - C.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * C.cwiseAbs().maxCoeff()))
		return false;
	C = 0.5 * (C + C.transpose()).eval();
	const double min_ev =
	    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C, Eigen::EigenvaluesOnly).eigenvalues()[0];
	return min_ev >= 0 && min_ev + extra_var > 0;
}

std::string frameLabel(DvlFrame f)
{
	return f == DvlFrame::Instrument ? "velocity" : "velocity_" + std::string(obs::dvlFrameName(f));
}

/** v_s_b: the DVL point's velocity over ground in body axes, seen through
 *  the misalignment state δ (if any; not in the Earth frames, dvl.h). */
Eigen::Vector3d sensorVelocity_b(const NavState& x, const Eigen::Vector3d& r_s, const FilterContext& ctx,
                                 const PluginState& misalignment, DvlFrame frame)
{
	const Eigen::Matrix3d R_bn = x.R_nb.transpose();
	const Eigen::Vector3d omega_eb_b = ctx.omega_ib_b - x.b_w - R_bn * ctx.omega_ie_n;
	Eigen::Vector3d v_s_b = R_bn * x.v_n + omega_eb_b.cross(r_s - ctx.imu_position_b);
	// The true mounting is Exp(δ) R_bs: the sensor sees Exp(δ)ᵀ v in body axes.
	if (misalignment.enabled() && frame != DvlFrame::EarthNed && frame != DvlFrame::EarthEnu)
		v_s_b = so3::Exp(misalignment.segment<3>(x)).transpose() * v_s_b;
	return v_s_b;
}
}  // namespace

DvlModel::DvlModel(const config::Node& cfg, const std::string& /*label*/)
    : GatedModel(cfg),
      position_b_(cfg.vector3("position_m", Eigen::Vector3d(0.659, -0.141, 0.206))),
      R_bs_(rotationFromYprDeg(cfg.vector3("orientation_ypr_deg", Eigen::Vector3d(-22.5, 0, 0)))),
      use_observation_pose_(cfg.boolean("use_observation_pose", false)),
      sigma_mps_(cfg.positive("sigma_mps", 0.02)),
      extra_sigma_mps_(cfg.nonNegative("extra_sigma_mps", 0.005)),
      beam_sigma_mps_(cfg.positive("beam_sigma_mps", 0.01)),
      earth_heading_sigma_rad_(cfg.inRange("earth_heading_sigma_deg", 0, 90, 2.0) * kDeg),
      earth_tilt_sigma_rad_(cfg.inRange("earth_tilt_sigma_deg", 0, 90, 0.5) * kDeg),
      scale_reference_lag_s_(cfg.inRange("scale_reference_lag_s", 0, 600, 10.0))
{
	if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
	if (cfg.has("states"))
	{
		const auto st = cfg.child("states");
		st.allowOnly({"scale_factor", "misalignment"});
		if (st.has("scale_factor"))
			scale_ = PluginState(stateBlockFromConfig(st.child("scale_factor"), "scale_factor", {""}));
		if (st.has("misalignment"))
			misalignment_ = PluginState(stateBlockFromConfig(st.child("misalignment"), "misalignment",
			                                                 {"x", "y", "z"}, "_deg", kDeg));
	}
}

PrepareStatus DvlModel::doPrepare(const mrpt::obs::CObservation& o, const FilterContext& ctx,
                                  std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto* dvl = observationAs<obs::CObservationDVL>(o, why);
	if (!dvl) return PrepareStatus::Invalid;
	if (!dvl->bottom_lock)
	{
		why = "no bottom lock";
		return PrepareStatus::Skip;
	}

	Mount mount{position_b_, R_bs_};
	if (use_observation_pose_)
	{
		mount.r_s = Eigen::Vector3d(dvl->sensorPose.x(), dvl->sensorPose.y(), dvl->sensorPose.z());
		mount.R_bs = dvl->sensorPose.getRotationMatrix().asEigen();
		if (!mount.r_s.allFinite() || !mount.R_bs.allFinite())
		{
			why = "non-finite sensorPose";
			return PrepareStatus::Invalid;
		}
	}

	double sign = 1;
	switch (dvl->sign)
	{
		case obs::DvlSign::VehicleOverBottom:
			sign = 1;
			break;
		case obs::DvlSign::BottomOverInstrument:
			sign = -1;
			break;
		default:
			why = "unknown DVL sign code";
			return PrepareStatus::Invalid;
	}
	const PrepareStatus status = [&]
	{
		switch (dvl->frame)
		{
			case DvlFrame::Instrument:
			case DvlFrame::Vehicle:
			case DvlFrame::EarthNed:
			case DvlFrame::EarthEnu:
				return prepareVelocity(*dvl, mount, sign, out, why);
			case DvlFrame::Beam:
				return prepareBeams(*dvl, mount, sign, out, why);
		}
		why = "unknown DVL frame code " + std::to_string(static_cast<unsigned>(dvl->frame));
		return PrepareStatus::Invalid;
	}();
	if (status == PrepareStatus::Ok) setScaleReference(mount.r_s, dvl->frame, ctx, out);
	return status;
}

void DvlModel::setScaleReference(const Eigen::Vector3d& r_s, DvlFrame frame, const FilterContext& ctx,
                                 std::vector<Measurement>& out)
{
	if (!scale_.enabled()) return;
	Eigen::Vector3d ref_b = Eigen::Vector3d::Zero();
	double ref_valid = 0;
	if (scale_reference_lag_s_ > 0)
	{
		const double t = ctx.t_s, lag = scale_reference_lag_s_;
		auto& history = scale_reference_history_;
		// Re-filtering from an earlier checkpoint (delayed measurements): the
		// pings after it are undone, so are their entries.
		while (!history.empty() && history.back().first > t) history.pop_back();
		if (ctx.mean && scale_.presentIn(*ctx.mean) &&
		    (!misalignment_.enabled() || misalignment_.presentIn(*ctx.mean)))
			history.emplace_back(t, sensorVelocity_b(*ctx.mean, r_s, ctx, misalignment_, frame));
		// Kept for twice the lag plus re-filtering (≥ 10 s, filter_history.h); at
		// most kMaxHistory entries if time stands still.
		constexpr std::size_t kMaxHistory = 100000;
		while (!history.empty() && (history.front().first < t - 2 * lag - 60 || history.size() > kMaxHistory))
			history.pop_front();
		// The newest entry at least `lag` old, if it is not older than 2 lag
		// (after a gap in bottom lock the velocity may have changed).
		const auto newer = std::upper_bound(history.begin(), history.end(), t - lag,
		                                    [](double tt, const auto& e) { return tt < e.first; });
		if (newer != history.begin())
		{
			const auto& [t_ref, r] = *std::prev(newer);
			if (t - t_ref <= 2 * lag)
			{
				ref_b = r;
				ref_valid = 1;
			}
		}
	}
	for (Measurement& m : out)
	{
		DvlPing& ping = m.payload<DvlPing>();
		Eigen::Map<Eigen::Vector3d>(ping.scale_reference_b) = ref_b;
		ping.scale_reference_valid = ref_valid;
	}
}

PrepareStatus DvlModel::prepareVelocity(const obs::CObservationDVL& dvl, const Mount& mount, double sign,
                                        std::vector<Measurement>& out, std::string& why) const
{
	const Eigen::Vector3d v(dvl.velocity_s_mps[0], dvl.velocity_s_mps[1], dvl.velocity_s_mps[2]);
	if (!v.allFinite())
	{
		why = "non-finite velocity";
		return PrepareStatus::Invalid;
	}
	const double extra_var = extra_sigma_mps_ * extra_sigma_mps_;
	Eigen::Matrix3d C;
	const bool cov_ok = usableCovariance(dvl.velocity_cov, extra_var, C);
	if (!cov_ok) C = Eigen::Matrix3d::Identity() * (sigma_mps_ * sigma_mps_);

	Measurement m;
	m.z = v;
	m.R = C + Eigen::Matrix3d::Identity() * extra_var;
	if (dvl.frame == DvlFrame::EarthNed) m.R += earthAttitudeCovariance(v);
	if (dvl.frame == DvlFrame::EarthEnu)
	{
		const Eigen::Matrix3d P = nedToEnu();
		m.R += P * earthAttitudeCovariance(P * v) * P.transpose();
	}
	m.tag = static_cast<int>(dvl.frame);
	m.label = frameLabel(dvl.frame) + (cov_ok ? "" : "_default_cov");
	DvlPing& ping = m.setPayload(
	    DvlPing{{mount.r_s.x(), mount.r_s.y(), mount.r_s.z()}, {0, 0, 0}, sign, 0, {0, 0, 0}, 0});
	if (dvl.frame == DvlFrame::Instrument) Eigen::Map<Eigen::Vector3d>(ping.axis) = so3::Log(mount.R_bs);
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

PrepareStatus DvlModel::prepareBeams(const obs::CObservationDVL& dvl, const Mount& mount, double sign,
                                     std::vector<Measurement>& out, std::string& why) const
{
	const double incl = dvl.beam_inclination_rad;
	if (!(incl > 0 && incl < M_PI / 2))
	{
		why = "beam inclination " + std::to_string(incl) + " rad outside (0, pi/2)";
		return PrepareStatus::Invalid;
	}
	const double obs_sigma = dvl.beam_velocity_sigma_mps;
	const bool sigma_ok = std::isfinite(obs_sigma) && obs_sigma > 0;
	const double sigma = sigma_ok ? obs_sigma : beam_sigma_mps_;
	const double var = sigma * sigma + extra_sigma_mps_ * extra_sigma_mps_;
	for (std::size_t i = 0; i < dvl.beams.size(); ++i)
	{
		const auto& b = dvl.beams[i];
		if (!b.valid) continue;  // no bottom return: nothing measured along this beam
		if (!std::isfinite(b.velocity_mps) || !std::isfinite(b.azimuth_rad))
		{
			out.clear();
			why = "non-finite velocity or azimuth of valid beam " + std::to_string(i);
			return PrepareStatus::Invalid;
		}
		const Eigen::Vector3d u_s(std::sin(incl) * std::cos(b.azimuth_rad),
		                          std::sin(incl) * std::sin(b.azimuth_rad), std::cos(incl));
		const Eigen::Vector3d u_b = mount.R_bs * u_s;
		Measurement m;
		m.z = Eigen::VectorXd::Constant(1, b.velocity_mps);
		m.R = Eigen::MatrixXd::Constant(1, 1, var);
		m.tag = static_cast<int>(DvlFrame::Beam);
		m.label = sigma_ok ? "beam" : "beam_default_sigma";
		m.setPayload(DvlPing{{mount.r_s.x(), mount.r_s.y(), mount.r_s.z()},
		                     {u_b.x(), u_b.y(), u_b.z()},
		                     sign,
		                     static_cast<double>(i),
		                     {0, 0, 0},
		                     0});
		out.push_back(std::move(m));
	}
	// Three beams fix the 3-D velocity; fewer would let one bad beam pass unchecked.
	if (out.size() < 3)
	{
		why = "beam mode: " + std::to_string(out.size()) + " valid beam(s), at least 3 needed";
		out.clear();
		return PrepareStatus::Skip;
	}
	return PrepareStatus::Ok;
}

Eigen::Matrix3d DvlModel::earthAttitudeCovariance(const Eigen::Vector3d& v_n) const
{
	// δv = δθ × v = −[v]× δθ, δθ = (roll/pitch-like tilt about N and E, heading about D).
	const Eigen::Vector3d var(earth_tilt_sigma_rad_ * earth_tilt_sigma_rad_,
	                          earth_tilt_sigma_rad_ * earth_tilt_sigma_rad_,
	                          earth_heading_sigma_rad_ * earth_heading_sigma_rad_);
	const Eigen::Matrix3d S = skew(v_n);
	return S * var.asDiagonal() * S.transpose();
}

bool DvlModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
                         Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	const DvlPing& ping = m.payload<DvlPing>();
	const Eigen::Map<const Eigen::Vector3d> r_s(ping.r_s);
	Eigen::Vector3d v_s_b = sensorVelocity_b(x, r_s, ctx, misalignment_, static_cast<DvlFrame>(m.tag));
	if (scale_.enabled())
	{
		// (1 + s) v_s_b, with the scale's term at the lagged reference (dvl.h).
		const double s = scale_.value(x);
		if (ping.scale_reference_valid != 0)
			v_s_b += s * Eigen::Map<const Eigen::Vector3d>(ping.scale_reference_b);
		else
			v_s_b *= 1 + s;
	}
	const double sign = ping.sign;
	const Eigen::Map<const Eigen::Vector3d> a(ping.axis);
	switch (static_cast<DvlFrame>(m.tag))
	{
		case DvlFrame::Instrument:
			if (z_pred.size() != 3) return false;
			z_pred = sign * (so3::Exp(a).transpose() * v_s_b);
			return true;
		case DvlFrame::Vehicle:
			if (z_pred.size() != 3) return false;
			z_pred = sign * v_s_b;
			return true;
		case DvlFrame::EarthNed:
			if (z_pred.size() != 3) return false;
			z_pred = sign * (x.R_nb * v_s_b);
			return true;
		case DvlFrame::EarthEnu:
			if (z_pred.size() != 3) return false;
			z_pred = sign * (nedToEnu() * (x.R_nb * v_s_b));
			return true;
		case DvlFrame::Beam:
			if (z_pred.size() != 1) return false;
			z_pred[0] = sign * a.dot(v_s_b);
			return true;
	}
	return false;
}

}  // namespace auvnav::plugins
