#pragma once
/** @file state.h
 *  The navigation filter's state: the 43-dimensional state of Arnold &
 *  Medagoda (2018, Table I), as named members with frame suffixes, and its
 *  manifold operations.
 *
 *  Tangent-space layout (fixed; `idx::`): the blocks are ordered so that the
 *  inertial states (whose prediction is nonlinear under the retraction below)
 *  come first, the high-rate accelerometer update's within the first 13. The
 *  filter exploits this order (see ukf.h), so it is part of the plugin ABI.
 *
 *    0  attitude error δθ_n (3)        left perturbation, see so3.h
 *    3  gyro bias b_w (3)              [rad/s], IMU axes
 *    6  acceleration a_n (3)           [m/s²] of the IMU point, NED
 *    9  gravity g (1)                  [m/s²], magnitude, down
 *   10  accelerometer bias b_a (3)     [m/s²], stored in IMU axes, perturbed
 *                                      in NED axes: b_a ⊞ δ = b_a + R_nbᵀ δ
 *   13  velocity v_n (3)               [m/s] of the IMU point, NED
 *   16  position p_n (3)               [m] of the IMU point, NED tangent frame
 *   19  water current at the vehicle (2)     [m/s] N, E
 *   21  water current at the ADCP far range (2) [m/s] N, E
 *   23  ADCP bias (2)                  [m/s], ADCP x, y axes
 *   25  inertia sub-matrix M_sub (2x3)        rows x,y; columns x,y,ψ; row-major
 *   31  linear damping sub-matrix D_l,sub (2x3)
 *   37  quadratic damping sub-matrix D_q,sub (2x3)
 *
 *  43… plugin-owned states (plugin SDK v2): blocks a sensor plugin declares
 *     (MeasurementModel::states), appended in the order of the
 *     navigator's `sensors:` list, at most idx::max_extra coordinates in
 *     all; Euclidean, additive, in NavState::extra.
 *
 *  Model parameters: the diagonal entries of each sub-matrix (xx and yy) are
 *  stored as natural logarithms, so that the physical values, exp(·), stay
 *  positive under any update without a non-smooth abs(); the off-diagonal
 *  couplings (xy, xψ, yx, yψ) are stored as they are. Use physicalSub() to
 *  read them in SI units.
 */
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

//! Room for plugin-owned states (part of the plugin build fingerprint).
#define AUVNAV_MAX_EXTRA_STATES 21

