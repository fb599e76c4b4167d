// Non-negative least squares. Private to the library.
#pragma once

#include <Eigen/Dense>

#include <functional>

namespace sd {

/// Lawson–Hanson active-set NNLS (Solving Least Squares Problems, 1974, ch. 23):
/// min ‖A u − b‖₂ subject to u >= 0. The solution it returns is basic: at most rank(A) entries
/// are positive, which is what Carathéodory–Tchakaloff compression relies on. Each passive-set
/// subproblem is solved by Eigen's column-pivoting Householder QR. `stop` is polled before every
/// outer iteration; returning true throws DesignCancelled.
Eigen::VectorXd nnls(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int max_iterations,
                     const std::function<bool()>& stop = {});

}  // namespace sd
