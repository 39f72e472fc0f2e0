// The robot's loop closure as the constraint part of a ConstrainedOde
// (core/dae.h): H(Theta) = 0 (model.md §3), J = dH/dTheta and the
// correction weights D from the kinematic model. The right-hand side is
// the derived class's: the simulator's (zoh or coupled), the step
// derivative's field, or none where only the manifold is used.
#pragma once

#include <Eigen/Core>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/kinematics.h"

namespace quasiroll {

class LoopClosureOde : public ConstrainedOde {
 public:
  explicit LoopClosureOde(const KinematicModel& model)
      : model_(model), weights_(model.CorrectionWeights()) {}

  int state_size() const override { return kConfigSize; }
  int num_constraints() const override { return kNumConstraints; }

  // No field by default (a manifold-only use, e.g. WeightedProjection).
  bool Rhs(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
           Eigen::Ref<Eigen::VectorXd> /*ydot*/) override {
    return false;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    LoopClosure hh;
    model_.Constraints(y, &hh);
    h = hh;
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override {
    LoopClosureJacobian j;
    model_.ConstraintJacobian(y, &j);
    jac = j;
  }
  void CorrectionWeights(Eigen::Ref<Eigen::VectorXd> d) const override {
    d = weights_;
  }

 protected:
  const KinematicModel& model() const { return model_; }

 private:
  const KinematicModel& model_;
  Configuration weights_;
};

}  // namespace quasiroll