namespace auvnav
{
namespace idx
{
constexpr int att = 0, gyro_bias = 3, acc = 6, gravity = 9, acc_bias = 10, vel = 13, pos = 16,
              current_vehicle = 19, current_far = 21, adcp_bias = 23, inertia = 25, damping_lin = 31,
              damping_quad = 37;
constexpr int core_dim = 43;                        //!< the paper's state (Table I)
constexpr int extra = core_dim;                     //!< first plugin-owned coordinate
constexpr int max_extra = AUVNAV_MAX_EXTRA_STATES;  //!< room for plugin-owned states
constexpr int max_dim = core_dim + max_extra;
}  // namespace idx

/** One bit per state block, for a measurement model to declare what h reads. */
enum StateBlock : uint32_t
{
	kAttitude = 1u << 0,
	kGyroBias = 1u << 1,
	kAcceleration = 1u << 2,
	kGravity = 1u << 3,
	kAccelBias = 1u << 4,
	kVelocity = 1u << 5,
	kPosition = 1u << 6,
	kCurrentVehicle = 1u << 7,
	kCurrentFar = 1u << 8,
	kAdcpBias = 1u << 9,
	kInertia = 1u << 10,
	kDampingLinear = 1u << 11,
	kDampingQuadratic = 1u << 12,
	//! Plugin-owned states (any of them: they come after the paper's 43, so a
	//! model reading them spans the whole state in the filter's update).
	kPluginStates = 1u << 13,
	kAllBlocks = (1u << 14) - 1
};

/** One of the paper's 13 state blocks: its StateBlock bit, its tangent
 *  coordinates [begin, begin + size), its name in messages ("attitude") and
 *  the prefix of its coordinates' names ("att", as in tangentNames() and the
 *  keys of filter.sigma_limits). */
struct StateBlockInfo
{
	uint32_t bit;
	int begin, size;
	const char* name;
	const char* prefix;
};
/** The paper's 13 blocks, in tangent order. */
const std::array<StateBlockInfo, 13>& coreStateBlocks();

/** Number of leading tangent coordinates that cover every block in `mask`,
 *  for a state of `dim` coordinates (kPluginStates covers all of them). */
int tangentPrefix(uint32_t mask, int dim = idx::core_dim);
/** The block (a StateBlock bit) tangent coordinate `i` belongs to
 *  (kPluginStates from idx::extra on; 0 outside the state). */
uint32_t blockOfCoordinate(int i, int dim = idx::core_dim);

//! Tangent vectors and covariances have the state's run-time dimension
//! (43 + plugin states) with fixed storage, so they never touch the heap.
using TangentVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, idx::max_dim, 1>;
using Covariance = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, idx::max_dim, idx::max_dim>;
using ExtraVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, idx::max_extra, 1>;

struct NavState
{
	Eigen::Matrix3d R_nb = Eigen::Matrix3d::Identity();            //!< IMU (= body axes) to NED
	Eigen::Vector3d b_w = Eigen::Vector3d::Zero();                 //!< gyro bias [rad/s]
	Eigen::Vector3d a_n = Eigen::Vector3d::Zero();                 //!< IMU acceleration [m/s²]
	double g = 9.78;                                               //!< gravity magnitude [m/s²]
	Eigen::Vector3d b_a = Eigen::Vector3d::Zero();                 //!< accelerometer bias [m/s²]
	Eigen::Vector3d v_n = Eigen::Vector3d::Zero();                 //!< IMU velocity [m/s]
	Eigen::Vector3d p_n = Eigen::Vector3d::Zero();                 //!< IMU position [m]
	Eigen::Vector2d current_vehicle_ne = Eigen::Vector2d::Zero();  //!< water current around the vehicle
	Eigen::Vector2d current_far_ne = Eigen::Vector2d::Zero();      //!< water current at ADCP far range
	Eigen::Vector2d b_adcp = Eigen::Vector2d::Zero();              //!< ADCP bias, sensor x/y
	Eigen::Matrix<double, 2, 3> M_sub = Eigen::Matrix<double, 2, 3>::Zero();
	Eigen::Matrix<double, 2, 3> Dl_sub = Eigen::Matrix<double, 2, 3>::Zero();
	Eigen::Matrix<double, 2, 3> Dq_sub = Eigen::Matrix<double, 2, 3>::Zero();
	ExtraVector extra;  //!< plugin-owned states (tangent 43…), empty by default

	/** Tangent dimension: 43 + extra.size(). */
	int dim() const { return idx::core_dim + static_cast<int>(extra.size()); }

	/** x ⊞ δ: R ← Exp(δ_att)·R; velocity and acceleration rotate with it,
	 *  v ← Exp(δ_att)·v + δ_v, a ← Exp(δ_att)·a + δ_a (as in invariant filters
	 *  on SE_2(3)), and so do the two water currents (horizontal part of the
	 *  turned vector); everything else additive. Rotating these nav-frame
	 *  vectors keeps a large heading uncertainty from turning body-frame
	 *  measurements (DVL, accelerometer, model aiding, ADCP) into spurious
	 *  heading information. The accelerometer bias, a body-fixed vector, is
	 *  perturbed in NED axes (b_a ← b_a + R_newᵀ δ_ba): tilt and bias are
	 *  told apart only by turning the body, and with IMU-axis coordinates a
	 *  changing heading estimate looked like such a turn, so roll and bias
	 *  separated spuriously while the heading converged. */
	NavState boxplus(const Eigen::Ref<const TangentVector>& delta) const;
	/** x ⊞ δ into `plus` and x ⊞ (−δ) into `minus` (a sigma-point pair),
	 *  the same values bit for bit as two boxplus calls, with one Exp for
	 *  both turns and no new states: every member of both is overwritten.
	 *  plus and minus are two states other than x (std::invalid_argument
	 *  otherwise, as for a δ of the wrong size). */
	void boxplusPair(const Eigen::Ref<const TangentVector>& delta, NavState& plus, NavState& minus) const;
	/** boxplusPair of δ = step·direction (each entry that product, as a δ
	 *  formed first would hold it) for the members of `blocks` (StateBlock
	 *  bits) and the attitude only: those are the values boxplusPair writes,
	 *  bit for bit; every other member of plus and minus is left as it is.
	 *  For sigma points fed to an h that reads only `blocks` (its uses()),
	 *  with plus and minus set to x beforehand so that the rest holds x's
	 *  values; no δ vector is formed. */
	void boxplusPairBlocks(const Eigen::Ref<const TangentVector>& direction, double step, uint32_t blocks,
	                       NavState& plus, NavState& minus) const;
	/** x ⊞ h·e_i, one tangent coordinate moved: the same state as boxplus of
	 *  that vector, without forming it or touching the other members
	 *  (affine slopes by differences, ukf.cpp). */
	NavState boxplusCoordinate(int i, double h) const;
	/** x ⊟ y: the tangent vector δ with y ⊞ δ = x. Both states have the
	 *  same dimension (std::invalid_argument otherwise, as for ⊞). */
	TangentVector boxminus(const NavState& y) const;
	/** The first idx::adcp_bias coordinates of x ⊟ y (attitude … the two
	 *  currents, the inertial block the prediction's mean iterates over),
	 *  bit for bit those of boxminus, without the parameters' and plugin
	 *  states' differences. */
	Eigen::Matrix<double, idx::adcp_bias, 1> boxminusHead(const NavState& y) const;
	/** The same into d (no vector returned and copied: the prediction's
	 *  mean iteration writes its deviations in place). */
	void boxminusHeadInto(const NavState& y, Eigen::Matrix<double, idx::adcp_bias, 1>& d) const;

