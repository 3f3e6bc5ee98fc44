#pragma once
// SE(3) pose-graph optimisation over preallocated storage: nodes are keyframe poses T_w_n,
// edges relative poses T_from_to with an information matrix in (v, omega). Gauss-Newton on
// right perturbations T <- T exp(delta), the normal equations solved by conjugate gradients
// with a block-Jacobi preconditioner, so that memory and time stay linear in nodes plus edges
// (a chain of keyframes with a few loops is sparse). The first node is held fixed (the gauge),
// or the first few (a map being localised in).
// optimize() never allocates.

#include <memory>

#include "rgbdtam/core/assert.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

// The information of a tracked pose T_k_c, which the tracker measures for the perturbation
// T_c_k exp(-delta), for the graph's perturbation T_k_c exp(xi).
Matrix6d graph_information(const Matrix6d& tracker_information, const SE3& T_k_c);
// The information of T_a_b = T_a_f T_b_f^-1, from those of T_a_f and T_b_f (graph convention):
// two keyframes tied by a frame both measured.
Matrix6d information_through(const Matrix6d& info_a_f, const Matrix6d& info_b_f, const SE3& T_b_f);

// The information of a pose that may also have jumped by up to jump_m and jump_rad in any
// direction: the jump's square added to the covariance of each axis.
Matrix6d information_with_jump(const Matrix6d& information, double jump_m, double jump_rad);

struct PoseGraphStats {
  int iterations = 0;         // Gauss-Newton steps taken
  int cg_iterations = 0;      // over all steps
  double initial_cost = 0.0;  // sum of e^T Omega e
  double final_cost = 0.0;
};

class PoseGraph {
 public:
  void allocate(int max_nodes, int max_edges);
  void clear() { nodes_ = edges_ = 0; }
  // The first `count` nodes (at least one: the gauge) keep their poses.
  void set_fixed(int count) { fixed_ = count > 1 ? count : 1; }
  // Returns the node's index, or -1 when full.
  int add_node(const SE3& T_w_n);
  bool add_edge(int from, int to, const SE3& T_from_to, const Matrix6d& information);
  PoseGraphStats optimize(int max_iterations);
  double cost() const;
  const SE3& pose(int i) const { return pose_[i]; }
  int nodes() const { return nodes_; }
  int edges() const { return edges_; }

 private:
  struct Edge {
    int from = 0, to = 0;
    SE3 T_from_to;
    Matrix6d information;
    Matrix6d H_from_to;  // the normal equations' off-diagonal block of this step
  };
  Vector6d residual(const Edge& e) const;
  void build_normal_equations();
  int solve(int max_iterations);  // conjugate gradients into delta_
  void multiply(const Vector6d* x, Vector6d* out) const;

  int nodes_ = 0, edges_ = 0, max_nodes_ = 0, max_edges_ = 0, fixed_ = 1;
  std::unique_ptr<SE3[]> pose_;
  std::unique_ptr<Edge[]> edge_;
  std::unique_ptr<Matrix6d[]> H_diag_, preconditioner_;
  std::unique_ptr<Vector6d[]> g_, delta_, r_, z_, p_, Ap_;
};

}  // namespace rgbdtam
