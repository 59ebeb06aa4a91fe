// Properties every group shares, run as one typed suite over SO3d, SE3d, RxSO3d and Sim3d:
// exp agrees with the matrix exponential of hat, exp/log invert each other on the principal range,
// hat/vee invert each other, group axioms, the action agrees with matrix(), the adjoint satisfies
// paper eq. 26, and the left/right Jacobians and the action Jacobian agree with numeric differences.
#include <gtest/gtest.h>

#include <unsupported/Eigen/MatrixFunctions>

#include "framework/lie/lie_test_util.h"
#include "rsvio/lie/lie.h"
#include "support/numeric_jacobian.h"

namespace rsvio {
namespace {

using lie_test::kPi;
using lie_test::Rng;

// Where each part sits in a group's tangent (-1: absent).
template <class G>
struct Layout;
template <>
struct Layout<SO3d> {
  static constexpr int trans = -1, rot = 0, sigma = -1;
  static constexpr bool has_jacobians = true;
};
template <>
struct Layout<SE3d> {
  static constexpr int trans = 0, rot = 3, sigma = -1;
  static constexpr bool has_jacobians = true;
};
template <>
struct Layout<RxSO3d> {
  static constexpr int trans = -1, rot = 0, sigma = 3;
  static constexpr bool has_jacobians = true;
};
template <>
struct Layout<Sim3d> {
  static constexpr int trans = 0, rot = 3, sigma = 6;
  static constexpr bool has_jacobians = false;  // Sim3's exp Jacobians are not needed (yet)
};

template <class G>
typename G::Tangent makeTangent(const Eigen::Vector3d& upsilon, const Eigen::Vector3d& omega, double sigma) {
  using L = Layout<G>;
  typename G::Tangent x;
  if constexpr (L::trans >= 0) x.template segment<3>(L::trans) = upsilon;
  x.template segment<3>(L::rot) = omega;
  if constexpr (L::sigma >= 0) x[L::sigma] = sigma;
  return x;
}

template <class G>
double rotationAngle(const typename G::Tangent& x) {
  return x.template segment<3>(Layout<G>::rot).norm();
}

template <class G>
typename G::Tangent randomTangent(Rng& rng, double max_angle = kPi) {
  return makeTangent<G>(lie_test::randomVector(rng, 10.0), lie_test::randomRotationVector(rng, max_angle),
                        lie_test::uniform(rng, -3.0, 3.0));
}

// Edge rotations x a few translations x edge scales (0 log-scale, tiny, around the Sim3 series switch
// at |(theta, sigma)| = 1, scales 1e-11 and 1e11).
template <class G>
std::vector<typename G::Tangent> edgeTangents() {
  std::vector<typename G::Tangent> out;
  const std::vector<double> sigmas =
      Layout<G>::sigma >= 0 ? std::vector<double>{0.0, 1e-15, -1e-9, 1e-6, 0.5, -1.0 + 1e-12, 1.0 + 1e-12, -2.0, -25.0, 25.0}
                            : std::vector<double>{0.0};
  const std::vector<Eigen::Vector3d> ups = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1e-9, 0, 0),
                                            Eigen::Vector3d(0.3, -2.0, 7.0)};
  for (const Eigen::Vector3d& w : lie_test::edgeRotationVectors())
    for (double s : sigmas)
      for (const auto& u : ups) {
        out.push_back(makeTangent<G>(u, w, s));
        if (Layout<G>::trans < 0) break;
      }
  return out;
}

// Apply a group's matrix to a point: 3x3 groups directly, 4x4 homogeneously.
template <class M>
Eigen::Vector3d applyMatrix(const M& m, const Eigen::Vector3d& p) {
  if constexpr (M::RowsAtCompileTime == 3) {
    return m * p;
  } else {
    return m.template topLeftCorner<3, 3>() * p + m.template topRightCorner<3, 1>();
  }
}

double relErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

template <class G>
class GroupProperties : public ::testing::Test {};
using Groups = ::testing::Types<SO3d, SE3d, RxSO3d, Sim3d>;
TYPED_TEST_SUITE(GroupProperties, Groups);

TYPED_TEST(GroupProperties, ExpIsMatrixExponentialOfHat) {
  using G = TypeParam;
  Rng rng(100);
  std::vector<typename G::Tangent> xs = edgeTangents<G>();
  for (int i = 0; i < lie_test::kSamples; ++i) xs.push_back(randomTangent<G>(rng));
  for (const auto& x : xs) {
    const Eigen::MatrixXd expm = G::hat(x).exp();
    ASSERT_LT(relErr(G::exp(x).matrix(), expm), 1e-13) << x.transpose();
  }
}

TYPED_TEST(GroupProperties, LogInvertsExp) {
  using G = TypeParam;
  Rng rng(101);
  std::vector<typename G::Tangent> xs = edgeTangents<G>();
  for (int i = 0; i < lie_test::kSamples; ++i) xs.push_back(randomTangent<G>(rng));
  for (const auto& x : xs) {
    const G T = G::exp(x);
    const typename G::Tangent l = T.log();
    ASSERT_TRUE(l.allFinite()) << x.transpose();
    ASSERT_TRUE(G::exp(l).isApprox(T, 1e-12)) << x.transpose();
    if (rotationAngle<G>(x) < kPi) {  // at exactly pi the axis sign is free
      ASSERT_LT((l - x).norm(), 1e-12 * std::max(1.0, x.norm())) << x.transpose() << "\n" << l.transpose();
    }
  }
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const G T = G::sampleUniform(rng);
    ASSERT_TRUE(G::exp(T.log()).isApprox(T, 1e-13));
    ASSERT_LE(rotationAngle<G>(T.log()), kPi + 1e-15);
  }
}

