#pragma once
// Eigenvalues and eigenvectors of small symmetric matrices, by cyclic Jacobi rotations.
// Eigen's SelfAdjointEigenSolver does the same job, but each fixed size it is instantiated for
// took about 10 s of compiling (4x4 and 6x6), half of the core library's build in every one of
// CI's builds. Jacobi is as accurate (the reference method for symmetric matrices) and, at
// these sizes, about as fast (a 6x6: 3.2 us against Eigen's 2.8 here; a 3x3: 0.4 against 0.3).

#include <Eigen/Core>

namespace rgbdtam {

template <int N>
struct SymmetricEigen {
  Eigen::Matrix<double, N, 1> values;   // ascending
  Eigen::Matrix<double, N, N> vectors;  // column i: the unit eigenvector of values(i)
};

// Reads the lower triangle. A non-finite entry makes every value and vector NaN.
SymmetricEigen<3> symmetric_eigen(const Eigen::Matrix<double, 3, 3>& a);
SymmetricEigen<4> symmetric_eigen(const Eigen::Matrix<double, 4, 4>& a);
SymmetricEigen<6> symmetric_eigen(const Eigen::Matrix<double, 6, 6>& a);

}  // namespace rgbdtam
