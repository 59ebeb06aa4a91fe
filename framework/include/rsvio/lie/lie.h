// rsvio's Lie groups. THE conventions of the whole project, stated once here:
//
// 1. Perturbation side: the optimiser perturbs every group-valued state on the LEFT,
//        T <- exp(delta) * T,
//    and every analytic Jacobian w.r.t. a pose/rotation/similarity is d(...)/d(delta) at delta = 0 of
//    that left perturbation, unless its name or comment says otherwise (Forster's IMU preintegration
//    uses right perturbations R * exp(d) internally and converts at its edge: d_left = R d_right,
//    i.e. R exp(d) = exp(Adj(R) d) R).
// 2. Adjoint: Adj(T) is defined by   T * exp(d) = exp(Adj(T) d) * T   (paper eq. 26).
// 3. Frames: T_a_b maps points from frame b to frame a, p_a = T_a_b * p_b; T_a_b * T_b_c = T_a_c.
// 4. Tangent order (Sophus' order):
//        SO3   omega                     (3)
//        SE3   (upsilon; omega)          (6)  translation first, as in the paper (sec. III)
//        RxSO3 (omega; sigma)            (4)  sigma = log(scale)
//        Sim3  (upsilon; omega; sigma)   (7)
//    exp and log are the group exponential and its inverse on the principal range (rotation angle
//    in [0, pi]); hat maps a tangent vector to its Lie-algebra matrix, vee inverts hat.
// 5. Names follow Sophus (exp, log, hat, vee, inverse, Adj, matrix, rotationMatrix, translation,
//    unit_quaternion, so3, scale, cast, params). Sophus is not packaged in Debian 12; this is our own
//    implementation of the same interface, templated on the scalar (aliases ...d for double, SO3f).
// 6. Jacobians of exp/log (left/right Jacobians) and of the group action (dActionDLeft) live with each
//    group, each documented with its formula; every one is checked against numeric differences in
//    tests/framework/lie/ with the shared helper tests/support/numeric_jacobian.h.
// Errors: constructors given a non-unit quaternion or a non-rotation matrix throw rsvio::Error.
#pragma once

#include "rsvio/lie/lie_common.h"
#include "rsvio/lie/so3.h"
#include "rsvio/lie/se3.h"
#include "rsvio/lie/rxso3.h"
#include "rsvio/lie/sim3.h"