TYPED_TEST(GroupProperties, HatVee) {
  using G = TypeParam;
  Rng rng(102);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const typename G::Tangent x = randomTangent<G>(rng);
    ASSERT_LT((G::vee(G::hat(x)) - x).norm(), 1e-14 * x.norm());
  }
}

TYPED_TEST(GroupProperties, GroupAxiomsAndAction) {
  using G = TypeParam;
  Rng rng(103);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const G A = G::exp(randomTangent<G>(rng)), B = G::exp(randomTangent<G>(rng)), C = G::sampleUniform(rng);
    const Eigen::Vector3d p = lie_test::randomVector(rng, 10.0);
    ASSERT_TRUE((A.inverse() * A).isApprox(G::Identity(), 1e-12));
    ASSERT_TRUE((A * A.inverse()).isApprox(G(), 1e-12));
    ASSERT_TRUE(((A * B) * C).isApprox(A * (B * C), 1e-12));
    ASSERT_LT(relErr((A * B).matrix(), A.matrix() * B.matrix()), 1e-13);
    ASSERT_LT(relErr(A.inverse().matrix(), A.matrix().inverse()), 1e-12);
    ASSERT_LT((A * p - applyMatrix(A.matrix(), p)).norm(), 1e-12 * std::max(1.0, (A * p).norm()));
    ASSERT_LT((A.inverse() * (A * p) - p).norm(), 1e-12 * std::max(1.0, p.norm()));
    ASSERT_LT(relErr(A.rotationMatrix(), A.unit_quaternion().toRotationMatrix()), 1e-15);
    ASSERT_TRUE(A.template cast<float>().template cast<double>().isApprox(A, 1e-5));
  }
}

TYPED_TEST(GroupProperties, AdjointPropertyEq26) {  // T exp(d) = exp(Adj(T) d) T
  using G = TypeParam;
  Rng rng(104);
  for (int i = 0; i < lie_test::kSamples; ++i) {
    const G T = G::exp(randomTangent<G>(rng));
    const typename G::Tangent d = randomTangent<G>(rng, 1.0) * 0.1;
    ASSERT_TRUE((T * G::exp(d)).isApprox(G::exp(T.Adj() * d) * T, 1e-11));
    // Infinitesimal form: hat(Adj d) = T hat(d) T^-1.
    const Eigen::MatrixXd lhs = G::hat(T.Adj() * d);
    ASSERT_LT(relErr(lhs, T.matrix() * G::hat(d) * T.inverse().matrix()), 1e-12);
    // Adj is a homomorphism.
    const G S = G::sampleUniform(rng);
    ASSERT_LT(relErr((T * S).Adj(), T.Adj() * S.Adj()), 1e-12);
  }
}

TYPED_TEST(GroupProperties, ActionJacobianLeftPerturbation) {
  using G = TypeParam;
  Rng rng(105);
  for (int i = 0; i < lie_test::kJacobianSamples; ++i) {
    const G T = G::exp(randomTangent<G>(rng));
    const Eigen::Vector3d p = lie_test::randomVector(rng, 10.0);
    const auto act = [&p](const G& X) { return Eigen::Vector3d(X * p); };
    EXPECT_JACOBIAN_NEAR(T.dActionDLeft(p), test::numericJacobian(act, T, test::leftPlus<G>, G::DoF), 1e-7);
  }
}

TYPED_TEST(GroupProperties, LeftAndRightJacobians) {
  using G = TypeParam;
  if constexpr (Layout<G>::has_jacobians) {
    Rng rng(106);
    std::vector<typename G::Tangent> xs = edgeTangents<G>();
    for (int i = 0; i < lie_test::kJacobianSamples; ++i) xs.push_back(randomTangent<G>(rng));
    const auto exp = [](const typename G::Tangent& x) { return G::exp(x); };
    const auto log = [](const G& X) { return X.log(); };
    const int n = G::DoF;
    for (const auto& x : xs) {
      // exp(x + d) = exp(Jl d) exp(x) = exp(x) exp(Jr d).
      EXPECT_JACOBIAN_NEAR(G::leftJacobian(x),
                           test::numericJacobian(exp, x, test::vectorPlus, test::leftMinus<G>, n), 1e-7);
      EXPECT_JACOBIAN_NEAR(G::rightJacobian(x),
                           test::numericJacobian(exp, x, test::vectorPlus, test::rightMinus<G>, n), 1e-7);
      const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
      EXPECT_LT(relErr(G::leftJacobian(x) * G::leftJacobianInverse(x), I), 1e-12);
      EXPECT_LT(relErr(G::rightJacobian(x) * G::rightJacobianInverse(x), I), 1e-12);
      // log(exp(d) T) = log T + Jl^-1 d, log(T exp(d)) = log T + Jr^-1 d; not across the cut at pi.
      if (rotationAngle<G>(x) < kPi - 1e-3) {
        const G T = G::exp(x);
        EXPECT_JACOBIAN_NEAR(G::leftJacobianInverse(x), test::numericJacobian(log, T, test::leftPlus<G>, n), 1e-6);
        EXPECT_JACOBIAN_NEAR(G::rightJacobianInverse(x), test::numericJacobian(log, T, test::rightPlus<G>, n), 1e-6);
      }
    }
  }
}

}  // namespace
}  // namespace rsvio
