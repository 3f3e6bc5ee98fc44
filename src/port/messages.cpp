#include "rgbdtam/port/messages.hpp"

#include <Eigen/LU>

namespace rgbdtam {

// Out of line: the LU's instantiation cost a second and a half in every file that included
// this header.
Eigen::Matrix<double, 6, 6> pose_covariance(const PoseEstimate& pose) {
  const Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(pose.information);
  if (!lu.isInvertible()) return Eigen::Matrix<double, 6, 6>::Constant(NAN);
  return lu.inverse();
}

}  // namespace rgbdtam
