#include <auvnav/so3.h>
#include <auvnav/state.h>

#include <cmath>
#include <stdexcept>
#include <type_traits>

namespace auvnav
{
namespace
{
// Row-major copies of the 2x3 parameter blocks.
void put23(TangentVector& t, int at, const Eigen::Matrix<double, 2, 3>& m)
{
	for (int r = 0; r < 2; ++r)
		for (int c = 0; c < 3; ++c) t[at + 3 * r + c] = m(r, c);
}
void get23(const Eigen::Ref<const TangentVector>& t, int at, Eigen::Matrix<double, 2, 3>& m)
{
	for (int r = 0; r < 2; ++r)
		for (int c = 0; c < 3; ++c) m(r, c) = t[at + 3 * r + c];
}
}  // namespace

const std::array<StateBlockInfo, 13>& coreStateBlocks()
{
	static constexpr std::array<StateBlockInfo, 13> kBlocks = {
	    {{kAttitude, idx::att, 3, "attitude", "att"},
	     {kGyroBias, idx::gyro_bias, 3, "gyro_bias", "gyro_bias"},
	     {kAcceleration, idx::acc, 3, "acceleration", "acc"},
	     {kGravity, idx::gravity, 1, "gravity", "gravity"},
	     {kAccelBias, idx::acc_bias, 3, "accel_bias", "acc_bias"},
	     {kVelocity, idx::vel, 3, "velocity", "vel"},
	     {kPosition, idx::pos, 3, "position", "pos"},
	     {kCurrentVehicle, idx::current_vehicle, 2, "current_vehicle", "current"},
	     {kCurrentFar, idx::current_far, 2, "current_far", "current_far"},
	     {kAdcpBias, idx::adcp_bias, 2, "adcp_bias", "adcp_bias"},
	     {kInertia, idx::inertia, 6, "inertia", "M"},
	     {kDampingLinear, idx::damping_lin, 6, "damping_linear", "Dl"},
	     {kDampingQuadratic, idx::damping_quad, 6, "damping_quadratic", "Dq"}}};
	return kBlocks;
}

int tangentPrefix(uint32_t mask, int dim)
{
	if (mask & kPluginStates) return dim;
	int end = 0;
	for (const auto& b : coreStateBlocks())
		if (mask & b.bit) end = std::max(end, b.begin + b.size);
	return end;
}

uint32_t blockOfCoordinate(int i, int dim)
{
	if (i < 0 || i >= dim) return 0;
	if (i >= idx::extra) return kPluginStates;
	for (const auto& b : coreStateBlocks())
		if (i >= b.begin && i < b.begin + b.size) return b.bit;
	return 0;
}

TangentVector NavState::euclidean() const
{
	TangentVector t(dim());  // every entry is written below
	t.segment<3>(idx::att).setZero();
	t.segment<3>(idx::gyro_bias) = b_w;
	t.segment<3>(idx::acc) = a_n;
	t[idx::gravity] = g;
	t.segment<3>(idx::acc_bias) = b_a;
	t.segment<3>(idx::vel) = v_n;
	t.segment<3>(idx::pos) = p_n;
	t.segment<2>(idx::current_vehicle) = current_vehicle_ne;
	t.segment<2>(idx::current_far) = current_far_ne;
	t.segment<2>(idx::adcp_bias) = b_adcp;
	put23(t, idx::inertia, M_sub);
	put23(t, idx::damping_lin, Dl_sub);
	put23(t, idx::damping_quad, Dq_sub);
	t.tail(extra.size()) = extra;
	return t;
}

void NavState::setEuclidean(const Eigen::Ref<const TangentVector>& t)
{
	if (t.size() < idx::core_dim || t.size() > idx::max_dim)
		throw std::invalid_argument("NavState::setEuclidean: " + std::to_string(t.size()) + " coordinates");
	b_w = t.segment<3>(idx::gyro_bias);
	a_n = t.segment<3>(idx::acc);
	g = t[idx::gravity];
	b_a = t.segment<3>(idx::acc_bias);
	v_n = t.segment<3>(idx::vel);
	p_n = t.segment<3>(idx::pos);
	current_vehicle_ne = t.segment<2>(idx::current_vehicle);
	current_far_ne = t.segment<2>(idx::current_far);
	b_adcp = t.segment<2>(idx::adcp_bias);
	get23(t, idx::inertia, M_sub);
	get23(t, idx::damping_lin, Dl_sub);
	get23(t, idx::damping_quad, Dq_sub);
	extra = t.tail(t.size() - idx::core_dim);
}

namespace
{
void checkTangentSize(Eigen::Index size, int dim)
{
	if (size != dim)
		throw std::invalid_argument("NavState::boxplus: a " + std::to_string(size) + "-vector on a " +
		                            std::to_string(dim) + "-state");
}
}  // namespace

NavState NavState::boxplus(const Eigen::Ref<const TangentVector>& delta) const
{
	checkTangentSize(delta.size(), dim());
	NavState y;
	// (1·δ is δ bit for bit.)
	if (delta.segment<3>(idx::att).isZero(0))
		boxplusInto<false>(delta, 1.0, nullptr, kAllBlocks, y);
	else
	{
		const Eigen::Matrix3d dR = so3::Exp(delta.segment<3>(idx::att));
		boxplusInto<false>(delta, 1.0, &dR, kAllBlocks, y);
	}
	return y;
}

void NavState::boxplusPair(const Eigen::Ref<const TangentVector>& delta, NavState& plus,
                           NavState& minus) const
{
	boxplusPairBlocks(delta, 1.0, kAllBlocks, plus, minus);
}

void NavState::boxplusPairBlocks(const Eigen::Ref<const TangentVector>& direction, double step,
                                 uint32_t blocks, NavState& plus, NavState& minus) const
{
	checkTangentSize(direction.size(), dim());
	if (&plus == this || &minus == this || &plus == &minus)
		throw std::invalid_argument("NavState::boxplusPair: the pair must be two states other than x");
	if (direction.segment<3>(idx::att).isZero(0))
	{
		boxplusInto<false>(direction, step, nullptr, blocks, plus);
		boxplusInto<true>(direction, step, nullptr, blocks, minus);
		return;
	}
	// Exp(−φ) = Exp(φ)ᵀ, bit for bit as so3::Exp forms them.
	const Eigen::Vector3d phi = step * direction.segment<3>(idx::att);
	const Eigen::Matrix3d dR = so3::Exp(phi);
	const Eigen::Matrix3d dR_back = dR.transpose();
	boxplusInto<false>(direction, step, &dR, blocks, plus);
	boxplusInto<true>(direction, step, &dR_back, blocks, minus);
}

namespace
{
// a + δ, or a − δ for the pair's minus point: a − δ is a + (−δ) bit for bit
// (IEEE subtraction adds the negation), so no negated copy of δ is formed.
// (Scalars or Eigen expressions alike.)
template <bool kMinus, typename A, typename D>
auto plusOrMinus(const A& a, const D& d)
{
	if constexpr (std::is_arithmetic_v<A>)
		return kMinus ? a - d : a + d;
	else if constexpr (kMinus)
		return (a - d).eval();
	else
		return (a + d).eval();
}
template <bool kMinus>
void add23Signed(Eigen::Matrix<double, 2, 3>& out, const Eigen::Matrix<double, 2, 3>& m,
                 const Eigen::Ref<const TangentVector>& dir, double step, int at)
{
	for (int r = 0; r < 2; ++r)
		for (int c = 0; c < 3; ++c) out(r, c) = plusOrMinus<kMinus>(m(r, c), step * dir[at + 3 * r + c]);
}
}  // namespace

template <bool kMinus>
void NavState::boxplusInto(const Eigen::Ref<const TangentVector>& dir, double step,
                           const Eigen::Matrix3d* dR_turn, uint32_t blocks, NavState& y) const
{
	// Member by member (no flat round trip through euclidean(): this runs per
	// sigma point); members of blocks not asked for are left as they are.
	// δ = step·dir entry by entry, as a product formed first would round it
	// (no δ vector is stored); (−δ)'s products are the negated products bit
	// for bit, so the minus point subtracts them.
	auto wants = [blocks](uint32_t bit) { return (blocks & bit) != 0; };
	auto delta3 = [&](int at) { return (step * dir.segment<3>(at)).eval(); };
	auto delta2 = [&](int at) { return (step * dir.segment<2>(at)).eval(); };
	// The additive members.
	if (wants(kGyroBias)) y.b_w = plusOrMinus<kMinus>(b_w, delta3(idx::gyro_bias));
	if (wants(kGravity)) y.g = plusOrMinus<kMinus>(g, step * dir[idx::gravity]);
	if (wants(kPosition)) y.p_n = plusOrMinus<kMinus>(p_n, delta3(idx::pos));
	if (wants(kAdcpBias)) y.b_adcp = plusOrMinus<kMinus>(b_adcp, delta2(idx::adcp_bias));
	if (wants(kInertia)) add23Signed<kMinus>(y.M_sub, M_sub, dir, step, idx::inertia);
	if (wants(kDampingLinear)) add23Signed<kMinus>(y.Dl_sub, Dl_sub, dir, step, idx::damping_lin);
	if (wants(kDampingQuadratic)) add23Signed<kMinus>(y.Dq_sub, Dq_sub, dir, step, idx::damping_quad);
	if (wants(kPluginStates))
	{
		const int e = static_cast<int>(extra.size());
		y.extra.resize(e);
		for (int i = 0; i < e; ++i) y.extra[i] = plusOrMinus<kMinus>(extra[i], step * dir[idx::extra + i]);
	}
	if (!dR_turn)
	{
		// No turn (every sigma point along a Cholesky column past the
		// attitude's): Exp(0) is exactly I, so this is the turned case's
		// result without its rotations.
		y.R_nb = R_nb;
		if (wants(kVelocity)) y.v_n = plusOrMinus<kMinus>(v_n, delta3(idx::vel));
		if (wants(kAcceleration)) y.a_n = plusOrMinus<kMinus>(a_n, delta3(idx::acc));
		if (wants(kCurrentVehicle))
			y.current_vehicle_ne = plusOrMinus<kMinus>(current_vehicle_ne, delta2(idx::current_vehicle));
		if (wants(kCurrentFar))
			y.current_far_ne = plusOrMinus<kMinus>(current_far_ne, delta2(idx::current_far));
		if (wants(kAccelBias))
			y.b_a = plusOrMinus<kMinus>(b_a, (R_nb.transpose() * delta3(idx::acc_bias)).eval());
		return;
	}
	const Eigen::Matrix3d& dR = *dR_turn;
	// The attitude always: the accelerometer bias below reads it.
	y.R_nb = dR * R_nb;
	// Velocity and acceleration turn with the attitude (SE_2(3)-like
	// retraction): a heading perturbation moves the whole body-fixed motion.
	if (wants(kVelocity)) y.v_n = plusOrMinus<kMinus>((dR * v_n).eval(), delta3(idx::vel));
	if (wants(kAcceleration)) y.a_n = plusOrMinus<kMinus>((dR * a_n).eval(), delta3(idx::acc));
	// The water currents too (horizontal part of the turned vector): they are
	// inferred from body-frame measurements just like the velocity.
	if (wants(kCurrentVehicle))
		y.current_vehicle_ne = plusOrMinus<kMinus>(
		    (dR * Eigen::Vector3d(current_vehicle_ne.x(), current_vehicle_ne.y(), 0)).head<2>().eval(),
		    delta2(idx::current_vehicle));
	if (wants(kCurrentFar))
		y.current_far_ne = plusOrMinus<kMinus>(
		    (dR * Eigen::Vector3d(current_far_ne.x(), current_far_ne.y(), 0)).head<2>().eval(),
		    delta2(idx::current_far));
	// The accelerometer bias is stored in IMU axes but perturbed in NED axes.
	if (wants(kAccelBias))
		y.b_a = plusOrMinus<kMinus>(b_a, (y.R_nb.transpose() * delta3(idx::acc_bias)).eval());
}

NavState NavState::boxplusCoordinate(int i, double h) const
{
	if (i < idx::gyro_bias || i >= idx::inertia)
	{
		// A turn, or a parameter / plugin coordinate: the general form.
		TangentVector delta = TangentVector::Zero(dim());
		delta[i] = h;
		return boxplus(delta);
	}
	NavState y = *this;
	auto at = [&](int block) { return i - block; };
	if (i < idx::acc)
		y.b_w[at(idx::gyro_bias)] += h;
	else if (i < idx::gravity)
		y.a_n[at(idx::acc)] += h;
	else if (i == idx::gravity)
		y.g += h;
	else if (i < idx::vel)
		y.b_a += R_nb.row(at(idx::acc_bias)).transpose() * h;  // R_nbᵀ (h e_i), as boxplus
	else if (i < idx::pos)
		y.v_n[at(idx::vel)] += h;
	else if (i < idx::current_vehicle)
		y.p_n[at(idx::pos)] += h;
	else if (i < idx::current_far)
		y.current_vehicle_ne[at(idx::current_vehicle)] += h;
	else if (i < idx::adcp_bias)
		y.current_far_ne[at(idx::current_far)] += h;
	else
		y.b_adcp[at(idx::adcp_bias)] += h;
	return y;
}

TangentVector NavState::boxminus(const NavState& y) const
{
	if (y.dim() != dim())
		throw std::invalid_argument("NavState::boxminus: states of " + std::to_string(dim()) + " and " +
		                            std::to_string(y.dim()) + " coordinates");
	TangentVector d(dim());  // every entry is written below
	d.head<idx::adcp_bias>() = boxminusHead(y);
	d.segment<2>(idx::adcp_bias) = b_adcp - y.b_adcp;
	put23(d, idx::inertia, M_sub - y.M_sub);
	put23(d, idx::damping_lin, Dl_sub - y.Dl_sub);
	put23(d, idx::damping_quad, Dq_sub - y.Dq_sub);
	d.tail(extra.size()) = extra - y.extra;
	return d;
}

Eigen::Matrix<double, idx::adcp_bias, 1> NavState::boxminusHead(const NavState& y) const
{
	Eigen::Matrix<double, idx::adcp_bias, 1> d;
	boxminusHeadInto(y, d);
	return d;
}

void NavState::boxminusHeadInto(const NavState& y, Eigen::Matrix<double, idx::adcp_bias, 1>& d) const
{
	// dR = Exp(Log(·)) is the relative rotation itself: taken as the product
	// (no Exp per call: this runs per sigma point and mean iteration).
	const Eigen::Matrix3d dR = R_nb * y.R_nb.transpose();
	d.segment<3>(idx::att) = so3::Log(dR);
	d.segment<3>(idx::gyro_bias) = b_w - y.b_w;
	d[idx::gravity] = g - y.g;
	d.segment<3>(idx::pos) = p_n - y.p_n;
	d.segment<3>(idx::vel) = v_n - dR * y.v_n;
	d.segment<3>(idx::acc) = a_n - dR * y.a_n;
	d.segment<2>(idx::current_vehicle) =
	    current_vehicle_ne -
	    (dR * Eigen::Vector3d(y.current_vehicle_ne.x(), y.current_vehicle_ne.y(), 0)).head<2>();
	d.segment<2>(idx::current_far) =
	    current_far_ne - (dR * Eigen::Vector3d(y.current_far_ne.x(), y.current_far_ne.y(), 0)).head<2>();
	d.segment<3>(idx::acc_bias) = R_nb * (b_a - y.b_a);
}

bool NavState::allFinite() const
{
	return R_nb.allFinite() && euclidean().allFinite();
}

Eigen::Matrix<double, 2, 3> physicalSub(const Eigen::Matrix<double, 2, 3>& stored)
{
	Eigen::Matrix<double, 2, 3> m = stored;
	m(0, 0) = std::exp(stored(0, 0));
	m(1, 1) = std::exp(stored(1, 1));
	return m;
}

Eigen::Matrix<double, 2, 3> storedSub(const Eigen::Matrix<double, 2, 3>& physical)
{
	Eigen::Matrix<double, 2, 3> m = physical;
	m(0, 0) = std::log(physical(0, 0));
	m(1, 1) = std::log(physical(1, 1));
	return m;
}

std::string StateBlockSpec::problem() const
{
	auto finite = [](double v) { return std::isfinite(v); };
	if (name.empty()) return "a state block without a name";
	if (components.empty()) return "state block '" + name + "' has no components";
	const std::size_t d = components.size();
	if (!mean.empty() && mean.size() != d) return "state block '" + name + "': mean has the wrong size";
	if (sigma.size() != d && sigma.size() != 1) return "state block '" + name + "': sigma has the wrong size";
	for (double v : mean)
		if (!finite(v)) return "state block '" + name + "': non-finite mean";
	for (double v : sigma)
		if (!finite(v) || !(v > 0)) return "state block '" + name + "': initial sigma must be positive";
	if (!finite(process_sigma) || process_sigma < 0)
		return "state block '" + name + "': negative process sigma";
	if (process == StateProcess::GaussMarkov && !(tau_s > 0 && std::isfinite(tau_s)))
		return "state block '" + name + "': Gauss-Markov needs tau_s > 0";
	if (static_cast<int>(process) < 0 || process > StateProcess::RandomWalkPerMetre)
		return "state block '" + name + "': unknown process";
	// Components name the outputs' columns, so two alike would be one column.
	for (std::size_t i = 0; i < d; ++i)
		for (std::size_t j = 0; j < i; ++j)
			if (components[i] == components[j])
				return "state block '" + name + "': component '" + components[i] + "' twice";
	return "";
}

const std::vector<std::string>& tangentNames()
{
	static const std::vector<std::string> names = []
	{
		std::vector<std::string> n;
		auto add3 = [&](const std::string& b, const char* a, const char* c, const char* d)
		{
			n.push_back(b + a);
			n.push_back(b + c);
			n.push_back(b + d);
		};
		add3("att_", "n", "e", "d");
		add3("gyro_bias_", "x", "y", "z");
		add3("acc_", "n", "e", "d");
		n.push_back("gravity");
		add3("acc_bias_", "n", "e", "d");  // tangent in NED axes (state.h)
		add3("vel_", "n", "e", "d");
		add3("pos_", "n", "e", "d");
		n.push_back("current_n");
		n.push_back("current_e");
		n.push_back("current_far_n");
		n.push_back("current_far_e");
		n.push_back("adcp_bias_x");
		n.push_back("adcp_bias_y");
		// Diagonal entries are stored as logarithms (see state.h).
		for (const char* m : {"M", "Dl", "Dq"})
			for (const char* rc : {"ln_xx", "xy", "xpsi", "yx", "ln_yy", "ypsi"})
				n.push_back(std::string(m) + "_" + rc);
		return n;
	}();
	return names;
}

const std::vector<std::string>& storedNames()
{
	static const std::vector<std::string> names = []
	{
		std::vector<std::string> n = tangentNames();
		n[idx::acc_bias] = "acc_bias_x";
		n[idx::acc_bias + 1] = "acc_bias_y";
		n[idx::acc_bias + 2] = "acc_bias_z";
		return n;
	}();
	return names;
}

}  // namespace auvnav