	/** Flat copy of the Euclidean part (everything but the attitude), in
	 *  tangent order (entries 0..2 are zero), dim() entries. */
	TangentVector euclidean() const;
	/** Sets everything but the attitude; t.size() − 43 plugin states. */
	void setEuclidean(const Eigen::Ref<const TangentVector>& t);

	bool allFinite() const;

 private:
	/** x ⊞ δ (kMinus: x ⊞ (−δ)), δ = step·dir, into y for the members of
	 *  `blocks` and the attitude, the turn's Exp(±δ_att) given (nullptr:
	 *  δ_att is 0). */
	template <bool kMinus>
	void boxplusInto(const Eigen::Ref<const TangentVector>& dir, double step, const Eigen::Matrix3d* dR,
	                 uint32_t blocks, NavState& y) const;
};

/** How a plugin-owned state evolves between updates (exact for any dt). */
enum class StateProcess
{
	RandomConstant,  //!< x' = x, no process noise (a fixed unknown: a mounting angle)
	RandomWalk,      //!< x' = x + w, Var w = process_sigma² · dt  (σ per √s)
	GaussMarkov,     //!< x' = μ + φ (x − μ), φ = e^{−dt/τ}, Var = process_sigma² (1 − φ²)
	//! x' = x + w, Var w = process_sigma² · d (σ per √m), d the distance the
	//! vehicle moved through the water over the step (3-D: the horizontal
	//! speed through water the core's current noise uses, and the vertical
	//! speed; ProcessModel::addNoiseCovariance): an error that changes with
	//! where the vehicle is, not with time (it holds still while hovering).
	RandomWalkPerMetre
};

/** A block of states a plugin owns (plugin SDK v2, plugin_state.h):
 *  declared by the plugin, checked and appended by the host after the
 *  paper's 43 and named "<sensor label>.<name>_<component>" in outputs. */
struct StateBlockSpec
{
	std::string name;                     //!< e.g. "dvl_scale"
	std::vector<std::string> components;  //!< one name per coordinate (dimension); "" for a scalar
	std::vector<double> mean;             //!< initial value and Gauss–Markov mean; empty: zeros
	std::vector<double> sigma;            //!< initial σ per coordinate (> 0), or one for all
	StateProcess process = StateProcess::RandomConstant;
	//! RandomWalk: σ per √s; RandomWalkPerMetre: σ per √m; GaussMarkov: stationary σ
	double process_sigma = 0;
	double tau_s = 0;  //!< GaussMarkov correlation time [s]

	int dimension() const { return static_cast<int>(components.size()); }
	/** Empty if usable, else what is wrong (for the host's refusal message). */
	std::string problem() const;
};

/** A parameter sub-matrix in SI units from its stored form (exp of the
 *  diagonal entries (0,0) and (1,1)), and back. */
Eigen::Matrix<double, 2, 3> physicalSub(const Eigen::Matrix<double, 2, 3>& stored);
Eigen::Matrix<double, 2, 3> storedSub(const Eigen::Matrix<double, 2, 3>& physical);

/** Names of the paper's 43 tangent coordinates, for CSV headers ("att_n",
 *  "vel_e", …); the navigator appends its plugin states' names. */
const std::vector<std::string>& tangentNames();
/** Names of euclidean()'s entries (the stored values): tangentNames() except
 *  the accelerometer bias, stored in IMU axes ("acc_bias_x" …) but perturbed
 *  in NED axes ("acc_bias_n" …). */
const std::vector<std::string>& storedNames();

}  // namespace auvnav
