// Sensitivities of the quasi-static solution (model.md §7.8): derivatives of
// the twist, joint rates, contact forces and multipliers with respect to the
// configuration state Theta, mu, epsilon and the commanded joint rates, by
// the implicit function theorem on the KKT system at a returned solution.
//
// KKT conditions of the NLP (nlp.h, Ipopt's sign convention L = f + l^T g)
// on the active set A (equality rows, plus the inequality sides and bounds
// that are active):
//   F(z, l_A; p) = [grad_z f + J_A^T l_A; c_A] = 0
//   [H  J_A^T] [dz/dp  ]     [d(grad_z L)/dp]
//   [J_A  0  ] [dl_A/dp] = - [dc_A/dp       ],   H = d2L/dz2.
// The quasi-static equality system is square and regular at a solution
// (model.md §7.3), and C implies I2 strictly for eps > 0, so at a regular
// point A = the equality rows E, J_E is square and the block system
// decouples (block elimination, the same solution):
//   J_E dz/dp = -dc_E/dp,
//   J_E^T dl_E/dp = -(d(grad_z L)/dp + H dz/dp) = -D_t grad_z L,
// D_t the derivative along the solution's tangent (z + t dz/dp, p + t e_p).
// Outputs y(z; p) (twist, joint rates, world forces) then follow by
// dy/dp = (dy/dz) dz/dp + dy/dp|_z, dy/dz exact (y is affine in z).
//
// Derivatives the problem does not provide (method "ift-kkt+central-fd"):
//  - dc/dp at fixed z, split into two channels so that no difference is
//    taken across the creep scale sigma ~ eps of the friction law:
//      dc/dp = (dg/dvel)(dvel/dp) + dc/dp|_vel,
//    dg/dvel exact (QuasiStaticProblem::ConstraintVelocityJacobian), the
//    contact velocities' dvel/dp (smooth in Theta, linear in the rates) and
//    dc/dp at fixed velocities (statics in Theta, mu, eps) by central
//    differences with h_k = cbrt(eps_mach) s_k (s_k = 1 for Theta, |mu|,
//    eps, max(1, |rate|)): truncation h^2 f'''/6 and round-off eps_mach f/h
//    balance at h ~ cbrt(eps_mach) times the scale on which f varies, both
//    ~eps_mach^(2/3) ~ 4e-11 relative;
//  - D_t grad_z L by central differences along the tangent at t = h_k and
//    t/2, Richardson-extrapolated (truncation O(t^4)): along the tangent
//    the slips move smoothly; the multipliers of the friction rows scale
//    like 1/sigma and the paper-mode path curves on a scale ~1e-4 in p, so
//    one plain difference left ~1e-5 (measured, docs/model.md §7.8).
//    The multipliers themselves solve J_E^T l_E = -grad f.
//  - dy/dp|_z by central differences with h_k (smooth: rotations in Theta).
//
// Active set (tolerances in SensitivityOptions): an inequality side or bound
// with slack <= activity_tolerance is active or about to become active; with
// the square E it cannot join A regularly (LICQ fails), so the derivatives
// returned are those of the branch on which it stays inactive (a one-sided
// derivative): `one_sided` is set and the constraint named, never a silently
// two-sided value. An inequality with slack > activity_tolerance has zero
// multiplier (inactive). A singular J_E (reciprocal condition estimate at or
// below singular_rcond) gives status kSingular.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/core/quasi_static.h"

namespace quasiroll {

// Parameter columns: Theta (21, model.md §2), mu, epsilon, the six
// commanded joint rates (phi1, alpha1, delta2, alpha2, delta3, alpha3).
struct SensitivityParameter {
  static constexpr int kState = 0;
  static constexpr int kNumState = 21;
  static constexpr int kMu = 21;
  static constexpr int kEpsilon = 22;
  static constexpr int kRates = 23;
  static constexpr int kCount = 29;
};

// Names of Theta's coordinates in order: u_w1, v_w1, x_g1, y_g1, psi1, ...,
// psi3, phi1, alpha1, delta2, alpha2, delta3, alpha3.
const std::array<const char*, 21>& StateNames();
// Names of the joint rates in order: phi1, alpha1, ..., alpha3.
const std::array<const char*, 6>& JointNames();

enum class SensitivityStatus {
  kOk,
  kSingular,   // J_E singular: no derivative exists
  kNotSquare,  // #equalities != #unknowns: not the quasi-static problem
  kNotComputed,
};
const char* ToString(SensitivityStatus status);  // "OK", "SINGULAR", ...

struct SensitivityOptions {
  // Scaled slack at or below which an inequality side or bound counts as
  // active or about to become active (one-sided): 100 x the solve's
  // residual tolerance (1e-12), i.e. a slack the solve itself resolves.
  double activity_tolerance = 1e-10;
  // J_E counts as singular at or below this reciprocal condition estimate
  // (min of Eigen's 1-norm estimate and the smallest / largest LU pivot).
  double singular_rcond = 1e-14;
  // Also the multipliers' derivatives (4 more evaluations of the Lagrangian
  // gradient per parameter); off: `multipliers` is NaN, the rest unchanged.
  bool multipliers = true;
  bool IsValid(std::string* why) const;
};

struct QuasiStaticSensitivities {
  using ParamMatrix6 = Eigen::Matrix<double, 6, SensitivityParameter::kCount>;
  using ParamMatrix9 = Eigen::Matrix<double, 9, SensitivityParameter::kCount>;
  using MultiplierMatrix =
      Eigen::Matrix<double, Eigen::Dynamic, SensitivityParameter::kCount, 0,
                    QuasiStaticProblem::kMaxRows, SensitivityParameter::kCount>;
  using MultiplierVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0,
                                         QuasiStaticProblem::kMaxRows, 1>;

  SensitivityStatus status = SensitivityStatus::kNotComputed;
  static constexpr const char* kMethod = "ift-kkt+central-fd";
  // d/dp, columns as SensitivityParameter.
  ParamMatrix6 twist = ParamMatrix6::Zero();        // V^B = (v^B, omega^B)
  ParamMatrix6 joint_rates = ParamMatrix6::Zero();  // all six rates
  ParamMatrix9 forces = ParamMatrix9::Zero();       // F_1, F_2, F_3 (world)
  MultiplierMatrix multipliers;        // constraint multipliers (rows of g)
  MultiplierVector multiplier_values;  // the multipliers at the solution
  // Constraints that make the derivative one-sided: inequality rows of g
  // (row index) and lower bounds of z (num_constraints + variable index).
  bool one_sided = false;
  std::array<int, QuasiStaticProblem::kMaxRows> one_sided_items{};
  int num_one_sided = 0;
  int num_constraints = 0, num_motion = 0;  // of the problem (for names)
  double min_inequality_slack = 0.0;  // smallest scaled slack (inf if none)
  double rcond = 0.0;                 // reciprocal condition estimate of J_E
};

// Human-readable name of a one-sided item (QuasiStaticSensitivities), e.g.
// "I2 wheel 2 (friction cone)" or "I1 wheel 1 (f_n >= 0)".
std::string OneSidedName(const QuasiStaticSensitivities& sens, int item);

// The front ends' view (docs/cli.md, `solve --sensitivities`): entries
// d<output>_d<input>, outputs twist (6), joint_rates (6), forces (9: F_1,
// F_2, F_3 world x y z), multipliers (rows of g); inputs state (21 columns,
// StateNames()), mu and eps (vectors), rates (6 columns, JointNames()).
struct SensitivityEntry {
  std::string name;
  Eigen::MatrixXd value;  // rows: output, columns: input
  bool vector = false;    // a single input: one column, shown as a vector
};
std::vector<SensitivityEntry> SensitivityEntries(
    const QuasiStaticSensitivities& sens);

// Sets parameter k (SensitivityParameter) to nominal + delta: a Theta
// coordinate in *theta (the configuration to set the problem up at), mu,
// epsilon or a commanded rate on *problem; the other parameters of *problem
// are reset to nominal.
void PerturbParameter(const QuasiStaticParameters& nominal, int k, double delta,
                      QuasiStaticProblem* problem, Configuration* theta);

// Computes sensitivities with preallocated workspaces: after the first call
// for a given mode, Compute() does not allocate (one_sided names aside).
class SensitivityAnalyzer {
 public:
  explicit SensitivityAnalyzer(const SensitivityOptions& options = {});

  // `problem` is the problem the solution was computed for (its
  // configuration and parameters), `z` its scaled solution. Throws
  // std::invalid_argument for z of the wrong size or non-finite.
  SensitivityStatus Compute(const QuasiStaticProblem& problem,
                            const Eigen::Ref<const Eigen::VectorXd>& z,
                            QuasiStaticSensitivities* out);

 private:
  using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0,
                            QuasiStaticProblem::kMaxRows, 1>;
  using Mat =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0,
                    QuasiStaticProblem::kMaxRows, QuasiStaticProblem::kMaxRows>;
  using Outputs = Eigen::Matrix<double, 21, 1>;

  bool FindActiveSet(const QuasiStaticProblem& problem,
                     QuasiStaticSensitivities* out);
  // Sets parameter k of work_ to its nominal value + delta (the others
  // nominal, except Theta between state columns: Restore()).
  void SetParameter(int k, double delta);
  void Restore(int k);
  double Scale(int k) const;
  // dc/dp_k at fixed z (both channels, header) and dy/dp_k|_z.
  void ParameterDerivatives(int k, Vec* dc, Outputs* dy);
  // D_t grad_z L: central difference along (z + t dz, p_k + t).
  void TangentDifference(int k, const Vec& dz, double t, Vec* d);
  // grad_z L at (z, lambda) on work_.
  void LagrangianGradient(const Eigen::Ref<const Eigen::VectorXd>& z,
                          Eigen::Ref<Eigen::VectorXd> grad);
  Outputs OutputsAt(const Eigen::Ref<const Eigen::VectorXd>& z) const;

  SensitivityOptions options_;
  std::optional<QuasiStaticProblem> work_;
  QuasiStaticParameters nominal_;
  Configuration theta_ = Configuration::Zero();
  Eigen::VectorXd z_, zt_, g_, grad_, lambda_, x_lb_, x_ub_, g_lb_, g_ub_;
  Eigen::MatrixXd jac_, dg_dvel_;
  Eigen::Matrix<double, 9, 1> vel0_;    // contact velocities at the solution
  Eigen::PartialPivLU<Mat> lu_, lu_t_;  // J_E and J_E^T
  Mat jac_eq_;
  Eigen::Matrix<double, 21, Eigen::Dynamic, 0, 21, QuasiStaticProblem::kMaxRows>
      dy_dz_;
};

}  // namespace quasiroll
